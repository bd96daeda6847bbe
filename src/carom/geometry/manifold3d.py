"""Contact manifolds in 3D: world-free functions per shape pair, as in 2D (:mod:`.manifold2d`).

Each ``contact_<a>_<b>`` takes two placed shapes and writes up to four contact points into
``out`` (19,) float64: the unit normal ``n`` from A to B in ``out[0:3]``, then for point ``j``
its position ``out[3 + 4j : 6 + 4j]`` [m], midway between the two surfaces, and its separation
``out[6 + 4j]`` [m] (the gap along ``n``; negative when they overlap); ``ids[j]`` names the
features that made the point, so the solver can warm-start it next step. It returns the number
of points; none when the shapes are further apart than ``margin`` [m] (speculative contact
reaches that far). Returning none for that reason, hull-hull and hull-sphere write a lower
bound of the gap [m] into ``out[6]`` (what the separating axis showed), so the caller can tell
how far the pair may move before it can touch; the others leave ``out`` as it was.

Round shapes are cores with a radius (a sphere is a point, a capsule a segment), so their
manifolds are closed forms on closest points of cores:

- sphere-sphere: the centres' line;
- capsule-sphere: the closest point of the segment to the centre (clamped projection);
- capsule-capsule: the closest points of two segments (Ericson, *Real-Time Collision
  Detection*, 2005, sec. 5.1.9); nearly parallel segments whose spans overlap touch along a
  line, and give the two ends of the overlap, so a capsule lying on another rests on two
  points;
- sphere-, capsule- and hull-plane: the core's corners below the plane (up to 4, the deepest
  and those spanning the largest area, so a box resting on a plane has its 4 corners).

Convex polytopes (boxes, hulls, and mesh triangles as flat ones) are given placed, with their
faces and edges (:func:`carom.geometry.polyhedron.polyhedron_features`):

- hull-hull: separating axes (face normals, crosses of edge directions) with face clipping,
  or the exact closest points when they are apart and beside each other;
- hull-sphere: the exact closest point of the surface;
- hull-capsule: the segment clipped to a face, the closest points to an edge, or the exact
  gap when apart.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.jit import leaf

__all__ = [
    "MAX_POINTS",
    "OUT_SIZE",
    "closest_hulls",
    "closest_segment_segment",
    "contact_capsule_capsule",
    "contact_capsule_sphere",
    "contact_hull_capsule",
    "contact_hull_hull",
    "contact_hull_plane",
    "contact_hull_sphere",
    "contact_segments_plane",
    "contact_sphere_sphere",
    "reduce_points",
]

#: points in a manifold at most
MAX_POINTS = 4
#: floats in a manifold: the normal and 4 points of (x, y, z, separation)
OUT_SIZE = 3 + 4 * MAX_POINTS

#: below this squared sine between two segments they count as parallel [-]
_PARALLEL = 1e-10
# Vectors are multiplied with _dot, never "@": Numba's "@" calls BLAS through SciPy, and the
# core needs nothing beyond NumPy and Numba.
#: the edge list of a segment taken as a polytope: its two ends joined
_ONE_EDGE = np.array([[0, 1]], np.int64)


@njit(cache=True, inline="always")
def _point(
    out: np.ndarray, ids: np.ndarray, j: int, x: float, y: float, z: float, sep: float, fid: int
) -> None:
    """Point j of the manifold."""
    out[3 + 4 * j] = x
    out[4 + 4 * j] = y
    out[5 + 4 * j] = z
    out[6 + 4 * j] = sep
    ids[j] = fid


@njit(cache=True)
def _balls(
    ax: float, ay: float, az: float, ra: float,
    bx: float, by: float, bz: float, rb: float,
    margin: float, fid: int, out: np.ndarray, ids: np.ndarray,
) -> int:  # fmt: skip
    """Ball (a, ra) against ball (b, rb): one point on the centres' line, or none."""
    dx, dy, dz = bx - ax, by - ay, bz - az
    distance = math.sqrt(dx * dx + dy * dy + dz * dz)
    sep = distance - ra - rb
    if sep > margin:
        return 0
    if distance > 0.0:
        nx, ny, nz = dx / distance, dy / distance, dz / distance
    else:  # concentric: any direction is as good; up, so the choice is fixed
        nx, ny, nz = 0.0, 0.0, 1.0
    # midway between A's surface point a + ra n and B's b - rb n
    h = 0.5 * (ra - rb + distance)
    out[0], out[1], out[2] = nx, ny, nz
    _point(out, ids, 0, ax + h * nx, ay + h * ny, az + h * nz, sep, fid)
    return 1


@njit(cache=True)
def contact_sphere_sphere(
    a: np.ndarray,
    ra: float,
    b: np.ndarray,
    rb: float,
    margin: float,
    out: np.ndarray,
    ids: np.ndarray,
) -> int:
    """Sphere (centre ``a`` (3,) [m], radius ``ra``) against sphere (``b``, ``rb``).

    Returns
    -------
    int
        0 or 1 point (module docstring for ``out`` and ``ids``).

    Examples
    --------
    >>> out, ids = np.zeros(OUT_SIZE), np.zeros(MAX_POINTS, np.int64)
    >>> contact_sphere_sphere(np.zeros(3), 1.0, np.array([0.0, 0.0, 1.5]), 1.0, 0.0, out, ids)
    1
    >>> out[:3].tolist(), out[3:7].tolist()  # up, at z = 0.75, overlapping by 0.5 m
    ([0.0, 0.0, 1.0], [0.0, 0.0, 0.75, -0.5])
    """
    return _balls(a[0], a[1], a[2], ra, b[0], b[1], b[2], rb, margin, 0, out, ids)


@njit(cache=True, inline="always")
def _on_segment(p0: np.ndarray, p1: np.ndarray, x: float, y: float, z: float) -> float:
    """The fraction t in [0, 1] of the point of segment p0-p1 nearest (x, y, z)."""
    dx, dy, dz = p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]
    length2 = dx * dx + dy * dy + dz * dz
    if length2 == 0.0:
        return 0.0
    t: float = ((x - p0[0]) * dx + (y - p0[1]) * dy + (z - p0[2]) * dz) / length2
    return min(max(t, 0.0), 1.0)


@njit(cache=True)
def contact_capsule_sphere(
    a0: np.ndarray, a1: np.ndarray, ra: float, b: np.ndarray, rb: float, margin: float,
    out: np.ndarray, ids: np.ndarray,
) -> int:  # fmt: skip
    """Capsule (segment ``a0``-``a1`` (3,) [m], radius ``ra``) against sphere (``b``, ``rb``):
    the ball of the segment's point nearest ``b``. The point's id is 0 at ``a0``, 1 at ``a1``
    and 2 between."""
    t = _on_segment(a0, a1, b[0], b[1], b[2])
    fid = 0 if t == 0.0 else (1 if t == 1.0 else 2)
    px = a0[0] + t * (a1[0] - a0[0])
    py = a0[1] + t * (a1[1] - a0[1])
    pz = a0[2] + t * (a1[2] - a0[2])
    return _balls(px, py, pz, ra, b[0], b[1], b[2], rb, margin, fid, out, ids)


