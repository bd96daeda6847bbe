"""carom.geometry.polyhedron: a hull's triangles merged into faces, and its edges."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from carom.geometry.polyhedron import polyhedron_features
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
    f = polyhedron_features(hull.vertices, hull.triangles)
    assert hull.vertices.shape[0] - f.edges.shape[0] + f.normals.shape[0] == 2
    size = float(np.max(np.abs(hull.vertices)))
    for face in range(f.normals.shape[0]):
        ring = hull.vertices[
            f.corners[f.face_start[face] : f.face_start[face] + f.face_count[face]]
        ]
        assert np.max(np.abs(ring @ f.normals[face] - f.offsets[face])) <= 1e-9 * size
        turn = np.cross(np.roll(ring, -1, axis=0) - ring, np.roll(ring, -2, axis=0) - ring)
        assert np.all(turn @ f.normals[face] > 0.0)
        # outward: every corner of the hull on or below the face's plane
        assert np.all(hull.vertices @ f.normals[face] <= f.offsets[face] + 1e-9 * size)
    # each edge joins two different faces, and it is a side of each (consecutive corners)
    for a, b, f0, f1 in f.edges.tolist():
        assert f0 != f1
        for face in (f0, f1):
            ring = f.corners[f.face_start[face] : f.face_start[face] + f.face_count[face]]
            sides = {frozenset(pair) for pair in zip(ring, np.roll(ring, -1), strict=True)}
            assert frozenset((a, b)) in sides
