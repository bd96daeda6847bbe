"""Rays against the pieces of rigid bodies, exactly: the closed forms of each shape kind.

A ray is an origin ``o`` and a unit direction ``d``; it hits a solid at the least distance
``t >= 0`` where it enters it, with the outward normal there. A ray that starts inside a solid
does not hit it (it looks outward, as a game's line of sight does).

- **A rounded convex polygon** (2D: circles, capsules, boxes, polygons, segments of
  chains): the Minkowski sum of a polygon and a disc of radius ``r``, whose boundary is the
  edges pushed out by ``r`` along their normals and arcs of radius ``r`` about the corners.
  Each pushed edge facing the ray is met at ``t = (a + r n - o) . n / (d . n)`` and kept when
  the point lies along the edge; each arc is met at the entering root of a quadratic and kept
  when its normal lies in the corner's cone (between its two edges' normals). A circle is a
  corner alone; a segment (two corners, no radius) has two edges, one a side.
- **A convex polytope** (3D boxes, hulls, a mesh's triangles): each face facing the ray is
  met in its plane and kept when the point lies inside the face (on the inner side of each of
  its edges). A triangle has its two faces, front and back.
- **A sphere and a capsule** (3D): the entering root of ``|o + t d - c|^2 = r^2`` (about the
  nearest point of the axis segment: the cylinder's quadratic with the axial part removed, and
  the end spheres beyond it).
- **A plane**: ``t = (p - o) . n / (d . n)``, from above only.

The quadratic's root is taken as ``c / (-b + sqrt(b^2 - c))`` (no cancellation), so a
distance agrees with the closed form to round-off.

References: Ericson, Real-Time Collision Detection, 5.3 (rays against spheres, capsules,
polyhedra); Box2D v3 ``b2RayCastPolygon`` and ``b2RayCastCapsule`` for the rounded polygon.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.jit import kernel_only

__all__ = ["ray_box", "ray_capsule", "ray_plane", "ray_polytope", "ray_rounded_polygon",
           "ray_sphere"]  # fmt: skip

INF = math.inf


@kernel_only(error_model="numpy")
def _enter(fx: float, fy: float, fz: float, d: np.ndarray, r: float) -> float:
    """Where the ray from ``f`` (the origin less the centre) along unit ``d`` enters a sphere
    of radius ``r`` about the centre: the least root ``t >= 0`` of ``|f + t d|^2 = r^2``, or
    inf when it misses or starts inside."""
    b = fx * d[0] + fy * d[1] + (fz * d[2] if d.shape[0] == 3 else 0.0)
    c = fx * fx + fy * fy + fz * fz - r * r
    if c <= 0.0 or b >= 0.0:
        return INF  # inside, or looking away
    disc = b * b - c
    if disc < 0.0:
        return INF
    t: float = c / (-b + math.sqrt(disc))
    return t


@njit(cache=True, error_model="numpy")
def ray_sphere(o: np.ndarray, d: np.ndarray, c: np.ndarray, r: float) -> float:
    """Distance along the ray (``o``, unit ``d``; 2D or 3D) to the sphere or circle of centre
    ``c`` and radius ``r`` (inf: no hit)."""
    fz = o[2] - c[2] if o.shape[0] == 3 else 0.0
    return _enter(o[0] - c[0], o[1] - c[1], fz, d, r)


@njit(cache=True, error_model="numpy")
def ray_rounded_polygon(
    o: np.ndarray, d: np.ndarray, v: np.ndarray, n: np.ndarray, count: int, r: float,
    out: np.ndarray,
) -> float:  # fmt: skip
    """Distance along the 2D ray (``o``, unit ``d``) to the polygon of ``count`` corners
    ``v`` (counter-clockwise; 1: a circle, 2: a segment) and edge normals ``n`` (``n[k]`` of
    the edge from corner k to k + 1) grown by ``r`` [m]; the normal where it enters goes to
    ``out`` (2,). inf: no hit."""
    best = INF
    if count >= 2:
        for k in range(count):
            nx, ny = n[k, 0], n[k, 1]
            facing = d[0] * nx + d[1] * ny
            if facing >= 0.0:
                continue
            ax, ay = v[k, 0] + r * nx, v[k, 1] + r * ny
            t = ((ax - o[0]) * nx + (ay - o[1]) * ny) / facing
            if t < 0.0 or t >= best:
                continue
            j = (k + 1) % count
            ex, ey = v[j, 0] - v[k, 0], v[j, 1] - v[k, 1]
            along = (o[0] + t * d[0] - ax) * ex + (o[1] + t * d[1] - ay) * ey
            if 0.0 <= along <= ex * ex + ey * ey:
                best = t
                out[0], out[1] = nx, ny
    if r > 0.0:
        for k in range(count):
            t = _enter(o[0] - v[k, 0], o[1] - v[k, 1], 0.0, d, r)
            if t >= best:
                continue
            mx = (o[0] + t * d[0] - v[k, 0]) / r
            my = (o[1] + t * d[1] - v[k, 1]) / r
            if count >= 2:
                # the corner's arc spans its two edges' normals: beyond its edges' ends
                p = (k - 1) % count
                j = (k + 1) % count
                behind = mx * (v[k, 0] - v[p, 0]) + my * (v[k, 1] - v[p, 1])
                ahead = mx * (v[j, 0] - v[k, 0]) + my * (v[j, 1] - v[k, 1])
                if behind < 0.0 or ahead > 0.0:
                    continue
            best = t
            out[0], out[1] = mx, my
    return best


@njit(cache=True, error_model="numpy")
def ray_polytope(
    o: np.ndarray, d: np.ndarray, v: np.ndarray, normals: np.ndarray, face_first: np.ndarray,
    face_size: np.ndarray, corners: np.ndarray, out: np.ndarray,
) -> float:  # fmt: skip
    """Distance along the 3D ray (``o``, unit ``d``) to the convex polytope of corners ``v``
    (k, 3), faces of outward ``normals`` (F, 3), face f's corners
    ``corners[face_first[f]: face_first[f] + face_size[f]]`` (counter-clockwise from outside,
    indices into ``v``); the normal where it enters goes to ``out`` (3,). inf: no hit."""
    best = INF
    for f in range(normals.shape[0]):
        nx, ny, nz = normals[f, 0], normals[f, 1], normals[f, 2]
        facing = d[0] * nx + d[1] * ny + d[2] * nz
        if facing >= 0.0:
            continue
        c0 = corners[face_first[f]]
        t = ((v[c0, 0] - o[0]) * nx + (v[c0, 1] - o[1]) * ny + (v[c0, 2] - o[2]) * nz) / facing
        if t < 0.0 or t >= best:
            continue
        px, py, pz = o[0] + t * d[0], o[1] + t * d[1], o[2] + t * d[2]
        inside = True
        size = face_size[f]
        for k in range(size):
            a = corners[face_first[f] + k]
            b = corners[face_first[f] + (k + 1) % size]
            ex, ey, ez = v[b, 0] - v[a, 0], v[b, 1] - v[a, 1], v[b, 2] - v[a, 2]
            qx, qy, qz = px - v[a, 0], py - v[a, 1], pz - v[a, 2]
            # (e x q) . n >= 0: the point is on the inner side of edge a -> b
            side = (ey * qz - ez * qy) * nx + (ez * qx - ex * qz) * ny + (ex * qy - ey * qx) * nz
            if side < 0.0:
                inside = False
                break
        if inside:
            best = t
            out[0], out[1], out[2] = nx, ny, nz
    return best


@njit(cache=True, error_model="numpy")
def ray_capsule(
    o: np.ndarray, d: np.ndarray, a: np.ndarray, b: np.ndarray, r: float, out: np.ndarray
) -> float:
    """Distance along the 3D ray (``o``, unit ``d``) to the capsule of axis ``a`` to ``b`` and
    radius ``r``; the normal where it enters goes to ``out`` (3,). inf: no hit."""
    ab = b - a
    length2 = ab[0] * ab[0] + ab[1] * ab[1] + ab[2] * ab[2]
    best = INF
    if length2 > 0.0:
        ao = o - a
        k_o = (ao[0] * ab[0] + ao[1] * ab[1] + ao[2] * ab[2]) / length2
        k_d = (d[0] * ab[0] + d[1] * ab[1] + d[2] * ab[2]) / length2
        # the cylinder: the ray and origin less their parts along the axis
        px, py, pz = ao[0] - k_o * ab[0], ao[1] - k_o * ab[1], ao[2] - k_o * ab[2]
        qx, qy, qz = d[0] - k_d * ab[0], d[1] - k_d * ab[1], d[2] - k_d * ab[2]
        qq = qx * qx + qy * qy + qz * qz
        pq = px * qx + py * qy + pz * qz
        c = px * px + py * py + pz * pz - r * r
        if qq > 0.0 and c > 0.0 and pq < 0.0:
            disc = pq * pq - qq * c
            if disc >= 0.0:
                t = c / (-pq + math.sqrt(disc))
                s = k_o + t * k_d
                if 0.0 <= s <= 1.0:
                    best = t
                    out[0] = (px + t * qx) / r
                    out[1] = (py + t * qy) / r
                    out[2] = (pz + t * qz) / r
    for end in range(2):
        c_ = a if end == 0 else b
        t = _enter(o[0] - c_[0], o[1] - c_[1], o[2] - c_[2], d, r)
        if t >= best:
            continue
        mx = (o[0] + t * d[0] - c_[0]) / r
        my = (o[1] + t * d[1] - c_[1]) / r
        mz = (o[2] + t * d[2] - c_[2]) / r
        # an end's cap is the half beyond the axis' end
        axial = mx * ab[0] + my * ab[1] + mz * ab[2]
        if (end == 0 and axial > 0.0) or (end == 1 and axial < 0.0):
            continue
        best = t
        out[0], out[1], out[2] = mx, my, mz
    return best


@njit(cache=True, error_model="numpy")
def ray_plane(o: np.ndarray, d: np.ndarray, p: np.ndarray, n: np.ndarray) -> float:
    """Distance along the 3D ray (``o``, unit ``d``) to the plane through ``p`` of outward
    normal ``n`` (the solid below it), met from above (inf: no hit)."""
    facing = d[0] * n[0] + d[1] * n[1] + d[2] * n[2]
    above = (o[0] - p[0]) * n[0] + (o[1] - p[1]) * n[1] + (o[2] - p[2]) * n[2]
    if facing >= 0.0 or above < 0.0:
        return INF
    t: float = above / -facing
    return t


@njit(cache=True, inline="always")
def ray_box(o: np.ndarray, inv: np.ndarray, box: np.ndarray, t_max: float) -> bool:
    """Whether the ray from ``o`` with inverse direction ``inv`` (1 / d, inf where d is 0)
    meets the box ``box`` (lower corner then upper, 2 d) within ``[0, t_max]`` (slabs)."""
    d = o.shape[0]
    lo, hi = 0.0, t_max
    for k in range(d):
        if inv[k] == INF or inv[k] == -INF:
            if o[k] < box[k] or o[k] > box[d + k]:
                return False
            continue
        t1 = (box[k] - o[k]) * inv[k]
        t2 = (box[d + k] - o[k]) * inv[k]
        if t1 > t2:
            t1, t2 = t2, t1
        lo = max(lo, t1)
        hi = min(hi, t2)
        if lo > hi:
            return False
    return True