@leaf
def closest_segment_segment(
    p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray
) -> tuple[float, float]:
    """Fractions (s, t) in [0, 1] of the closest points ``p0 + s (p1 - p0)`` and
    ``q0 + t (q1 - q0)`` of two segments (Ericson 2005, sec. 5.1.9: the unclamped minimum of
    ``|p(s) - q(t)|^2``, clamped to the square edge by edge; for parallel segments any s
    works, and s = 0 is taken)."""
    # in scalars (no arrays are made: this runs for every edge pair of two polytopes)
    d1x, d1y, d1z = p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2]
    d2x, d2y, d2z = q1[0] - q0[0], q1[1] - q0[1], q1[2] - q0[2]
    rx, ry, rz = p0[0] - q0[0], p0[1] - q0[1], p0[2] - q0[2]
    a = d1x * d1x + d1y * d1y + d1z * d1z
    e = d2x * d2x + d2y * d2y + d2z * d2z
    f = d2x * rx + d2y * ry + d2z * rz
    if a == 0.0 and e == 0.0:
        return 0.0, 0.0
    if a == 0.0:
        return 0.0, min(max(f / e, 0.0), 1.0)
    c = d1x * rx + d1y * ry + d1z * rz
    if e == 0.0:
        return min(max(-c / a, 0.0), 1.0), 0.0
    b = d1x * d2x + d1y * d2y + d1z * d2z
    denominator = a * e - b * b  # |d1 x d2|^2 >= 0
    s = (
        min(max((b * f - c * e) / denominator, 0.0), 1.0)
        if denominator > _PARALLEL * a * e
        else 0.0
    )
    # the nearest t to p(s), and if it left [0, 1], the nearest s to the clamped end
    t = (b * s + f) / e
    if t < 0.0:
        t = 0.0
        s = min(max(-c / a, 0.0), 1.0)
    elif t > 1.0:
        t = 1.0
        s = min(max((b - c) / a, 0.0), 1.0)
    return s, t


@njit(cache=True)
def contact_capsule_capsule(
    a0: np.ndarray, a1: np.ndarray, ra: float, b0: np.ndarray, b1: np.ndarray, rb: float,
    margin: float, out: np.ndarray, ids: np.ndarray,
) -> int:  # fmt: skip
    """Capsule (``a0``-``a1``, ``ra``) against capsule (``b0``-``b1``, ``rb``).

    Crossing segments touch at their closest points (one point, id 2). Nearly parallel ones
    (sine of the angle below 1e-5) whose spans overlap along A touch along a line: two points,
    at the overlap's ends (ids 0 and 1), on the common normal."""
    da = a1 - a0
    db = b1 - b0
    la2 = _dot(da, da)
    lb2 = _dot(db, db)
    cross = np.cross(da, db)
    if la2 > 0.0 and lb2 > 0.0 and _dot(cross, cross) <= _PARALLEL * la2 * lb2:
        # B's ends along A, as fractions of A
        u0 = _dot(b0 - a0, da) / la2
        u1 = _dot(b1 - a0, da) / la2
        lo = max(min(u0, u1), 0.0)
        hi = min(max(u0, u1), 1.0)
        if hi > lo:
            # every point of two parallel lines has the same normal, A's line to B's
            _normal_of(a0, da, la2, b0, out)
            n = out[0:3].copy()
            count = 0
            for j, u in enumerate((lo, hi)):
                p = a0 + u * da
                q = b0 + _on_segment(b0, b1, p[0], p[1], p[2]) * db
                gap = _dot(q - p, n)
                sep = gap - ra - rb
                if sep > margin:
                    continue
                m = p + (0.5 * (ra - rb + gap)) * n
                _point(out, ids, count, m[0], m[1], m[2], sep, j)
                count += 1
            return count
    s, t = closest_segment_segment(a0, a1, b0, b1)
    p = a0 + s * da
    q = b0 + t * db
    return _balls(p[0], p[1], p[2], ra, q[0], q[1], q[2], rb, margin, 2, out, ids)


@njit(cache=True)
def _normal_of(a0: np.ndarray, da: np.ndarray, la2: float, b0: np.ndarray, out: np.ndarray) -> None:
    """The unit normal from line A to a parallel line through b0 (up when they coincide)."""
    r = b0 - a0
    r = r - (_dot(r, da) / la2) * da
    length = math.sqrt(_dot(r, r))
    if length > 0.0:
        out[0], out[1], out[2] = r[0] / length, r[1] / length, r[2] / length
    else:
        out[0], out[1], out[2] = 0.0, 0.0, 1.0


@njit(cache=True)
def contact_segments_plane(
    ends: np.ndarray, radius: float, normal: np.ndarray, offset: float, margin: float,
    out: np.ndarray, ids: np.ndarray,
) -> int:  # fmt: skip
    """A sphere (``ends`` (1, 3)) or a capsule (``ends`` (2, 3)) of ``radius`` [m] against the
    plane ``normal . x = offset`` (B, solid below): each end within ``margin`` of the plane is
    a point (id: the end's index). The normal from A to B is ``-normal``."""
    return _core_plane(ends, radius, normal, offset, margin, out, ids)


@njit(cache=True)
def contact_hull_plane(
    vertices: np.ndarray, normal: np.ndarray, offset: float, margin: float,
    out: np.ndarray, ids: np.ndarray,
) -> int:  # fmt: skip
    """A convex polyhedron's placed corners ``vertices`` (k, 3) [m] against the plane
    ``normal . x = offset``: the corners within ``margin`` of the plane, at most 4 of them.

    When more are near, four are kept: the deepest; the one farthest from it along the plane;
    the one farthest from the line of those two; and the one that adds the most area to that
    triangle (the greatest distance outside its edges) - so a face resting on the plane keeps
    its outline, and the deepest point is always kept. Ids are the corners' indices.
    """
    return _core_plane(vertices, 0.0, normal, offset, margin, out, ids)


@njit(cache=True)
def _core_plane(
    core: np.ndarray, radius: float, normal: np.ndarray, offset: float, margin: float,
    out: np.ndarray, ids: np.ndarray,
) -> int:  # fmt: skip
    """A rounded core's corners ``core`` (k, 3) within ``margin`` of the plane, at most four
    (:func:`reduce_points`), each midway between the plane and its ball's lowest point."""
    out[0], out[1], out[2] = -normal[0], -normal[1], -normal[2]
    k = core.shape[0]
    near = np.empty(k, np.int64)
    sep = np.empty(k)
    count = 0
    for i in range(k):
        s = _dot(core[i], normal) - offset - radius
        if s <= margin:
            near[count] = i
            sep[count] = s
            count += 1
    if count == 0:
        return 0
    points = np.empty((count, 3))
    for j in range(count):
        points[j] = core[near[j]]
    keep = np.empty(MAX_POINTS, np.int64)
    kept = reduce_points(points, sep, count, normal, keep)
    for j in range(kept):
        i = near[keep[j]]
        # midway between the ball's lowest point (height - radius) and the plane (0)
        h = 0.5 * (sep[keep[j]] + 2.0 * radius)
        _point(
            out,
            ids,
            j,
            core[i, 0] - h * normal[0],
            core[i, 1] - h * normal[1],
            core[i, 2] - h * normal[2],
            sep[keep[j]],
            i,
        )
    return kept


