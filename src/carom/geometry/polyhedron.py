"""A convex polyhedron's features for contact: its faces as polygons, its edges (NumPy; when
shapes are built, never per step).

A hull comes as triangles (qhull's facets); contact wants whole faces, so a box's side is one
quadrilateral that the other body's face is clipped against, not two triangles with a
diagonal. Coplanar triangles are merged (their normals within 1e-9 and their planes within
round-off of the solid's size) and each face's corners ordered counter-clockwise seen from
outside.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

__all__ = ["PolyhedronFeatures", "polyhedron_features", "triangle_features"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class PolyhedronFeatures:
    """Faces and edges of a convex polyhedron, in its own frame.

    Attributes
    ----------
    normals : (F, 3) float64
        Each face's unit outward normal.
    offsets : (F,) float64
        Each face's plane: ``normals[f] . x = offsets[f]`` [m].
    face_start, face_count : (F,) int64
        Face f's corners are ``corners[face_start[f] : face_start[f] + face_count[f]]``.
    corners : (C,) int64
        Vertex indices, face by face, counter-clockwise seen from outside.
    edges : (E, 4) int64
        Each edge once: its two vertex indices (the lower first) and the two faces that meet
        at it (their arc on the Gauss map prunes the separating-axis test,
        :func:`carom.geometry.manifold3d.contact_hull_hull`).
    """

    normals: FloatArray
    offsets: FloatArray
    face_start: IntArray
    face_count: IntArray
    corners: IntArray
    edges: IntArray


def polyhedron_features(vertices: FloatArray, triangles: IntArray) -> PolyhedronFeatures:
    """The faces (coplanar triangles merged) and edges of a convex polyhedron, in time and
    memory linear in its triangles (whole-array NumPy: 2e5 triangles in well under a second).

    Neighbouring triangles whose normals agree within 1e-9 and whose planes agree within
    1e-9 of the solid's size are one face; faces come in the order of their first triangle.

    Parameters
    ----------
    vertices : (V, 3) float64
        Corners [m].
    triangles : (T, 3) int64
        Outward counter-clockwise triangles of its closed surface.

    Raises
    ------
    ValueError
        The surface is open: an edge of a face is not shared by exactly two faces.
    """
    v = np.asarray(vertices, float)
    tri = np.asarray(triangles, np.int64)
    cross = np.cross(v[tri[:, 1]] - v[tri[:, 0]], v[tri[:, 2]] - v[tri[:, 0]])
    area2 = np.sqrt(_dot(cross, cross))
    normals = cross / area2[:, None]
    plane = _dot(normals, v[tri[:, 0]])
    size = float(np.max(np.abs(v - v.mean(axis=0))))
    plane_tol = 1e-9 * max(size, 1e-300)
    face_of = _coplanar_groups(tri, normals, plane, plane_tol)
    count = int(face_of.max()) + 1 if tri.shape[0] else 0
    nv = max(int(v.shape[0]), 1)
    # a face of one triangle (most of a hull of points on a sphere) is that triangle, already
    # counter-clockwise about its normal; faces of several go through the general path; both
    # give what the general path alone gives, bit for bit
    size_of = np.bincount(face_of, minlength=count)
    alone = size_of[face_of] == 1  # (T,): the triangle is a face by itself
    one = np.flatnonzero(size_of == 1)  # those faces, in order
    many = np.flatnonzero(size_of > 1)
    corner_count = np.full(count, 3, np.int64)
    n = np.zeros((count, 3))
    offsets = np.zeros(count)
    rings = _triangle_faces(v, tri[alone], normals[alone], area2[alone])
    n[one], offsets[one] = rings[3], rings[4]
    if many.size:
        compact = np.cumsum(size_of > 1) - 1  # a merged face's number among them
        merged = _merged_faces(
            v, tri[~alone], normals[~alone], area2[~alone], compact[face_of[~alone]], many.size
        )
        corner_count[many] = merged[1]
        n[many], offsets[many] = merged[3], merged[4]
    start = np.concatenate([[0], np.cumsum(corner_count)[:-1]]).astype(np.int64)
    corners = np.empty(int(corner_count.sum()), np.int64)
    corners[(start[one][:, None] + np.arange(3)).ravel()] = rings[2]
    if many.size:
        first, sizes, ring = merged[0], merged[1], merged[2]
        at = np.repeat(start[many] - first, sizes) + np.arange(ring.size)
        corners[at] = ring
    face = np.repeat(np.arange(count), corner_count)
    return _with_edges(n, offsets, start, corner_count, corners, face, nv)


def _merged_faces(
    v: FloatArray, tri: IntArray, normals: FloatArray, area2: FloatArray, face_of: IntArray,
    count: int,
) -> tuple[IntArray, IntArray, IntArray, FloatArray, FloatArray]:  # fmt: skip
    """Faces of several triangles (``face_of`` each triangle's, ``count`` faces): their ring
    starts, sizes, rings (counter-clockwise about the normal from the lowest-numbered
    corner), normals (averaged over the triangles, weighted by area) and plane offsets."""
    nv = max(int(v.shape[0]), 1)
    n = np.zeros((count, 3))
    np.add.at(n, face_of, normals * area2[:, None])
    n /= np.sqrt(_dot(n, n))[:, None]
    # each face's corners: the distinct vertices of its triangles, face by face
    key = np.sort(np.repeat(face_of, 3) * nv + tri.ravel())
    key = key[np.concatenate([[True], key[1:] != key[:-1]])]
    face, ids = key // nv, key % nv
    corner_count = np.bincount(face, minlength=count).astype(np.int64)
    start = np.concatenate([[0], np.cumsum(corner_count)[:-1]]).astype(np.int64)
    centre = np.add.reduceat(v[ids], start, axis=0) / corner_count[:, None]
    offsets = np.add.reduceat(_dot(v[ids], n[face]), start) / corner_count
    # corners counter-clockwise about the normal, from its lowest-numbered corner: by angle in
    # the face's plane, in [0, 2 pi) from that corner (its own angle 0 exactly, so that no
    # rounding of a zero, +0 or -0, turns the ring)
    u = v[ids[start]] - centre
    u -= _dot(u, n)[:, None] * n
    u /= np.sqrt(_dot(u, u))[:, None]
    w = np.cross(n, u)
    rel = v[ids] - centre[face]
    angle = np.mod(np.arctan2(_dot(rel, w[face]), _dot(rel, u[face])), 2.0 * np.pi)
    angle[start] = 0.0
    corners = ids[np.lexsort((angle, face))]
    return start, corner_count, corners, n, offsets


def _triangle_faces(
    v: FloatArray, tri: IntArray, normals: FloatArray, area2: FloatArray
) -> tuple[IntArray, IntArray, IntArray, FloatArray, FloatArray]:
    """Faces that are one triangle each: their ring starts, sizes (3), rings from the
    lowest-numbered corner, normals and plane offsets, computed as :func:`_merged_faces`
    computes them (the same bits)."""
    t = tri.shape[0]
    n = normals * area2[:, None]
    n /= np.sqrt(_dot(n, n))[:, None]
    ordered = np.sort(tri, axis=1).ravel()  # (the general path sums a face's corners by number)
    start = 3 * np.arange(t, dtype=np.int64)
    count = np.full(t, 3, np.int64)
    offsets = np.add.reduceat(_dot(v[ordered], np.repeat(n, 3, axis=0)), start) / count
    first = np.argmin(tri, axis=1)
    ring = tri[np.arange(t)[:, None], (first[:, None] + np.arange(3)) % 3]
    return start, count, ring.ravel(), n, offsets


def _with_edges(
    n: FloatArray, offsets: FloatArray, start: IntArray, corner_count: IntArray,
    corners: IntArray, face: IntArray, nv: int,
) -> PolyhedronFeatures:  # fmt: skip
    """The features with their edges: each side of a face's ring (``corners``, each one's
    ``face``), which must be shared by exactly two faces."""
    following = np.arange(corners.size) + 1
    last = start + corner_count - 1
    following[last] = start
    a, b = corners, corners[following]
    low, high = np.minimum(a, b), np.maximum(a, b)
    # by (low, high), then face: one key, sorted stably (the sides come in face order)
    order = np.argsort(low * nv + high, kind="stable")
    low, high, side_face = low[order], high[order], face[order]
    first = np.flatnonzero(
        np.concatenate([[True], (low[1:] != low[:-1]) | (high[1:] != high[:-1])])
    )
    sides = np.diff(np.concatenate([first, [low.size]]))
    if np.any(sides != 2):
        raise ValueError("a convex polyhedron's every edge joins two faces; this surface is open")
    edges = np.stack([low[first], high[first], side_face[first], side_face[first + 1]], axis=1)
    return PolyhedronFeatures(
        n, offsets, start, corner_count, corners.astype(np.int64), edges.astype(np.int64)
    )


def _dot(a: FloatArray, b: FloatArray) -> FloatArray:
    """Row by row dot products of (n, 3) arrays, summed in one fixed order (no BLAS: its
    kernels sum in an order of their own, which differs between machines)."""
    return a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1] + a[:, 2] * b[:, 2]


def _coplanar_groups(
    tri: IntArray, normals: FloatArray, plane: FloatArray, plane_tol: float
) -> IntArray:
    """Each triangle's face (T,): neighbouring triangles (sharing an edge) on one plane, their
    normals within 1e-9 and their planes within ``plane_tol``, are one face; the faces are
    numbered in the order of their first triangle."""
    t = tri.shape[0]
    a = tri.ravel()
    b = tri[:, [1, 2, 0]].ravel()
    owner = np.repeat(np.arange(t), 3)
    low, high = np.minimum(a, b), np.maximum(a, b)
    # by (low, high), then owner: one key, sorted stably (the edges come in owner order)
    nv = int(tri.max()) + 1 if t else 1
    order = np.argsort(low * nv + high, kind="stable")
    low, high, owner = low[order], high[order], owner[order]
    same = (low[1:] == low[:-1]) & (high[1:] == high[:-1])
    i, j = owner[:-1][same], owner[1:][same]
    flat = (_dot(normals[i], normals[j]) > 1.0 - 1e-9) & (np.abs(plane[i] - plane[j]) <= plane_tol)
    i, j = i[flat], j[flat]
    # connected components by pointer jumping: each triangle ends labelled with the lowest
    # triangle of its face
    label = np.arange(t)
    while True:
        joined = np.minimum(label[i], label[j])
        before = label.copy()
        np.minimum.at(label, i, joined)
        np.minimum.at(label, j, joined)
        label = label[label]
        if np.array_equal(label, before):
            break
    first = label == np.arange(t)  # the lowest triangle of each face, in order
    return (np.cumsum(first) - 1)[label].astype(np.int64)


def triangle_features(
    corners: FloatArray,
) -> tuple[FloatArray, FloatArray, IntArray, IntArray, IntArray, IntArray]:
    """A mesh triangle as a flat convex polytope, in the placed form the contact kernels take
    (:func:`carom.geometry.manifold3d.contact_hull_hull` and the like, as body B): corners
    (3, 3) [m]; two faces, the front (counter-clockwise) and the back; three edges, each
    joining the two faces.

    Returns
    -------
    vertices, normals, face_start, face_count, corners, edges
        (3, 3), (2, 3), (2,), (2,), (6,), (3, 4).
    """
    v = np.asarray(corners, float)
    n = np.cross(v[1] - v[0], v[2] - v[0])
    n /= np.linalg.norm(n)
    return (
        v.copy(),
        np.array([n, -n]),
        np.array([0, 3], np.int64),
        np.array([3, 3], np.int64),
        np.array([0, 1, 2, 0, 2, 1], np.int64),
        np.array([[0, 1, 0, 1], [1, 2, 0, 1], [0, 2, 0, 1]], np.int64),
    )
