"""carom.shapes3d: the 3D shapes' checks and messages (the mass formulas are in
tests/geometry/test_mass3d.py)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from carom.errors import CaromError
from carom.shapes3d import Box, Capsule, Compound, Hull, Plane, Sphere, rotation_matrix

pytest.importorskip("scipy")


@pytest.mark.parametrize(
    ("build", "message"),
    [
        (lambda: Sphere(0.0), "Sphere radius must be positive"),
        (lambda: Sphere(float("nan")), "Sphere radius must be positive"),
        (lambda: Capsule(-1.0, 0.1), "Capsule length must be positive"),
        (lambda: Box([1.0, 0.0, 1.0]), "Box size along y must be positive"),
        (lambda: Box([1.0, 1.0]), "Box size must be 3 finite numbers"),
        (lambda: Hull([[0, 0, 0], [1, 0, 0], [0, 1, 0]]), "at least 4 points"),
        (lambda: Hull([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0]]), "flat"),
        (lambda: Hull([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, math.inf]]), "point 3"),
        (lambda: Plane([0, 0, 0]), "no direction"),
        (lambda: Compound([]), "non-empty list"),
        (lambda: Compound([(Box([1, 1, 1]), [0, 0])]), "offset must be 3 finite numbers"),
        (lambda: Compound([Plane()]), "Plane is unbounded"),
        (lambda: Compound([(Box([1, 1, 1]), [0, 0, 0], [0, 0, 0, 0])]), r"quaternion \(0, 0"),
        (lambda: rotation_matrix(np.diag([1.0, 1.0, -1.0])), "must be a rotation"),
        (lambda: Box([1, 1, 1]).mass_properties(), "give density"),
        (lambda: Box([1, 1, 1]).mass_properties(1.0, mass=1.0), "give density"),
        (lambda: Box([1, 1, 1]).mass_properties(-1.0), "density must be positive"),
        (lambda: Plane().mass_properties(mass=1.0), "no mass"),
    ],
)
def test_bad_shapes_are_refused_with_a_message_that_names_the_fault(
    build: object, message: str
) -> None:
    with pytest.raises(CaromError, match=message):
        build()  # type: ignore[operator]


def test_a_hull_keeps_only_its_corners_with_outward_faces() -> None:
    cube = Box([2.0, 2.0, 2.0]).corners()
    inside = np.array([[0.0, 0.0, 0.0], [0.5, -0.2, 0.1]])
    hull = Hull(np.vstack([cube, inside]))
    assert hull.vertices.shape == (8, 3)
    assert hull.triangles.shape == (12, 3)
    assert hull.volume == pytest.approx(8.0, rel=1e-14)  # positive: the faces turn outward


def test_quaternions_and_matrices_give_the_same_rotation() -> None:
    # a third of a turn about (1, 1, 1) cycles the axes: x -> y -> z -> x
    half = math.pi / 3
    q = [math.cos(half), *(math.sin(half) * np.ones(3) / math.sqrt(3))]
    r = rotation_matrix(q)
    assert np.allclose(r, [[0, 0, 1], [1, 0, 0], [0, 1, 0]], atol=1e-15)
    assert np.array_equal(rotation_matrix(r), r)
    assert np.allclose(rotation_matrix(2.0 * np.array(q)), r, atol=1e-15)  # normalised


def test_a_plane_normalises_its_normal() -> None:
    plane = Plane([0.0, 3.0, 4.0], 1.5)
    assert np.allclose(plane.normal, [0.0, 0.6, 0.8])