@njit(cache=True, inline="always")
def _dot(u: np.ndarray, v: np.ndarray) -> float:
    """u . v of two (3,) vectors."""
    total: float = u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
    return total


@njit(cache=True, inline="always")
def _flat(points: np.ndarray, j: int, n: np.ndarray) -> tuple[float, float, float]:
    """Point ``j`` of ``points`` projected onto the plane through the origin across ``n``."""
    p = points[j]
    d = p[0] * n[0] + p[1] * n[1] + p[2] * n[2]
    return p[0] - d * n[0], p[1] - d * n[1], p[2] - d * n[2]


@njit(cache=True, inline="always")
def _cross(
    ax: float, ay: float, az: float, bx: float, by: float, bz: float
) -> tuple[float, float, float]:
    """a x b."""
    return ay * bz - az * by, az * bx - ax * bz, ax * by - ay * bx


@leaf
def reduce_points(
    points: np.ndarray, sep: np.ndarray, count: int, normal: np.ndarray, keep: np.ndarray
) -> int:
    """At most four of ``count`` contact candidates ``points`` (k, 3) [m] with separations
    ``sep`` into ``keep`` (their rows): all of them if four or fewer, else the deepest, the
    farthest from it across ``normal``, the farthest from the line of those two, and the one
    adding the most area outside that triangle (ties to the lower row). Returns how many.
    In scalars: no arrays are made."""
    if count <= MAX_POINTS:
        for j in range(count):
            keep[j] = j
        return count
    first = 0
    for j in range(1, count):
        if sep[j] < sep[first]:
            first = j
    fx, fy, fz = _flat(points, first, normal)
    second = first
    best = -1.0
    for j in range(count):
        x, y, z = _flat(points, j, normal)
        dx, dy, dz = x - fx, y - fy, z - fz
        reach = dx * dx + dy * dy + dz * dz
        if reach > best:
            best = reach
            second = j
    sx, sy, sz = _flat(points, second, normal)
    ax, ay, az = sx - fx, sy - fy, sz - fz
    third = first
    best = -1.0
    for j in range(count):
        x, y, z = _flat(points, j, normal)
        cx, cy, cz = _cross(ax, ay, az, x - fx, y - fy, z - fz)
        spread = cx * cx + cy * cy + cz * cz
        if spread > best:
            best = spread
            third = j
    keep[0], keep[1], keep[2] = first, second, third
    # the fourth: most area outside the triangle's edges, on the far side of an edge from the
    # triangle's remaining corner
    tx, ty, tz = _flat(points, third, normal)
    ux, uy, uz = _cross(ax, ay, az, tx - fx, ty - fy, tz - fz)
    fourth = -1
    best = 0.0
    for j in range(count):
        if j in (first, second, third):
            continue
        x, y, z = _flat(points, j, normal)
        for e in range(3):
            # the triangle's edge e, from corner p to corner q
            if e == 0:
                px, py, pz, qx, qy, qz = fx, fy, fz, sx, sy, sz
            elif e == 1:
                px, py, pz, qx, qy, qz = sx, sy, sz, tx, ty, tz
            else:
                px, py, pz, qx, qy, qz = tx, ty, tz, fx, fy, fz
            # signed area of (p, q, x) against the triangle's turn: negative is outside
            cx, cy, cz = _cross(qx - px, qy - py, qz - pz, x - px, y - py, z - pz)
            area = -(cx * ux + cy * uy + cz * uz)
            if area > best:
                best = area
                fourth = j
    if fourth < 0:
        return 3
    keep[3] = fourth
    return 4


@njit(cache=True)
def _face_separation(
    va: np.ndarray, na: np.ndarray, sa: np.ndarray, cora: np.ndarray, vb: np.ndarray
) -> tuple[float, int]:
    """The largest separation of polyhedron B's corners ``vb`` from a face plane of A, and
    that face: for each face, B's deepest corner's height above the plane."""
    best = -np.inf
    face = 0
    for f in range(na.shape[0]):
        n = na[f]
        d = _dot(n, va[cora[sa[f]]])
        deepest = np.inf
        for j in range(vb.shape[0]):
            deepest = min(deepest, _dot(n, vb[j]))
        if deepest - d > best:
            best = deepest - d
            face = f
    return best, face


