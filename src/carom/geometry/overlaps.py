"""Whether a point or an axis-aligned box overlaps a placed piece, exactly (issue 43, item 4).

2D pieces are rounded convex polygons (a core of 1, 2 or more corners and a radius): a point
or a box overlaps one when its exact distance to the core is at most the radius (the distance
between convex polygons, :func:`carom.geometry.manifold2d.core_witness`: zero when they
overlap, else attained between a corner of one and an edge of the other).

3D pieces: a sphere or a capsule (a core point or segment and a radius) overlaps a point or a
box within the radius of its core; the point to a box is clamped to it; a segment's least
distance to a box is the minimum of a convex function of the segment's parameter, found by
golden-section search to round-off. A sharp polytope (a box, a hull) holds a point under
every face's plane, and meets a box unless an axis separates them: the box's three axes, the
polytope's face normals, or the cross product of a box axis and a polytope edge (the
separating-axis theorem for convex polytopes). A mesh triangle (a flat polytope of two faces)
holds no point, and meets a box by the same test. A plane's solid is the half-space under it.
Touching counts as overlapping.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.geometry.manifold2d import core_witness
from carom.jit import leaf

__all__ = [
    "box_meets_piece_3d",
    "box_meets_polygon",
    "point_in_piece_3d",
    "point_in_polygon",
]

#: the 2D box's outward edge normals, corners counter-clockwise from its low corner
_BOX_NORMALS = np.array([[0.0, -1.0], [1.0, 0.0], [0.0, 1.0], [-1.0, 0.0]])


@njit(cache=True)
def point_in_polygon(
    p: np.ndarray, v: np.ndarray, n: np.ndarray, count: int, radius: float
) -> bool:
    """Whether point ``p`` (2,) lies in the rounded convex polygon of ``count`` corners ``v``
    (k, 2), outward edge normals ``n`` (k, 2) and ``radius`` [m]."""
    vertices = np.empty((count + 1, 2))
    normals = np.zeros((count + 1, 2))
    vertices[:count] = v[:count]
    normals[:count] = n[:count]
    vertices[count] = p
    distance = core_witness(vertices, normals, 0, count, count, 1)[0]
    return bool(distance <= radius)


@njit(cache=True)
def box_meets_polygon(
    low: np.ndarray, high: np.ndarray, v: np.ndarray, n: np.ndarray, count: int, radius: float
) -> bool:
    """Whether the box ``[low, high]`` (2,) meets the rounded convex polygon ``v``, ``n``,
    ``count``, ``radius`` (as :func:`point_in_polygon`)."""
    vertices = np.empty((count + 4, 2))
    normals = np.empty((count + 4, 2))
    vertices[:count] = v[:count]
    normals[:count] = n[:count]
    vertices[count, 0], vertices[count, 1] = low[0], low[1]
    vertices[count + 1, 0], vertices[count + 1, 1] = high[0], low[1]
    vertices[count + 2, 0], vertices[count + 2, 1] = high[0], high[1]
    vertices[count + 3, 0], vertices[count + 3, 1] = low[0], high[1]
    normals[count:] = _BOX_NORMALS
    distance = core_witness(vertices, normals, 0, count, count, 4)[0]
    return bool(distance <= radius)


@njit(cache=True, inline="always")
def _to_box(low: np.ndarray, high: np.ndarray, x: float, y: float, z: float) -> float:
    """Distance from ``(x, y, z)`` to the box ``[low, high]`` [m] (0 inside)."""
    dx = max(low[0] - x, 0.0, x - high[0])
    dy = max(low[1] - y, 0.0, y - high[1])
    dz = max(low[2] - z, 0.0, z - high[2])
    return math.sqrt(dx * dx + dy * dy + dz * dz)


@leaf
def _segment_to_box(low: np.ndarray, high: np.ndarray, a: np.ndarray, b: np.ndarray) -> float:
    """Least distance from the segment ``a b`` to the box [m]: the distance along the
    segment is convex, so golden-section search finds its minimum (to round-off in 80
    steps)."""
    lo, hi = 0.0, 1.0
    g = 0.5 * (math.sqrt(5.0) - 1.0)
    best = min(_to_box(low, high, a[0], a[1], a[2]), _to_box(low, high, b[0], b[1], b[2]))
    for _ in range(80):
        t1 = hi - g * (hi - lo)
        t2 = lo + g * (hi - lo)
        f1 = _to_box(
            low, high, a[0] + t1 * (b[0] - a[0]), a[1] + t1 * (b[1] - a[1]),
            a[2] + t1 * (b[2] - a[2]),
        )  # fmt: skip
        f2 = _to_box(
            low, high, a[0] + t2 * (b[0] - a[0]), a[1] + t2 * (b[1] - a[1]),
            a[2] + t2 * (b[2] - a[2]),
        )  # fmt: skip
        best = min(best, f1, f2)
        if f1 <= f2:
            hi = t2
        else:
            lo = t1
    return best


@leaf
def point_in_piece_3d(
    p: np.ndarray, kind: int, v: np.ndarray, count: int, n: np.ndarray, faces: int,
    face_first: np.ndarray, corners: np.ndarray, radius: float,
) -> bool:  # fmt: skip
    """Whether point ``p`` (3,) lies in a placed 3D piece: its kind (0 round, 1 polytope,
    2 plane), ``count`` corners ``v`` (k, 3), ``faces`` outward normals ``n`` (f, 3), each
    face's first corner ``face_first`` (f,) into the piece's ``corners`` (vertex indices),
    and ``radius`` [m]."""
    if kind == 2:  # a plane: the half-space under it
        return bool(
            (p[0] - v[0, 0]) * n[0, 0] + (p[1] - v[0, 1]) * n[0, 1] + (p[2] - v[0, 2]) * n[0, 2]
            <= 0.0
        )
    if kind == 0:
        if count == 1:
            dx, dy, dz = p[0] - v[0, 0], p[1] - v[0, 1], p[2] - v[0, 2]
            return bool(math.sqrt(dx * dx + dy * dy + dz * dz) <= radius)
        ex, ey, ez = v[1, 0] - v[0, 0], v[1, 1] - v[0, 1], v[1, 2] - v[0, 2]
        length2 = ex * ex + ey * ey + ez * ez
        t = ((p[0] - v[0, 0]) * ex + (p[1] - v[0, 1]) * ey + (p[2] - v[0, 2]) * ez) / length2
        t = min(max(t, 0.0), 1.0)
        dx = p[0] - v[0, 0] - t * ex
        dy = p[1] - v[0, 1] - t * ey
        dz = p[2] - v[0, 2] - t * ez
        return bool(math.sqrt(dx * dx + dy * dy + dz * dz) <= radius)
    if faces < 4:  # a mesh triangle: a surface holds no point
        return False
    for f in range(faces):
        c = corners[face_first[f]]
        s = (p[0] - v[c, 0]) * n[f, 0] + (p[1] - v[c, 1]) * n[f, 1] + (p[2] - v[c, 2]) * n[f, 2]
        if s > 0.0:
            return False
    return True


@njit(cache=True, inline="always")
def _interval(v: np.ndarray, count: int, ax: float, ay: float, az: float) -> tuple[float, float]:
    lo = math.inf
    hi = -math.inf
    for i in range(count):
        s = v[i, 0] * ax + v[i, 1] * ay + v[i, 2] * az
        lo = min(lo, s)
        hi = max(hi, s)
    return lo, hi


@njit(cache=True, inline="always")
def _box_interval(
    low: np.ndarray, high: np.ndarray, ax: float, ay: float, az: float
) -> tuple[float, float]:
    centre = 0.5 * ((low[0] + high[0]) * ax + (low[1] + high[1]) * ay + (low[2] + high[2]) * az)
    half = 0.5 * (
        abs(ax) * (high[0] - low[0]) + abs(ay) * (high[1] - low[1]) + abs(az) * (high[2] - low[2])
    )
    return centre - half, centre + half


@leaf
def box_meets_piece_3d(
    low: np.ndarray, high: np.ndarray, kind: int, v: np.ndarray, count: int, n: np.ndarray,
    faces: int, edges: np.ndarray, radius: float,
) -> bool:  # fmt: skip
    """Whether the box ``[low, high]`` (3,) meets a placed 3D piece (as
    :func:`point_in_piece_3d`; ``edges`` (e, 2+): each edge's two corners, vertex indices)."""
    if kind == 2:
        least = math.inf
        for cx in (low[0], high[0]):
            for cy in (low[1], high[1]):
                for cz in (low[2], high[2]):
                    s = (
                        (cx - v[0, 0]) * n[0, 0]
                        + (cy - v[0, 1]) * n[0, 1]
                        + (cz - v[0, 2]) * n[0, 2]
                    )
                    least = min(least, s)
        return bool(least <= 0.0)
    if kind == 0:
        if count == 1:
            return bool(_to_box(low, high, v[0, 0], v[0, 1], v[0, 2]) <= radius)
        return bool(_segment_to_box(low, high, v[0], v[1]) <= radius)
    for a in range(3):  # the box's axes
        lo, hi = _interval(
            v, count, 1.0 if a == 0 else 0.0, 1.0 if a == 1 else 0.0, 1.0 if a == 2 else 0.0
        )
        if hi < low[a] or lo > high[a]:
            return False
    for f in range(faces):
        ax, ay, az = n[f, 0], n[f, 1], n[f, 2]
        lo, hi = _interval(v, count, ax, ay, az)
        blo, bhi = _box_interval(low, high, ax, ay, az)
        if hi < blo or lo > bhi:
            return False
    for e in range(edges.shape[0]):
        i, j = edges[e, 0], edges[e, 1]
        dx, dy, dz = v[j, 0] - v[i, 0], v[j, 1] - v[i, 1], v[j, 2] - v[i, 2]
        for a in range(3):
            # the box's axis e_a cross the edge
            if a == 0:
                ax, ay, az = 0.0, -dz, dy
            elif a == 1:
                ax, ay, az = dz, 0.0, -dx
            else:
                ax, ay, az = -dy, dx, 0.0
            if ax * ax + ay * ay + az * az == 0.0:
                continue
            lo, hi = _interval(v, count, ax, ay, az)
            blo, bhi = _box_interval(low, high, ax, ay, az)
            if hi < blo or lo > bhi:
                return False
    return True
