"""Contact manifolds between two rounded convex polygons in 2D (world-free Numba kernels).

A piece is a rounded convex polygon (:class:`carom.shapes.ConvexPiece`): the points within
``radius`` of a core of ``k`` corners, counter-clockwise. k = 1 is a circle, k = 2 a capsule
(or a segment when the radius is 0), k >= 3 a polygon. The kernels read pieces already placed
in the world: ``vertices[start:start + k]`` and the edges' outward ``normals`` (edge ``i`` runs
from corner ``i`` to ``i + 1``; a two-corner piece has the two sides of its segment as edges).

:func:`collide` picks the kernel for the pair (circle-circle, polygon-circle, segment-segment,
polygon-polygon) and writes a manifold of 0, 1 or 2 points:

- ``out[0:2]`` the unit normal, pointing from piece B to piece A (carom's convention: A is
  pushed along ``+n``);
- ``out[2 + 3j : 5 + 3j]`` point ``j``: ``x, y`` halfway between the two surfaces [m] and the
  separation along the normal [m] (negative when they overlap);
- ``ids[j]`` the point's feature id ``256 a + b`` (the corners or edges of A and B it comes
  from), so a solver can match a point from one step to the next and warm-start it.

Points further apart than ``margin`` [m] are not reported (speculative contact: a point may be
reported before it touches). Polygon pairs use the separating-axis test, then clip the incident
edge to the reference edge's side planes (Box2D v3's ``b2CollidePolygons``, Ericson 2005 5.1.9
for the segment pairs); the formulas here are carom's own.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, uint64

from carom.jit import leaf

__all__ = ["collide", "core_distance", "core_witness", "segment_closest"]

#: a tie on separation within this fraction of the slop keeps A's face (no flip-flop)
_TIE = 0.1


@njit(cache=True, inline="always")
def _next(i: int, k: int) -> int:
    """The corner after corner ``i`` of ``k`` (``(i + 1) % k`` for ``0 <= i < k``), without an
    integer division (the manifold has up to a dozen: a box pair's 5% faster without them)."""
    return i + 1 if i + 1 < k else 0


@njit(cache=True, inline="always")
def _point(
    out: np.ndarray, ids: np.ndarray, j: int, x: float, y: float, s: float, fid: int
) -> None:
    out[2 + 3 * j] = x
    out[3 + 3 * j] = y
    out[4 + 3 * j] = s
    ids[j] = fid


@njit(cache=True, inline="always")
def _one_point(
    c1x: float,
    c1y: float,
    c2x: float,
    c2y: float,
    nx: float,
    ny: float,
    r1: float,
    r2: float,
    separation: float,
    fid: int,
    out: np.ndarray,
    ids: np.ndarray,
) -> int:
    """One point joining core point ``c1`` (of A, radius r1) to ``c2`` (of B, radius r2)
    along the unit normal ``n`` from A to B: halfway between the surfaces ``c1 + r1 n`` and
    ``c2 - r2 n``."""
    out[0] = nx
    out[1] = ny
    _point(
        out,
        ids,
        0,
        0.5 * ((c1x + r1 * nx) + (c2x - r2 * nx)),
        0.5 * ((c1y + r1 * ny) + (c2y - r2 * ny)),
        separation,
        fid,
    )
    return 1


@leaf
def _circles(
    ax: float,
    ay: float,
    ra: float,
    bx: float,
    by: float,
    rb: float,
    margin: float,
    out: np.ndarray,
    ids: np.ndarray,
) -> int:
    """Circle A against circle B; normal from A to B (the caller turns it round)."""
    dx = bx - ax
    dy = by - ay
    dist = math.sqrt(dx * dx + dy * dy)
    separation = dist - ra - rb
    if separation > margin:
        return 0
    if dist > 0.0:
        nx = dx / dist
        ny = dy / dist
    else:  # concentric: any normal is as good; up
        nx = 0.0
        ny = 1.0
    return _one_point(ax, ay, bx, by, nx, ny, ra, rb, separation, 0, out, ids)


@leaf
def _polygon_circle(
    vertices: np.ndarray,
    normals: np.ndarray,
    sa: int,
    ka: int,
    ra: float,
    cx: float,
    cy: float,
    rb: float,
    margin: float,
    out: np.ndarray,
    ids: np.ndarray,
) -> int:
    """Polygon (or segment) A, k >= 2, against circle B; normal from A to B."""
    best = -np.inf
    face = 0
    for i in range(ka):
        s = normals[sa + i, 0] * (cx - vertices[sa + i, 0]) + normals[sa + i, 1] * (
            cy - vertices[sa + i, 1]
        )
        if s > best:
            best = s
            face = i
    radius = ra + rb
    if best > radius + margin:
        return 0
    i1 = sa + face
    i2 = sa + _next(face, ka)
    x1, y1 = vertices[i1, 0], vertices[i1, 1]
    x2, y2 = vertices[i2, 0], vertices[i2, 1]
    # where the centre projects along the face: before corner 1, after corner 2, or between
    u1 = (cx - x1) * (x2 - x1) + (cy - y1) * (y2 - y1)
    u2 = (cx - x2) * (x1 - x2) + (cy - y2) * (y1 - y2)
    if best > 0.0 and (u1 < 0.0 or u2 < 0.0):
        # the centre is outside, nearest a corner: the normal joins the corner to the centre
        vx, vy = (x1, y1) if u1 < 0.0 else (x2, y2)
        dx = cx - vx
        dy = cy - vy
        dist = math.sqrt(dx * dx + dy * dy)
        separation = dist - radius
        if separation > margin:
            return 0
        corner = face if u1 < 0.0 else _next(face, ka)
        return _one_point(
            vx, vy, cx, cy, dx / dist, dy / dist, ra, rb, separation, corner << 8, out, ids
        )
    nx = normals[i1, 0]
    ny = normals[i1, 1]
    out[0] = nx
    out[1] = ny
    # the centre projected onto the face, pushed out by ra; the circle's deepest point
    ax = cx + (ra - best) * nx
    ay = cy + (ra - best) * ny
    bx = cx - rb * nx
    by = cy - rb * ny
    _point(out, ids, 0, 0.5 * (ax + bx), 0.5 * (ay + by), best - radius, face << 8)
    return 1


@leaf
def segment_closest(
    p1x: float,
    p1y: float,
    q1x: float,
    q1y: float,
    p2x: float,
    p2y: float,
    q2x: float,
    q2y: float,
) -> tuple[float, float, float]:
    """Closest points of segments ``p1 q1`` and ``p2 q2``: fractions ``f1, f2`` in [0, 1]
    along each and the squared distance [m^2] (Ericson, Real-Time Collision Detection, 5.1.9).
    """
    d1x = q1x - p1x
    d1y = q1y - p1y
    d2x = q2x - p2x
    d2y = q2y - p2y
    rx = p1x - p2x
    ry = p1y - p2y
    a = d1x * d1x + d1y * d1y
    e = d2x * d2x + d2y * d2y
    f = d2x * rx + d2y * ry
    c = d1x * rx + d1y * ry
    b = d1x * d2x + d1y * d2y
    denom = a * e - b * b
    f1 = 0.0
    if denom > 0.0:  # not parallel: the closest point of the infinite lines, clamped
        f1 = min(max((b * f - c * e) / denom, 0.0), 1.0)
    f2 = (b * f1 + f) / e
    if f2 < 0.0:  # clamping segment 2 moves the closest point of segment 1
        f2 = 0.0
        f1 = min(max(-c / a, 0.0), 1.0)
    elif f2 > 1.0:
        f2 = 1.0
        f1 = min(max((b - c) / a, 0.0), 1.0)
    dx = (p1x + f1 * d1x) - (p2x + f2 * d2x)
    dy = (p1y + f1 * d1y) - (p2y + f2 * d2y)
    return f1, f2, dx * dx + dy * dy


@njit(cache=True, inline="always")
def _max_separation(
    vertices: np.ndarray, normals: np.ndarray, s1: int, k1: int, s2: int, k2: int
) -> tuple[float, int]:
    """The largest separation of polygon 2 from any edge of polygon 1, and that edge."""
    best = -np.inf
    edge = 0
    for i in range(k1):
        # (unsigned rows: Numba checks a signed index for a negative one to wrap, at every
        # load; the two searches, 40% of a box pair's manifold, ran 20% faster without it)
        r = uint64(s1 + i)
        nx = normals[r, 0]
        ny = normals[r, 1]
        vx = vertices[r, 0]
        vy = vertices[r, 1]
        deepest = np.inf
        for j in range(k2):
            c = uint64(s2 + j)
            deepest = min(deepest, nx * (vertices[c, 0] - vx) + ny * (vertices[c, 1] - vy))
        better = deepest > best
        edge = i if better else edge
        best = deepest if better else best
    return best, edge


@njit(cache=True, inline="always")
def _incident_edge(normals: np.ndarray, s2: int, k2: int, nx: float, ny: float) -> int:
    """The edge of polygon 2 whose normal is most anti-parallel to ``n``."""
    lowest = np.inf
    edge = 0
    for i in range(k2):
        d = nx * normals[s2 + i, 0] + ny * normals[s2 + i, 1]
        lower = d < lowest
        edge = i if lower else edge
        lowest = d if lower else lowest
    return edge


@njit(cache=True, inline="always")
def _clip(
    vertices: np.ndarray,
    normals: np.ndarray,
    s1: int,
    k1: int,
    r1: float,
    e1: int,
    s2: int,
    k2: int,
    r2: float,
    e2: int,
    flip: bool,
    overlap: bool,
    out: np.ndarray,
    ids: np.ndarray,
) -> int:
    """Two points from reference edge ``e1`` of polygon 1 and incident edge ``e2`` of polygon
    2: the incident edge clipped to the reference edge's extent. Normal from 1 to 2, turned to
    run from A to B (``flip`` when polygon 1 is B). ``overlap``: the cores touch or overlap."""
    i11 = s1 + e1
    i12 = s1 + _next(e1, k1)
    i21 = s2 + e2
    i22 = s2 + _next(e2, k2)
    nx = normals[i11, 0]
    ny = normals[i11, 1]
    tx = -ny  # the tangent along the reference edge, from corner 11 to corner 12
    ty = nx
    ox = vertices[i11, 0]
    oy = vertices[i11, 1]
    upper1 = tx * (vertices[i12, 0] - ox) + ty * (vertices[i12, 1] - oy)
    # the incident edge runs the other way round (both outlines are counter-clockwise)
    upper2 = tx * (vertices[i21, 0] - ox) + ty * (vertices[i21, 1] - oy)
    lower2 = tx * (vertices[i22, 0] - ox) + ty * (vertices[i22, 1] - oy)
    radius = r1 + r2
    if upper2 < 0.0 or upper1 < lower2:
        if not overlap:
            return 0  # apart and beside each other: the caller joins the closest points
        # The incident edge lies beside the reference edge in a deep overlap. One point at
        # polygon 2's deepest corner along n, which is what the separating-axis test measured.
        deepest = np.inf
        corner = 0
        for j in range(k2):
            d = nx * (vertices[s2 + j, 0] - ox) + ny * (vertices[s2 + j, 1] - oy)
            if d < deepest:
                deepest = d
                corner = j
        h = 0.5 * (r1 - r2 - deepest)
        px = vertices[s2 + corner, 0] + h * nx
        py = vertices[s2 + corner, 1] + h * ny
        sign = -1.0 if flip else 1.0
        out[0] = sign * nx
        out[1] = sign * ny
        fid = (corner << 8) | e1 if flip else (e1 << 8) | corner
        _point(out, ids, 0, px, py, deepest - radius, fid)
        return 1
    span = upper2 - lower2
    eps = 1e-12 * (abs(upper1) + abs(upper2) + abs(lower2))
    lx, ly = vertices[i22, 0], vertices[i22, 1]
    if lower2 < 0.0 and span > eps:
        f = (0.0 - lower2) / span
        lx = vertices[i22, 0] + f * (vertices[i21, 0] - vertices[i22, 0])
        ly = vertices[i22, 1] + f * (vertices[i21, 1] - vertices[i22, 1])
    hx, hy = vertices[i21, 0], vertices[i21, 1]
    if upper2 > upper1 and span > eps:
        f = (upper1 - lower2) / span
        hx = vertices[i22, 0] + f * (vertices[i21, 0] - vertices[i22, 0])
        hy = vertices[i22, 1] + f * (vertices[i21, 1] - vertices[i22, 1])
    sep_l = nx * (lx - ox) + ny * (ly - oy)
    sep_h = nx * (hx - ox) + ny * (hy - oy)
    # each point halfway between the two rounded surfaces
    lx += 0.5 * (r1 - r2 - sep_l) * nx
    ly += 0.5 * (r1 - r2 - sep_l) * ny
    hx += 0.5 * (r1 - r2 - sep_h) * nx
    hy += 0.5 * (r1 - r2 - sep_h) * ny
    if not flip:
        out[0] = nx
        out[1] = ny
        _point(out, ids, 0, lx, ly, sep_l - radius, (e1 << 8) | _next(e2, k2))
        _point(out, ids, 1, hx, hy, sep_h - radius, (_next(e1, k1) << 8) | e2)
    else:
        out[0] = -nx
        out[1] = -ny
        _point(out, ids, 0, hx, hy, sep_h - radius, (e2 << 8) | _next(e1, k1))
        _point(out, ids, 1, lx, ly, sep_l - radius, (_next(e2, k2) << 8) | e1)
    return 2


@njit(cache=True, inline="always")
def _polygons(
    vertices: np.ndarray,
    normals: np.ndarray,
    sa: int,
    ka: int,
    ra: float,
    sb: int,
    kb: int,
    rb: float,
    margin: float,
    slop: float,
    out: np.ndarray,
    ids: np.ndarray,
) -> int:
    """Rounded polygon A against rounded polygon B (not both segments); normal from A to B."""
    sep_a, edge_a = _max_separation(vertices, normals, sa, ka, sb, kb)
    sep_b, edge_b = _max_separation(vertices, normals, sb, kb, sa, ka)
    radius = ra + rb
    if sep_a > margin + radius or sep_b > margin + radius:
        return 0
    flip = not (sep_a + _TIE * slop >= sep_b)
    overlap = max(sep_a, sep_b) <= _TIE * slop
    if not flip:
        edge_b = _incident_edge(normals, sb, kb, normals[sa + edge_a, 0], normals[sa + edge_a, 1])
        count = _clip(
            vertices, normals, sa, ka, ra, edge_a, sb, kb, rb, edge_b, False, overlap, out, ids
        )
    else:
        edge_a = _incident_edge(normals, sa, ka, normals[sb + edge_b, 0], normals[sb + edge_b, 1])
        count = _clip(
            vertices, normals, sb, kb, rb, edge_b, sa, ka, ra, edge_a, True, overlap, out, ids
        )
    if overlap:
        return count  # the cores touch or overlap: the clipped face contact is right
    # The cores are apart. The clipped points may lie well beyond the true gap (an incident
    # edge tilted away, or clipped to nothing when only the corners face each other): when
    # the two edges' closest points are clearly nearer than every clipped point, one point
    # along the line joining them.
    i11 = sa + edge_a
    i12 = sa + _next(edge_a, ka)
    i21 = sb + edge_b
    i22 = sb + _next(edge_b, kb)
    f1, f2, d2 = segment_closest(
        vertices[i11, 0],
        vertices[i11, 1],
        vertices[i12, 0],
        vertices[i12, 1],
        vertices[i21, 0],
        vertices[i21, 1],
        vertices[i22, 0],
        vertices[i22, 1],
    )
    distance = math.sqrt(d2)
    if distance - radius > margin:
        return 0
    lowest = np.inf
    for j in range(count):
        lowest = min(lowest, out[4 + 3 * j])
    if distance > 0.0 and distance - radius + _TIE * slop < lowest:
        c1x = vertices[i11, 0] + f1 * (vertices[i12, 0] - vertices[i11, 0])
        c1y = vertices[i11, 1] + f1 * (vertices[i12, 1] - vertices[i11, 1])
        c2x = vertices[i21, 0] + f2 * (vertices[i22, 0] - vertices[i21, 0])
        c2y = vertices[i21, 1] + f2 * (vertices[i22, 1] - vertices[i21, 1])
        fa = edge_a if f1 == 0.0 else _next(edge_a, ka)
        fb = edge_b if f2 == 0.0 else _next(edge_b, kb)
        nx = (c2x - c1x) / distance
        ny = (c2y - c1y) / distance
        return _one_point(
            c1x, c1y, c2x, c2y, nx, ny, ra, rb, distance - radius, (fa << 8) | fb, out, ids
        )
    return count


@leaf
def _facing(
    ox: float,
    oy: float,
    nx: float,
    ny: float,
    length: float,
    px: float,
    py: float,
    qx: float,
    qy: float,
    lo: float,
    hi: float,
    r_ref: float,
    r_inc: float,
    sign: float,
    distance: float,
    slop: float,
    fid: int,
    out: np.ndarray,
    ids: np.ndarray,
) -> int:
    """Two points of a reference segment (from ``o``, ``length`` long, side normal ``n``)
    facing an incident segment ``p q`` whose ends lie at ``lo``, ``hi`` along it: the incident
    segment clipped to ``[0, length]``. Written with normal ``sign n`` and ids ``fid``,
    ``fid + 1`` unless the nearer clipped point lies clearly beyond the closest-point
    ``distance`` (then 0: the caller's one point at the closest points is the contact)."""
    cpx, cpy, cqx, cqy = px, py, qx, qy
    if lo < 0.0 < hi:
        t = -lo / (hi - lo)
        cpx, cpy = px + t * (qx - px), py + t * (qy - py)
    elif hi < 0.0 < lo:
        t = -hi / (lo - hi)
        cqx, cqy = qx + t * (px - qx), qy + t * (py - qy)
    if lo > length > hi:
        t = (lo - length) / (lo - hi)
        cpx, cpy = px + t * (qx - px), py + t * (qy - py)
    elif hi > length > lo:
        t = (hi - length) / (hi - lo)
        cqx, cqy = qx + t * (px - qx), qy + t * (py - qy)
    sp = nx * (cpx - ox) + ny * (cpy - oy)
    sq = nx * (cqx - ox) + ny * (cqy - oy)
    if min(sp, sq) > distance + _TIE * slop:
        return 0
    radius = r_ref + r_inc
    out[0] = sign * nx
    out[1] = sign * ny
    h = 0.5 * (r_ref - r_inc - sp)
    _point(out, ids, 0, cpx + h * nx, cpy + h * ny, sp - radius, fid)
    h = 0.5 * (r_ref - r_inc - sq)
    _point(out, ids, 1, cqx + h * nx, cqy + h * ny, sq - radius, fid + 1)
    return 2


@leaf
def _segments(
    vertices: np.ndarray,
    sa: int,
    ra: float,
    sb: int,
    rb: float,
    margin: float,
    slop: float,
    out: np.ndarray,
    ids: np.ndarray,
) -> int:
    """Capsule (or segment) A against capsule B; normal from A to B. Two points when the
    segments face each other along one of their normals, else one at the closest points."""
    p1x, p1y = vertices[sa, 0], vertices[sa, 1]
    q1x, q1y = vertices[sa + 1, 0], vertices[sa + 1, 1]
    p2x, p2y = vertices[sb, 0], vertices[sb, 1]
    q2x, q2y = vertices[sb + 1, 0], vertices[sb + 1, 1]
    f1, f2, d2 = segment_closest(p1x, p1y, q1x, q1y, p2x, p2y, q2x, q2y)
    radius = ra + rb
    reach = radius + margin
    if d2 > reach * reach:
        return 0
    distance = math.sqrt(d2)
    len1 = math.sqrt((q1x - p1x) ** 2 + (q1y - p1y) ** 2)
    len2 = math.sqrt((q2x - p2x) ** 2 + (q2y - p2y) ** 2)
    u1x = (q1x - p1x) / len1
    u1y = (q1y - p1y) / len1
    u2x = (q2x - p2x) / len2
    u2y = (q2y - p2y) / len2
    # each segment's ends measured along the other
    fp2 = (p2x - p1x) * u1x + (p2y - p1y) * u1y
    fq2 = (q2x - p1x) * u1x + (q2y - p1y) * u1y
    fp1 = (p1x - p2x) * u2x + (p1y - p2y) * u2y
    fq1 = (q1x - p2x) * u2x + (q1y - p2y) * u2y
    outside_a = (fp2 <= 0.0 and fq2 <= 0.0) or (fp2 >= len1 and fq2 >= len1)
    outside_b = (fp1 <= 0.0 and fq1 <= 0.0) or (fp1 >= len2 and fq1 >= len2)
    if not outside_a and not outside_b:
        # the side of each segment the other lies on, and how far (separating axes)
        nax, nay = -u1y, u1x
        s1 = nax * (p2x - p1x) + nay * (p2y - p1y)
        s2 = nax * (q2x - p1x) + nay * (q2y - p1y)
        if min(s1, s2) < min(-s1, -s2):
            nax, nay = -nax, -nay
        sep_a = max(min(s1, s2), min(-s1, -s2))
        nbx, nby = -u2y, u2x
        s1 = nbx * (p1x - p2x) + nby * (p1y - p2y)
        s2 = nbx * (q1x - p2x) + nby * (q1y - p2y)
        if min(s1, s2) < min(-s1, -s2):
            nbx, nby = -nbx, -nby
        sep_b = max(min(s1, s2), min(-s1, -s2))
        if sep_a + _TIE * slop >= sep_b:
            # reference A: B's segment clipped to A's extent; the normal from A to B is n_a
            count = _facing(
                p1x,
                p1y,
                nax,
                nay,
                len1,
                p2x,
                p2y,
                q2x,
                q2y,
                fp2,
                fq2,
                ra,
                rb,
                1.0,
                distance,
                slop,
                0,
                out,
                ids,
            )
        else:
            # reference B: A's segment clipped to B's extent; the normal from A to B is -n_b
            count = _facing(
                p2x,
                p2y,
                nbx,
                nby,
                len2,
                p1x,
                p1y,
                q1x,
                q1y,
                fp1,
                fq1,
                rb,
                ra,
                -1.0,
                distance,
                slop,
                256,
                out,
                ids,
            )
        if count:
            return count
    c1x = p1x + f1 * (q1x - p1x)
    c1y = p1y + f1 * (q1y - p1y)
    c2x = p2x + f2 * (q2x - p2x)
    c2y = p2y + f2 * (q2y - p2y)
    if distance > 0.0:
        nx = (c2x - c1x) / distance
        ny = (c2y - c1y) / distance
    else:  # crossing cores: A's left side
        nx, ny = -u1y, u1x
    fid = ((0 if f1 == 0.0 else 1) << 8) | (0 if f2 == 0.0 else 1)
    return _one_point(c1x, c1y, c2x, c2y, nx, ny, ra, rb, distance - radius, fid, out, ids)


@njit(cache=True, inline="always")
def collide(
    vertices: np.ndarray,
    normals: np.ndarray,
    sa: int,
    ka: int,
    ra: float,
    sb: int,
    kb: int,
    rb: float,
    margin: float,
    slop: float,
    out: np.ndarray,
    ids: np.ndarray,
) -> int:
    """The contact manifold of pieces A and B (module docstring for the layout of ``out``).

    Parameters
    ----------
    vertices, normals : (V, 2) float64
        Placed corners [m] and edge normals [-] of all pieces.
    sa, ka, ra : int, int, float
        Piece A's first corner, number of corners, rounding radius [m].
    sb, kb, rb : int, int, float
        The same for piece B.
    margin : float
        Report points up to this separation [m] (speculative contact).
    slop : float
        Length below which the cores count as touching [m] (the solver's linear slop).
    out : (8,) float64
        Normal (from B to A) and up to two points, written.
    ids : (2,) int64
        Feature ids of the points, written.

    Returns
    -------
    int
        Number of points, 0, 1 or 2.
    """
    if ka == 1 and kb == 1:
        count = _circles(
            vertices[sa, 0],
            vertices[sa, 1],
            ra,
            vertices[sb, 0],
            vertices[sb, 1],
            rb,
            margin,
            out,
            ids,
        )
    elif kb == 1:
        count = _polygon_circle(
            vertices, normals, sa, ka, ra, vertices[sb, 0], vertices[sb, 1], rb, margin, out, ids
        )
    elif ka == 1:
        count = _polygon_circle(
            vertices, normals, sb, kb, rb, vertices[sa, 0], vertices[sa, 1], ra, margin, out, ids
        )
        if count:  # the kernel's normal ran from B to A already; points' ids swap sides
            out[0] = -out[0]
            out[1] = -out[1]
            ids[0] = ids[0] >> 8
    elif ka == 2 and kb == 2:
        count = _segments(vertices, sa, ra, sb, rb, margin, slop, out, ids)
    else:
        count = _polygons(vertices, normals, sa, ka, ra, sb, kb, rb, margin, slop, out, ids)
    # the kernels' normals run from A to B; carom's from B to A
    out[0] = -out[0]
    out[1] = -out[1]
    return count


@leaf
def core_distance(
    vertices: np.ndarray, normals: np.ndarray, sa: int, ka: int, sb: int, kb: int
) -> float:
    """Exact distance between two convex cores [m]; 0 when they touch or overlap
    (:func:`core_witness`)."""
    return core_witness(vertices, normals, sa, ka, sb, kb)[0]


@leaf
def core_witness(
    vertices: np.ndarray, normals: np.ndarray, sa: int, ka: int, sb: int, kb: int
) -> tuple[float, float, float]:
    """Exact distance between two convex cores [m] and the unit vector from B's closest point
    to A's; ``(0, 0, 0)`` when they touch or overlap.

    The distance between disjoint convex polygons is attained between a corner of one and an
    edge (or corner) of the other, so the smallest corner-to-edge distance is exact. Overlap
    is found by the separating-axis test (no axis separates). Used by conservative advancement,
    which needs the true gap, not the face-normal estimate of :func:`collide`.
    """
    if ka >= 3 and kb >= 3:
        sep_a, _ = _max_separation(vertices, normals, sa, ka, sb, kb)
        sep_b, _ = _max_separation(vertices, normals, sb, kb, sa, ka)
        if sep_a <= 0.0 and sep_b <= 0.0:
            return 0.0, 0.0, 0.0
    elif (ka == 2 and kb >= 3) or (kb == 2 and ka >= 3):
        # a segment through a polygon: no face of either separates them
        sp, kp, ss = (sb, kb, sa) if ka == 2 else (sa, ka, sb)
        sep_p, _ = _max_separation(vertices, normals, sp, kp, ss, 2)
        sep_s, _ = _max_separation(vertices, normals, ss, 2, sp, kp)
        if sep_p <= 0.0 and sep_s <= 0.0:
            return 0.0, 0.0, 0.0
    elif (ka == 1 and kb >= 3) or (kb == 1 and ka >= 3):
        sp, kp, sc = (sb, kb, sa) if ka == 1 else (sa, ka, sb)
        sep, _ = _max_separation(vertices, normals, sp, kp, sc, 1)
        if sep <= 0.0:
            return 0.0, 0.0, 0.0
    best = np.inf
    wx = 0.0
    wy = 0.0
    if ka == 2 and kb == 2:
        # two segments: the closest points directly (they may cross with both ends apart)
        f1, f2, best = segment_closest(
            vertices[sa, 0],
            vertices[sa, 1],
            vertices[sa + 1, 0],
            vertices[sa + 1, 1],
            vertices[sb, 0],
            vertices[sb, 1],
            vertices[sb + 1, 0],
            vertices[sb + 1, 1],
        )
        wx = (vertices[sa, 0] + f1 * (vertices[sa + 1, 0] - vertices[sa, 0])) - (
            vertices[sb, 0] + f2 * (vertices[sb + 1, 0] - vertices[sb, 0])
        )
        wy = (vertices[sa, 1] + f1 * (vertices[sa + 1, 1] - vertices[sa, 1])) - (
            vertices[sb, 1] + f2 * (vertices[sb + 1, 1] - vertices[sb, 1])
        )
    else:
        for side in range(2):
            s1, k1, s2, k2 = (sa, ka, sb, kb) if side == 0 else (sb, kb, sa, ka)
            sign = 1.0 if side == 0 else -1.0
            edges = k2 if k2 >= 3 else (1 if k2 == 2 else 0)
            for i in range(k1):
                px = vertices[s1 + i, 0]
                py = vertices[s1 + i, 1]
                if edges == 0:
                    qx = px - vertices[s2, 0]
                    qy = py - vertices[s2, 1]
                    d2 = qx * qx + qy * qy
                    if d2 < best:
                        best = d2
                        wx = sign * qx
                        wy = sign * qy
                    continue
                for j in range(edges):
                    ax = vertices[s2 + j, 0]
                    ay = vertices[s2 + j, 1]
                    ex = vertices[s2 + _next(j, k2), 0] - ax
                    ey = vertices[s2 + _next(j, k2), 1] - ay
                    t = ((px - ax) * ex + (py - ay) * ey) / (ex * ex + ey * ey)
                    t = min(max(t, 0.0), 1.0)
                    qx = px - ax - t * ex
                    qy = py - ay - t * ey
                    d2 = qx * qx + qy * qy
                    if d2 < best:
                        best = d2
                        wx = sign * qx
                        wy = sign * qy
    distance = math.sqrt(best)
    if distance == 0.0:
        return 0.0, 0.0, 0.0
    return distance, wx / distance, wy / distance