@njit(cache=True)
def _clip_faces(
    vr: np.ndarray, nr: np.ndarray, sr: np.ndarray, cr: np.ndarray, cor_r: np.ndarray, fr: int,
    vi: np.ndarray, ni: np.ndarray, si: np.ndarray, ci: np.ndarray, cor_i: np.ndarray,
    margin: float, flip: bool, out: np.ndarray, ids: np.ndarray,
) -> int:  # fmt: skip
    """Face contact: the incident face (of the other body, the most anti-parallel to reference
    face ``fr``) clipped to the reference face's sides (Sutherland-Hodgman), the points within
    ``margin`` of the reference plane kept, at most four. ``flip``: the reference body is B."""
    n = nr[fr]
    d = _dot(n, vr[cor_r[sr[fr]]])
    incident = 0
    lowest = np.inf
    for f in range(ni.shape[0]):
        c = _dot(ni[f], n)
        if c < lowest:
            lowest = c
            incident = f
    size = ci[incident] + cr[fr] + 2
    # two layers of (x, y, z, tag, separation) rows: the polygon and the one being clipped
    # out of it, swapped after each side (one allocation)
    work = np.empty((2, size, 5))
    cur = 0
    count = ci[incident]
    for k in range(count):
        corner = cor_i[si[incident] + k]
        for c in range(3):
            work[0, k, c] = vi[corner, c]
        work[0, k, 3] = corner
    for k in range(cr[fr]):
        if count == 0:
            break
        r0 = cor_r[sr[fr] + k]
        r1 = cor_r[sr[fr] + (k + 1) % cr[fr]]
        ex = vr[r1, 0] - vr[r0, 0]
        ey = vr[r1, 1] - vr[r0, 1]
        ez = vr[r1, 2] - vr[r0, 2]
        # the side's outward normal, in the face's plane: edge x n
        sx = ey * n[2] - ez * n[1]
        sy = ez * n[0] - ex * n[2]
        sz = ex * n[1] - ey * n[0]
        level = sx * vr[r0, 0] + sy * vr[r0, 1] + sz * vr[r0, 2]
        nxt = 1 - cur
        kept = 0
        for j in range(count):
            q = (j + 1) % count
            dp = sx * work[cur, j, 0] + sy * work[cur, j, 1] + sz * work[cur, j, 2] - level
            dq = sx * work[cur, q, 0] + sy * work[cur, q, 1] + sz * work[cur, q, 2] - level
            if dp <= 0.0:
                for c in range(4):
                    work[nxt, kept, c] = work[cur, j, c]
                kept += 1
            if (dp <= 0.0) != (dq <= 0.0):
                frac = dp / (dp - dq)
                for c in range(3):
                    work[nxt, kept, c] = work[cur, j, c] + frac * (
                        work[cur, q, c] - work[cur, j, c]
                    )
                tag = int(work[cur, j, 3])
                work[nxt, kept, 3] = (1 << 20) | (k << 10) | (tag & 1023)
                kept += 1
        cur = nxt
        count = kept
    near = 0
    for j in range(count):
        s = n[0] * work[cur, j, 0] + n[1] * work[cur, j, 1] + n[2] * work[cur, j, 2] - d
        if s <= margin:
            for c in range(4):
                work[cur, near, c] = work[cur, j, c]
            work[cur, near, 4] = s
            near += 1
    if near == 0:
        return 0
    keep = np.empty(MAX_POINTS, np.int64)
    kept = reduce_points(work[cur, :, :3], work[cur, :, 4], near, n, keep)
    sign = -1.0 if flip else 1.0
    out[0], out[1], out[2] = sign * n[0], sign * n[1], sign * n[2]
    face_bits = (fr << 40) | (incident << 30) | ((1 << 29) if flip else 0)
    for j in range(kept):
        row = keep[j]
        s = work[cur, row, 4]
        # midway between the incident point and the reference plane
        _point(
            out,
            ids,
            j,
            work[cur, row, 0] - 0.5 * s * n[0],
            work[cur, row, 1] - 0.5 * s * n[1],
            work[cur, row, 2] - 0.5 * s * n[2],
            s,
            face_bits | int(work[cur, row, 3]),
        )
    return kept


@njit(cache=True, inline="always")
def _edge(v: np.ndarray, e: np.ndarray, i: int) -> tuple[float, float, float]:
    """Edge i's vector, first corner to second [m]."""
    a = e[i, 0]
    b = e[i, 1]
    return v[b, 0] - v[a, 0], v[b, 1] - v[a, 1], v[b, 2] - v[a, 2]


@leaf
def _directions(v: np.ndarray, e: np.ndarray, out: np.ndarray) -> int:
    """The edges of distinct directions (the first of each set of parallel edges) into
    ``out``; a box's 12 edges have 3."""
    count = 0
    for i in range(e.shape[0]):
        ux, uy, uz = _edge(v, e, i)
        uu = ux * ux + uy * uy + uz * uz
        seen = False
        for k in range(count):
            wx, wy, wz = _edge(v, e, out[k])
            cx, cy, cz = uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx
            if cx * cx + cy * cy + cz * cz <= _PARALLEL * uu * (wx * wx + wy * wy + wz * wz):
                seen = True
                break
        if not seen:
            out[count] = i
            count += 1
    return count


@njit(cache=True, inline="always")
def _extent(v: np.ndarray, x: float, y: float, z: float) -> tuple[float, float]:
    """Least and greatest of the corners ``v`` along (x, y, z)."""
    low = np.inf
    high = -np.inf
    for k in range(v.shape[0]):
        d = v[k, 0] * x + v[k, 1] * y + v[k, 2] * z
        low = min(low, d)
        high = max(high, d)
    return low, high


@leaf
def _support_edge(
    v: np.ndarray, e: np.ndarray, like: int, x: float, y: float, z: float, level: float,
    tol: float,
) -> int:  # fmt: skip
    """An edge parallel to edge ``like`` with both corners at ``level`` along (x, y, z)
    (within ``tol``), or -1."""
    ux, uy, uz = _edge(v, e, like)
    uu = ux * ux + uy * uy + uz * uz
    for i in range(e.shape[0]):
        wx, wy, wz = _edge(v, e, i)
        cx, cy, cz = uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx
        if cx * cx + cy * cy + cz * cz > _PARALLEL * uu * (wx * wx + wy * wy + wz * wz):
            continue
        if _at_level(v, e, i, x, y, z, level, tol):
            return i
    return -1


