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
    """The faces (coplanar triangles merged) and edges of a convex polyhedron.

    Parameters
    ----------
    vertices : (V, 3) float64
        Corners [m].
    triangles : (T, 3) int64
        Outward counter-clockwise triangles of its closed surface.
    """
    v = np.asarray(vertices, float)
    tri = np.asarray(triangles, np.int64)
    cross = np.cross(v[tri[:, 1]] - v[tri[:, 0]], v[tri[:, 2]] - v[tri[:, 0]])
    normals = cross / np.linalg.norm(cross, axis=1)[:, None]
    size = float(np.max(np.abs(v - v.mean(axis=0))))
    plane_tol = 1e-9 * max(size, 1e-300)
    # group triangles by plane (greedy, in order: the same faces every run)
    face_of = np.full(tri.shape[0], -1, np.int64)
    planes: list[tuple[FloatArray, float]] = []
    for t in range(tri.shape[0]):
        n = normals[t]
        d = float(n @ v[tri[t, 0]])
        for f, (m, e) in enumerate(planes):
            if float(n @ m) > 1.0 - 1e-9 and abs(d - e) <= plane_tol:
                face_of[t] = f
                break
        else:
            face_of[t] = len(planes)
            planes.append((n, d))
    face_normals = np.zeros((len(planes), 3))
    offsets = np.zeros(len(planes))
    starts: list[int] = []
    counts: list[int] = []
    corners: list[int] = []
    for f in range(len(planes)):
        members = tri[face_of == f]
        # the face's normal and plane, averaged over its triangles (weighted by area)
        weights = np.linalg.norm(cross[face_of == f], axis=1)
        n = (normals[face_of == f] * weights[:, None]).sum(axis=0)
        n /= np.linalg.norm(n)
        ids = np.unique(members)
        centre = v[ids].mean(axis=0)
        # corners counter-clockwise about n: angle in the face's plane
        u = v[ids[0]] - centre
        u -= (u @ n) * n
        u /= np.linalg.norm(u)
        w = np.cross(n, u)
        rel = v[ids] - centre
        order = np.argsort(np.arctan2(rel @ w, rel @ u), kind="stable")
        face_normals[f] = n
        offsets[f] = float(np.mean(v[ids] @ n))
        starts.append(len(corners))
        counts.append(ids.size)
        corners.extend(int(i) for i in ids[order])
    faces_at: dict[tuple[int, int], list[int]] = {}
    for f in range(len(planes)):
        ring = corners[starts[f] : starts[f] + counts[f]]
        for k in range(len(ring)):
            a, b = ring[k], ring[(k + 1) % len(ring)]
            faces_at.setdefault((min(a, b), max(a, b)), []).append(f)
    if any(len(meeting) != 2 for meeting in faces_at.values()):
        raise ValueError("a convex polyhedron's every edge joins two faces; this surface is open")
    edges = [(a, b, *faces_at[a, b]) for a, b in sorted(faces_at)]
    return PolyhedronFeatures(
        face_normals,
        offsets,
        np.array(starts, np.int64),
        np.array(counts, np.int64),
        np.array(corners, np.int64),
        np.array(edges, np.int64).reshape(-1, 4),
    )


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
