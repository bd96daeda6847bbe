"""carom.geometry.polyhedron: a hull's triangles merged into faces, and its edges."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from carom.geometry.polyhedron import PolyhedronFeatures, polyhedron_features
from carom.shapes3d import Box, Hull

pytest.importorskip("scipy")


def test_a_box_has_six_square_faces_and_twelve_edges() -> None:
    piece = Box([1.0, 2.0, 3.0]).pieces()[0]
    features = polyhedron_features(piece.vertices, piece.triangles)
    assert features.normals.shape == (6, 3)
    assert list(features.face_count) == [4] * 6
    assert features.edges.shape == (12, 4)  # two corners, then the two faces that meet
    # each face's plane is half the box's size out along its normal
    half = np.abs(features.normals) @ np.array([0.5, 1.0, 1.5])
    assert features.offsets == pytest.approx(half, abs=1e-15)


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), count=st.integers(4, 40))
def test_faces_of_random_hulls_are_planar_counterclockwise_and_close_a_sphere(
    seed: int, count: int
) -> None:
    # Euler: V - E + F = 2 for a convex polyhedron; each face's corners on its plane (to
    # round-off of the hull's size) and turning counter-clockwise about its outward normal
    rng = np.random.default_rng(seed)
    hull = Hull(rng.normal(size=(count, 3)))
    _check_features(hull.vertices, polyhedron_features(hull.vertices, hull.triangles))


def _check_features(vertices: np.ndarray, f: PolyhedronFeatures) -> None:
    """Euler's V - E + F = 2; each face's corners on its plane and turning counter-clockwise
    about its outward normal; each edge a side of the two faces it joins."""
    assert vertices.shape[0] - f.edges.shape[0] + f.normals.shape[0] == 2
    size = float(np.max(np.abs(vertices)))
    for face in range(f.normals.shape[0]):
        ring = vertices[f.corners[f.face_start[face] : f.face_start[face] + f.face_count[face]]]
        assert np.max(np.abs(ring @ f.normals[face] - f.offsets[face])) <= 1e-9 * size
        turn = np.cross(np.roll(ring, -1, axis=0) - ring, np.roll(ring, -2, axis=0) - ring)
        assert np.all(turn @ f.normals[face] > 0.0)
        # outward: every corner of the hull on or below the face's plane
        assert np.all(vertices @ f.normals[face] <= f.offsets[face] + 1e-9 * size)
    # each edge joins two different faces, and it is a side of each (consecutive corners)
    for a, b, f0, f1 in f.edges.tolist():
        assert f0 != f1
        for face in (f0, f1):
            ring = f.corners[f.face_start[face] : f.face_start[face] + f.face_count[face]]
            sides = {frozenset(pair) for pair in zip(ring, np.roll(ring, -1), strict=True)}
            assert frozenset((a, b)) in sides


def test_faces_of_one_triangle_and_merged_faces_together() -> None:
    # a box's corners under a cap of points on a sphere: the box's bottom stays one face of
    # two triangles (the merged path), the cap's faces are one triangle each (laid out in
    # bulk); together they must be what each gives alone: a closed, outward polyhedron
    rng = np.random.default_rng(7)
    box = np.array([[x, y, z] for x in (-1, 1) for y in (-1, 1) for z in (-1, 1)], float)
    cap = rng.normal(size=(300, 3))
    cap /= np.linalg.norm(cap, axis=1)[:, None]
    hull = Hull(np.concatenate([box, 1.6 * cap[cap[:, 2] > 0.3]]))
    f = polyhedron_features(hull.vertices, hull.triangles)
    assert np.any(f.face_count > 3)
    assert np.any(f.face_count == 3)
    _check_features(hull.vertices, f)


def test_a_face_ring_starts_at_its_lowest_corner_however_the_corners_are_numbered() -> None:
    # the same box, its corners numbered in another order: each face's ring starts at its
    # lowest-numbered corner and turns counter-clockwise, so the faces are the same polygons
    # (no rounding of a zero angle, +0 or -0, may turn a ring)
    piece = Box([1.0, 2.0, 3.0]).pieces()[0]
    rng = np.random.default_rng(11)
    for _ in range(5):
        perm = rng.permutation(8)
        renumber = np.argsort(perm)  # old corner index -> new
        f = polyhedron_features(piece.vertices[perm], renumber[piece.triangles])
        for face in range(6):
            ring = f.corners[f.face_start[face] : f.face_start[face] + f.face_count[face]]
            assert ring[0] == ring.min()
            corners = piece.vertices[perm][ring]
            turn = np.cross(corners[1] - corners[0], corners[2] - corners[1])
            assert turn @ f.normals[face] > 0.0


def test_faces_of_a_hull_of_thousands_of_points_close_a_sphere() -> None:
    # 20,000 points on a sphere: about 40,000 triangles, each its own face (whole-array
    # grouping, no loop per triangle); Euler's V - E + F = 2, every edge joins two faces
    rng = np.random.default_rng(5)
    points = rng.normal(size=(20_000, 3))
    hull = Hull(points / np.linalg.norm(points, axis=1)[:, None])
    f = polyhedron_features(hull.vertices, hull.triangles)
    assert hull.vertices.shape[0] - f.edges.shape[0] + f.normals.shape[0] == 2
    assert f.normals.shape[0] > 39_000
    assert np.all(f.edges[:, 2] != f.edges[:, 3])
    # every face's corners on its plane to round-off
    ring_plane = np.repeat(f.offsets, f.face_count)
    ring_normal = np.repeat(f.normals, f.face_count, axis=0)
    along = np.einsum("ij,ij->i", hull.vertices[f.corners], ring_normal)
    assert np.max(np.abs(along - ring_plane)) <= 1e-12


def test_an_open_surface_is_refused() -> None:
    # a box without its top: the top rim's edges have one face each
    piece = Box([1.0, 1.0, 1.0]).pieces()[0]
    top = piece.vertices[piece.triangles].mean(axis=1)[:, 2] > 0.49
    with pytest.raises(ValueError, match="surface is open"):
        polyhedron_features(piece.vertices, piece.triangles[~top])