@njit(cache=True)
def _gauss_edge_separation(
    va: np.ndarray, ea: np.ndarray, vb: np.ndarray, eb: np.ndarray,
    na: np.ndarray, nb: np.ndarray, floor: float,
) -> tuple[float, int, int, float, float, float]:  # fmt: skip
    """:func:`_edge_separation` over the edge pairs that make a face of the Minkowski
    difference A - B: edge i of A, between faces with normals a and b, and edge j of B,
    between c and d, when the arc a-b and the arc -c to -d cross on the unit sphere. An edge
    between a face and its own back (a mesh triangle, whose arc is a half circle) is always
    tried. Axes that separate by ``floor`` [m] or less are passed over before any square
    root (the face axes already do as well); -inf with no edges above the floor."""
    best = -np.inf
    best_i = -1
    best_j = -1
    bx = by = bz = 0.0
    top_a = bottom_b = 0.0
    # A's centre (the mean of its corners: inside it), to turn each axis outward
    cx = cy = cz = 0.0
    for k in range(va.shape[0]):
        cx += va[k, 0]
        cy += va[k, 1]
        cz += va[k, 2]
    cx /= va.shape[0]
    cy /= va.shape[0]
    cz /= va.shape[0]
    # B's arcs in rows (one allocation): the face normals c and d at each edge, the pole
    # d x c, whether the arc is a half circle; then, for each edge of A, whether it crosses
    n_b = eb.shape[0]
    arcs = np.empty((11, n_b))
    for j in range(n_b):
        fb0 = eb[j, 2]
        fb1 = eb[j, 3]
        c0, c1, c2 = nb[fb0, 0], nb[fb0, 1], nb[fb0, 2]
        d0, d1, d2 = nb[fb1, 0], nb[fb1, 1], nb[fb1, 2]
        arcs[0, j], arcs[1, j], arcs[2, j] = c0, c1, c2
        arcs[3, j], arcs[4, j], arcs[5, j] = d0, d1, d2
        arcs[6, j] = d1 * c2 - d2 * c1
        arcs[7, j] = d2 * c0 - d0 * c2
        arcs[8, j] = d0 * c1 - d1 * c0
        arcs[9, j] = 1.0 if 1.0 + (c0 * d0 + c1 * d1 + c2 * d2) <= 0.5 * _PARALLEL else 0.0
    cross = arcs[10]
    for i in range(ea.shape[0]):
        fa0 = ea[i, 2]
        fa1 = ea[i, 3]
        a0, a1, a2 = na[fa0, 0], na[fa0, 1], na[fa0, 2]
        b0, b1, b2 = na[fa1, 0], na[fa1, 1], na[fa1, 2]
        # b x a: the arc's pole
        px = b1 * a2 - b2 * a1
        py = b2 * a0 - b0 * a2
        pz = b0 * a1 - b1 * a0
        # a face and its own back (a mesh triangle): the arc is a half circle
        flat_a = 1.0 + (a0 * b0 + a1 * b1 + a2 * b2) <= 0.5 * _PARALLEL
        ux, uy, uz = _edge(va, ea, i)
        uu = ux * ux + uy * uy + uz * uz
        # do -c and -d lie on either side of the plane of arc a-b, and a and b on either side
        # of the arc from -c to -d, whose pole is (-d) x (-c) = d x c, on the same side as
        # each other's arcs? Every edge of B at once, without branches (the compiler makes
        # vectors of it); a half circle is always tried
        for j in range(n_b):
            cba = -(arcs[0, j] * px + arcs[1, j] * py + arcs[2, j] * pz)
            dba = -(arcs[3, j] * px + arcs[4, j] * py + arcs[5, j] * pz)
            adc = a0 * arcs[6, j] + a1 * arcs[7, j] + a2 * arcs[8, j]
            bdc = b0 * arcs[6, j] + b1 * arcs[7, j] + b2 * arcs[8, j]
            crosses = (cba * dba < 0.0) & (adc * bdc < 0.0) & (cba * bdc > 0.0)
            cross[j] = 1.0 if crosses | flat_a | (arcs[9, j] != 0.0) else 0.0
        for j in range(n_b):
            if cross[j] == 0.0:
                continue
            flat_b = arcs[9, j] != 0.0
            wx, wy, wz = _edge(vb, eb, j)
            x, y, z = uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx
            length2 = x * x + y * y + z * z
            if length2 <= _PARALLEL * uu * (wx * wx + wy * wy + wz * wz):
                continue  # parallel edges: their plane's normal is a face axis already
            if flat_a or flat_b:
                # a flat piece's edge need not be a support edge: the extents decide
                scale = 1.0 / math.sqrt(length2)
                x, y, z = x * scale, y * scale, z * scale
                low_a, high_a = _extent(va, x, y, z)
                low_b, high_b = _extent(vb, x, y, z)
                if low_b - high_a >= low_a - high_b:  # B ahead of A along the axis
                    sep = low_b - high_a
                else:  # behind: turn the axis round
                    sep = low_a - high_b
                    x, y, z = -x, -y, -z
                    low_b, high_a = -high_b, -low_a
            else:
                # a face of A - B: the edges are the supports, the axis points out of A at
                # its edge (away from A's centre), and the gap is between the edges' lines
                pa = ea[i, 0]
                pb = eb[j, 0]
                if (va[pa, 0] - cx) * x + (va[pa, 1] - cy) * y + (va[pa, 2] - cz) * z < 0.0:
                    x, y, z = -x, -y, -z
                gap = (
                    (vb[pb, 0] - va[pa, 0]) * x
                    + (vb[pb, 1] - va[pa, 1]) * y
                    + (vb[pb, 2] - va[pa, 2]) * z
                )  # the separation times |x, y, z|
                if floor >= 0.0:
                    if gap <= 0.0 or gap * gap <= floor * floor * length2:
                        continue
                elif gap < 0.0 and gap * gap >= floor * floor * length2:
                    continue
                scale = 1.0 / math.sqrt(length2)
                x, y, z = x * scale, y * scale, z * scale
                high_a = va[pa, 0] * x + va[pa, 1] * y + va[pa, 2] * z
                low_b = vb[pb, 0] * x + vb[pb, 1] * y + vb[pb, 2] * z
                sep = low_b - high_a
            if sep > best:
                best, best_i, best_j = sep, i, j
                bx, by, bz = x, y, z
                top_a, bottom_b = high_a, low_b
    if best_i < 0:
        return best, -1, -1, 0.0, 0.0, 0.0
    # a solid's crossing edges are its support edges along the axis; a flat piece's edges,
    # always tried, may not be: then a parallel edge at the support level is looked up
    tol = 1e-9 * _size(va, vb)
    if not _at_level(va, ea, best_i, bx, by, bz, top_a, tol):
        best_i = _support_edge(va, ea, best_i, bx, by, bz, top_a, tol)
    if not _at_level(vb, eb, best_j, bx, by, bz, bottom_b, tol):
        best_j = _support_edge(vb, eb, best_j, bx, by, bz, bottom_b, tol)
    if best_i < 0 or best_j < 0:
        return best, -1, -1, bx, by, bz
    return best, best_i, best_j, bx, by, bz


@njit(cache=True, inline="always")
def _size(va: np.ndarray, vb: np.ndarray) -> float:
    """The largest |x| + |y| + |z| of two corner sets [m] (a round-off scale)."""
    size = 0.0
    for k in range(va.shape[0]):
        size = max(size, abs(va[k, 0]) + abs(va[k, 1]) + abs(va[k, 2]))
    for k in range(vb.shape[0]):
        size = max(size, abs(vb[k, 0]) + abs(vb[k, 1]) + abs(vb[k, 2]))
    return size


@njit(cache=True, inline="always")
def _at_level(
    v: np.ndarray, e: np.ndarray, i: int, x: float, y: float, z: float, level: float, tol: float
) -> bool:
    """Whether both corners of edge i lie at ``level`` along (x, y, z), within ``tol``."""
    a = e[i, 0]
    b = e[i, 1]
    level_a: float = v[a, 0] * x + v[a, 1] * y + v[a, 2] * z
    level_b: float = v[b, 0] * x + v[b, 1] * y + v[b, 2] * z
    return abs(level_a - level) <= tol and abs(level_b - level) <= tol


@njit(cache=True)
def _edge_separation(
    va: np.ndarray, ea: np.ndarray, vb: np.ndarray, eb: np.ndarray,
    na: np.ndarray, nb: np.ndarray, floor: float,
) -> tuple[float, int, int, float, float, float]:  # fmt: skip
    """The largest separation along the cross product of an edge of A and one of B, the
    support edges along it (-1 if none: a degenerate axis), and the axis, from A to B.

    Along an axis the two bodies' extents are intervals; their gap, whichever lies ahead,
    is the separation (negative: the overlap). When both edge lists name the two faces at
    each edge (``(E, 4)``, with the face normals ``na``, ``nb``), only the pairs whose arcs
    cross on the Gauss map are tried (Gregorius, GDC 2013): those axes are the faces of the
    Minkowski difference, among which the deepest overlap always lies, and the two edges are
    then the support edges; axes separating by ``floor`` or less are passed over. Otherwise
    only distinct directions are crossed (a box pair: 3 x 3 axes, not 12 x 12) and the
    support edges are looked up for the best axis.
    """
    if ea.shape[1] == 4 and eb.shape[1] == 4:
        return _gauss_edge_separation(va, ea, vb, eb, na, nb, floor)
    dir_a = np.empty(ea.shape[0], np.int64)
    dir_b = np.empty(eb.shape[0], np.int64)
    na_ = _directions(va, ea, dir_a)
    nb_ = _directions(vb, eb, dir_b)
    best = -np.inf
    best_i = -1
    best_j = -1
    bx = by = bz = 0.0
    high_a = low_b = 0.0
    for i in range(na_):
        ux, uy, uz = _edge(va, ea, dir_a[i])
        uu = ux * ux + uy * uy + uz * uz
        for j in range(nb_):
            wx, wy, wz = _edge(vb, eb, dir_b[j])
            x, y, z = uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx
            length2 = x * x + y * y + z * z
            if length2 <= _PARALLEL * uu * (wx * wx + wy * wy + wz * wz):
                continue  # parallel edges: their plane's normal is a face axis already
            scale = 1.0 / math.sqrt(length2)
            x, y, z = x * scale, y * scale, z * scale
            low_a_, high_a_ = _extent(va, x, y, z)
            low_b_, high_b_ = _extent(vb, x, y, z)
            if low_b_ - high_a_ >= low_a_ - high_b_:  # B ahead of A along the axis
                s = low_b_ - high_a_
            else:  # behind: turn the axis round
                s = low_a_ - high_b_
                x, y, z = -x, -y, -z
                low_b_, high_a_ = -high_b_, -low_a_
            if s > best:
                best, best_i, best_j = s, dir_a[i], dir_b[j]
                bx, by, bz = x, y, z
                high_a, low_b = high_a_, low_b_
    if best_i < 0:
        return best, -1, -1, 0.0, 0.0, 0.0
    tol = 1e-9 * _size(va, vb)  # round-off of a corner's level along the axis [m]
    edge_a = _support_edge(va, ea, best_i, bx, by, bz, high_a, tol)
    edge_b = _support_edge(vb, eb, best_j, bx, by, bz, low_b, tol)
    if edge_a < 0 or edge_b < 0:
        return best, -1, -1, bx, by, bz
    return best, edge_a, edge_b, bx, by, bz


@njit(cache=True)
def contact_hull_hull(
    va: np.ndarray, na: np.ndarray, sa: np.ndarray, ca: np.ndarray, cora: np.ndarray,
    ea: np.ndarray, vb: np.ndarray, nb: np.ndarray, sb: np.ndarray, cb: np.ndarray,
    corb: np.ndarray, eb: np.ndarray, margin: float, slop: float, out: np.ndarray,
    ids: np.ndarray,
) -> int:  # fmt: skip
    """Convex polyhedron A against convex polyhedron B, by separating axes (the face normals
    of each, and the cross products of an edge of each) and face clipping.

    Each polyhedron is given placed: corners ``v`` (k, 3) [m], face normals ``n`` (F, 3),
    faces' first corner ``s`` and corner count ``c`` (F,) into ``cor`` (vertex indices,
    counter-clockwise from outside), and edges ``e`` (E, 4: two corners, two faces)
    (:func:`carom.geometry.polyhedron.polyhedron_features`, turned and moved).

    The axis of largest separation decides (Gottschalk's separating-axis test, as Gregorius
    presents it for games, GDC 2013). When an edge pair's axis separates more than every face
    axis, by ``slop/10`` [m] or more, the edges touch: one point midway between their closest
    points. Otherwise the face with the larger separation (A's, in a tie within ``slop/10``)
    is the reference and the other body's most anti-parallel face is clipped to it: up to four
    points, normal along the reference face's.

    Returns
    -------
    int
        Number of points, 0 to 4 (module docstring for ``out`` and ``ids``).
    """
    sep_a, face_a = _face_separation(va, na, sa, cora, vb)
    if sep_a > margin:
        out[6] = sep_a  # a separating axis: the gap is at least this
        return 0
    sep_b, face_b = _face_separation(vb, nb, sb, corb, va)
    if sep_b > margin:
        out[6] = sep_b
        return 0
    # edge axes matter only where they separate more than every face axis
    sep_e, edge_a, edge_b, ax, ay, az = _edge_separation(va, ea, vb, eb, na, nb, max(sep_a, sep_b))
    if sep_e > margin:
        out[6] = sep_e
        return 0
    tie = 0.1 * slop
    if edge_a >= 0 and sep_e > max(sep_a, sep_b) + tie:
        a0 = va[ea[edge_a, 0]]
        a1 = va[ea[edge_a, 1]]
        b0 = vb[eb[edge_b, 0]]
        b1 = vb[eb[edge_b, 1]]
        s, t = closest_segment_segment(a0, a1, b0, b1)
        mx = 0.5 * ((a0[0] + s * (a1[0] - a0[0])) + (b0[0] + t * (b1[0] - b0[0])))
        my = 0.5 * ((a0[1] + s * (a1[1] - a0[1])) + (b0[1] + t * (b1[1] - b0[1])))
        mz = 0.5 * ((a0[2] + s * (a1[2] - a0[2])) + (b0[2] + t * (b1[2] - b0[2])))
        out[0], out[1], out[2] = ax, ay, az
        _point(out, ids, 0, mx, my, mz, sep_e, (1 << 50) | (edge_a << 20) | edge_b)
        return 1
    if sep_a + tie >= sep_b:
        count = _clip_faces(
            va, na, sa, ca, cora, face_a, vb, nb, sb, cb, corb, margin, False, out, ids
        )
    else:
        count = _clip_faces(
            vb, nb, sb, cb, corb, face_b, va, na, sa, ca, cora, margin, True, out, ids
        )
    if count == 0 and max(sep_a, sep_b, sep_e) > 0.0:
        # apart and beside each other (a corner passing a face's edge): the clipped faces do
        # not overlap; the exact closest points decide
        return closest_hulls(va, na, sa, ca, cora, ea, vb, nb, sb, cb, corb, eb, margin, out, ids)
    if count == 0:
        # overlapping deeply, the incident face outside the reference face's sides: the
        # other body's corner deepest below the reference face still says how far to push
        if sep_a + tie >= sep_b:
            return _deepest_corner(va, na, sa, cora, face_a, vb, False, out, ids)
        return _deepest_corner(vb, nb, sb, corb, face_b, va, True, out, ids)
    return count


@njit(cache=True)
def _deepest_corner(
    vr: np.ndarray, nr: np.ndarray, sr: np.ndarray, cor_r: np.ndarray, fr: int, vi: np.ndarray,
    flip: bool, out: np.ndarray, ids: np.ndarray,
) -> int:  # fmt: skip
    """One point: the corner of the incident body (``vi``) deepest below reference face
    ``fr``, midway to the face's plane, with its separation (the face's separation, <= 0);
    the normal along the face's (``flip``: the reference body is B)."""
    n = nr[fr]
    d = _dot(n, vr[cor_r[sr[fr]]])
    best = np.inf
    k = 0
    for j in range(vi.shape[0]):
        s = _dot(n, vi[j]) - d
        if s < best:
            best = s
            k = j
    sign = -1.0 if flip else 1.0
    out[0], out[1], out[2] = sign * n[0], sign * n[1], sign * n[2]
    x, y, z = (
        vi[k, 0] - 0.5 * best * n[0],
        vi[k, 1] - 0.5 * best * n[1],
        vi[k, 2] - 0.5 * best * n[2],
    )
    _point(out, ids, 0, x, y, z, best, (4 << 50) | (fr << 30) | ((1 << 29) if flip else 0) | k)
    return 1


@njit(cache=True)
def closest_hulls(
    va: np.ndarray, na: np.ndarray, sa: np.ndarray, ca: np.ndarray, cora: np.ndarray,
    ea: np.ndarray, vb: np.ndarray, nb: np.ndarray, sb: np.ndarray, cb: np.ndarray,
    corb: np.ndarray, eb: np.ndarray, margin: float, out: np.ndarray, ids: np.ndarray,
) -> int:  # fmt: skip
    """One point at the closest points of two disjoint convex polytopes: the least over A's
    corners against B, B's corners against A, and A's edges against B's (every closest pair
    of two convex polytopes is one of these). Its separation is their exact distance (the
    exact impacts advance on it); none when they touch or are further apart than
    ``margin``."""
    best = np.inf
    ax = ay = az = bx = by = bz = 0.0  # the closest points on A and on B
    feature = 0
    for i in range(va.shape[0]):
        d, qx, qy, qz, f = _closest_on_hull(vb, nb, sb, cb, corb, eb, va[i, 0], va[i, 1], va[i, 2])
        if d < best:
            best, feature = d, (2 << 50) | (i << 25) | f
            ax, ay, az, bx, by, bz = va[i, 0], va[i, 1], va[i, 2], qx, qy, qz
    for j in range(vb.shape[0]):
        d, qx, qy, qz, f = _closest_on_hull(va, na, sa, ca, cora, ea, vb[j, 0], vb[j, 1], vb[j, 2])
        if d < best:
            best, feature = d, (3 << 50) | (j << 25) | f
            ax, ay, az, bx, by, bz = qx, qy, qz, vb[j, 0], vb[j, 1], vb[j, 2]
    for i in range(ea.shape[0]):
        p0 = va[ea[i, 0]]
        p1 = va[ea[i, 1]]
        for j in range(eb.shape[0]):
            q0 = vb[eb[j, 0]]
            q1 = vb[eb[j, 1]]
            s, t = closest_segment_segment(p0, p1, q0, q1)
            px = p0[0] + s * (p1[0] - p0[0])
            py = p0[1] + s * (p1[1] - p0[1])
            pz = p0[2] + s * (p1[2] - p0[2])
            qx = q0[0] + t * (q1[0] - q0[0])
            qy = q0[1] + t * (q1[1] - q0[1])
            qz = q0[2] + t * (q1[2] - q0[2])
            dx, dy, dz = qx - px, qy - py, qz - pz
            d = math.sqrt(dx * dx + dy * dy + dz * dz)
            if d < best:
                best, feature = d, (1 << 50) | (i << 20) | j
                ax, ay, az, bx, by, bz = px, py, pz, qx, qy, qz
    if best > margin or not best > 0.0:
        return 0
    out[0], out[1], out[2] = (bx - ax) / best, (by - ay) / best, (bz - az) / best
    _point(out, ids, 0, 0.5 * (ax + bx), 0.5 * (ay + by), 0.5 * (az + bz), best, feature)
    return 1


@leaf
def _closest_on_hull(
    va: np.ndarray, na: np.ndarray, sa: np.ndarray, ca: np.ndarray, cora: np.ndarray,
    ea: np.ndarray, bx: float, by: float, bz: float,
) -> tuple[float, float, float, float, int]:  # fmt: skip
    """Distance [m] from a point ``(bx, by, bz)`` on or outside a convex polytope to it, the
    nearest point (x, y, z), and its feature: a face whose plane the point is on or above and
    whose foot falls inside it (id: the face), or else an edge (id: ``1 << 20`` plus the
    edge). In scalars: no arrays are made."""
    best = np.inf
    cx = cy = cz = 0.0
    feature = 0
    for f in range(na.shape[0]):
        nx, ny, nz = na[f, 0], na[f, 1], na[f, 2]
        first = va[cora[sa[f]]]
        h = (nx * bx + ny * by + nz * bz) - (nx * first[0] + ny * first[1] + nz * first[2])
        if h < 0.0:
            continue
        fx, fy, fz = bx - h * nx, by - h * ny, bz - h * nz
        inside = True
        for k in range(ca[f]):
            r0 = va[cora[sa[f] + k]]
            r1 = va[cora[sa[f] + (k + 1) % ca[f]]]
            ex, ey, ez = r1[0] - r0[0], r1[1] - r0[1], r1[2] - r0[2]
            # (r1 - r0) x n, the side's outward normal in the face's plane
            sx, sy, sz = ey * nz - ez * ny, ez * nx - ex * nz, ex * ny - ey * nx
            if sx * (fx - r0[0]) + sy * (fy - r0[1]) + sz * (fz - r0[2]) > 0.0:
                inside = False
                break
        if inside and h < best:
            best = h
            cx, cy, cz = fx, fy, fz
            feature = f
    for e in range(ea.shape[0]):
        p0 = va[ea[e, 0]]
        p1 = va[ea[e, 1]]
        t = _on_segment(p0, p1, bx, by, bz)
        qx = p0[0] + t * (p1[0] - p0[0])
        qy = p0[1] + t * (p1[1] - p0[1])
        qz = p0[2] + t * (p1[2] - p0[2])
        dx, dy, dz = bx - qx, by - qy, bz - qz
        distance = math.sqrt(dx * dx + dy * dy + dz * dz)
        if distance < best:
            best = distance
            cx, cy, cz = qx, qy, qz
            feature = (1 << 20) | e
    return best, cx, cy, cz, feature


@njit(cache=True)
def contact_hull_sphere(
    va: np.ndarray, na: np.ndarray, sa: np.ndarray, ca: np.ndarray, cora: np.ndarray,
    ea: np.ndarray, b: np.ndarray, rb: float, margin: float, out: np.ndarray, ids: np.ndarray,
) -> int:  # fmt: skip
    """Convex polyhedron A (placed as in :func:`contact_hull_hull`) against sphere (``b``,
    ``rb``): the exact closest point of A's surface to the centre.

    Inside A, the face the centre is least deep below is the way out (id: the face). Outside,
    the closest point is on a face whose plane the centre is above, where its foot falls
    inside the face (id: the face), or else on an edge (id: ``1 << 20`` plus the edge).
    """
    highest = -np.inf
    top = 0
    for f in range(na.shape[0]):
        h = _dot(na[f], b) - _dot(na[f], va[cora[sa[f]]])
        if h > highest:
            highest = h
            top = f
    if highest - rb > margin:
        out[6] = highest - rb  # a face plane separates them by more than the margin
        return 0
    if highest < 0.0:  # the centre is inside (a flat polytope, a mesh triangle, has no inside)
        n = na[top]
        m = b - 0.5 * (rb + highest) * n  # midway between b - rb n and the face, b - highest n
        out[0], out[1], out[2] = n[0], n[1], n[2]
        _point(out, ids, 0, m[0], m[1], m[2], highest - rb, top)
        return 1
    best, cx, cy, cz, feature = _closest_on_hull(va, na, sa, ca, cora, ea, b[0], b[1], b[2])
    sep = best - rb
    if sep > margin:
        out[6] = sep  # the exact gap
        return 0
    if best > 0.0:
        nx, ny, nz = (b[0] - cx) / best, (b[1] - cy) / best, (b[2] - cz) / best
    else:  # on the surface itself: out along the face it lies on
        nx, ny, nz = na[top, 0], na[top, 1], na[top, 2]
    h = 0.5 * (best - rb)
    out[0], out[1], out[2] = nx, ny, nz
    _point(out, ids, 0, cx + h * nx, cy + h * ny, cz + h * nz, sep, feature)
    return 1


@njit(cache=True)
def _segment_on_face(
    va: np.ndarray, na: np.ndarray, sa: np.ndarray, ca: np.ndarray, cora: np.ndarray, f: int,
    p0: np.ndarray, p1: np.ndarray, rb: float, margin: float, out: np.ndarray, ids: np.ndarray,
) -> int:  # fmt: skip
    """The segment p0-p1 (a capsule's core, radius ``rb``) clipped to face ``f``'s sides; each
    clipped end within ``margin`` of the face is a point (ids: face f, end 0 or 1)."""
    n = na[f]
    d = _dot(n, va[cora[sa[f]]])
    lo = 0.0
    hi = 1.0
    u = p1 - p0
    for k in range(ca[f]):
        r0 = va[cora[sa[f] + k]]
        r1 = va[cora[sa[f] + (k + 1) % ca[f]]]
        side = np.cross(r1 - r0, n)
        a = _dot(side, p0 - r0)  # beyond the side where > 0
        b = _dot(side, u)
        if b == 0.0:
            if a > 0.0:
                return 0
            continue
        t = -a / b
        if b > 0.0:
            hi = min(hi, t)
        else:
            lo = max(lo, t)
    if lo > hi:
        return 0
    out[0], out[1], out[2] = n[0], n[1], n[2]
    count = 0
    for j, t in enumerate((lo, hi)):
        if j == 1 and hi == lo:
            break
        p = p0 + t * u
        h = _dot(n, p) - d
        sep = h - rb
        if sep > margin:
            continue
        m = p - 0.5 * (h + rb) * n  # midway between the face (p - h n) and p - rb n
        _point(out, ids, count, m[0], m[1], m[2], sep, (f << 20) | j)
        count += 1
    return count


@njit(cache=True)
def contact_hull_capsule(
    va: np.ndarray, na: np.ndarray, sa: np.ndarray, ca: np.ndarray, cora: np.ndarray,
    ea: np.ndarray, b0: np.ndarray, b1: np.ndarray, rb: float, margin: float, slop: float,
    out: np.ndarray, ids: np.ndarray,
) -> int:  # fmt: skip
    """Convex polyhedron A (placed as in :func:`contact_hull_hull`) against capsule
    (segment ``b0``-``b1``, radius ``rb``).

    The separating axes of a polyhedron and a segment are A's face normals and the cross
    products of the segment with A's edges. Where a face axis decides (within ``slop/10``),
    the segment is clipped to that face: one or two points, so a capsule lying on a box
    rests on both ends. Where an edge axis decides, one point at the closest points of the
    segment and that edge. When the two are apart, the gap is the exact distance (the least
    over the segment's ends against A, and the segment against A's edges), so speculative
    contact never reports less than the true gap's separation.
    """
    u = b1 - b0
    # face axes: the segment's lower end above each face's plane
    sep_f = -np.inf
    face = 0
    for f in range(na.shape[0]):
        d = _dot(na[f], va[cora[sa[f]]])
        h = min(_dot(na[f], b0), _dot(na[f], b1)) - d
        if h > sep_f:
            sep_f = h
            face = f
    # edge axes: the segment is a polytope of one edge
    ends = np.empty((2, 3))
    ends[0] = b0
    ends[1] = b1
    sep_e, edge, _, ax, ay, az = _edge_separation(va, ea, ends, _ONE_EDGE, na, na, -np.inf)
    if max(sep_f, sep_e) - rb > margin:
        return 0
    if max(sep_f, sep_e) > 0.0:
        # apart: the exact distance decides; the closest features give the points
        best = np.inf
        closest = np.zeros(3)
        on_segment = np.zeros(3)
        feature = -1
        for j in range(2):
            end = b0 if j == 0 else b1
            d, qx, qy, qz, f = _closest_on_hull(va, na, sa, ca, cora, ea, end[0], end[1], end[2])
            q = np.array([qx, qy, qz])
            if d < best:
                best = d
                closest = q
                on_segment = end.copy()
                feature = f if f < (1 << 20) else -1 - (f - (1 << 20))
        for e in range(ea.shape[0]):
            p0 = va[ea[e, 0]]
            p1 = va[ea[e, 1]]
            s, t = closest_segment_segment(b0, b1, p0, p1)
            p = b0 + s * u
            q = p0 + t * (p1 - p0)
            dd = p - q
            distance = math.sqrt(_dot(dd, dd))
            if distance < best:
                best = distance
                closest = q
                on_segment = p
                feature = -1 - e
        if best - rb > margin:
            return 0
        if feature >= 0:  # an end above a face: the segment on that face, one or two points
            return _segment_on_face(va, na, sa, ca, cora, feature, b0, b1, rb, margin, out, ids)
        n = (on_segment - closest) / best
        m = closest + 0.5 * (best - rb) * n
        out[0], out[1], out[2] = n[0], n[1], n[2]
        _point(out, ids, 0, m[0], m[1], m[2], best - rb, (1 << 50) | (-1 - feature))
        return 1
    if edge >= 0 and sep_e > sep_f + 0.1 * slop:
        p0 = va[ea[edge, 0]]
        p1 = va[ea[edge, 1]]
        s, t = closest_segment_segment(b0, b1, p0, p1)
        p = b0 + s * u
        q = p0 + t * (p1 - p0)
        m = 0.5 * (p + q) - 0.5 * rb * np.array([ax, ay, az])
        out[0], out[1], out[2] = ax, ay, az
        _point(out, ids, 0, m[0], m[1], m[2], sep_e - rb, (1 << 50) | edge)
        return 1
    return _segment_on_face(va, na, sa, ca, cora, face, b0, b1, rb, margin, out, ids)
