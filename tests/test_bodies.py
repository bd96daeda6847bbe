"""The body table (carom/bodies.py): orientations and spins are stored only when some body is
turned or spins, and read back the same either way, bit for bit."""

from __future__ import annotations

import numpy as np
import pytest

from carom.bodies import Bodies, all_still, all_unrotated, identity_orientations
from carom.shape_base import SHAPE_CODES
from carom.shapes import Box


def _spheres(dim: int, n: int, spins: np.ndarray | None = None) -> Bodies:
    bodies = Bodies(dim)
    w = np.zeros((n, 3)) if spins is None else spins
    bodies.append_spheres(np.zeros((n, dim)), np.zeros((n, dim)), w, np.ones(n), np.ones(n), 0.4, 0)
    return bodies


@pytest.mark.parametrize("dim", [2, 3])
def test_spheres_that_do_not_spin_store_no_orientations_or_spins(dim: int) -> None:
    bodies = _spheres(dim, 5)
    bodies.append_spheres(
        np.ones((2, dim)), np.ones((2, dim)), np.zeros((2, 3)), np.ones(2), np.ones(2), 0.4, 0
    )
    assert bodies.unrotated
    assert bodies.still
    # read as if stored: the identity (angle 0 in 2D, quaternion 1, 0, 0, 0 in 3D), no spin
    np.testing.assert_array_equal(bodies.orientation, identity_orientations(7, dim))
    np.testing.assert_array_equal(bodies.angular_velocity, np.zeros((7, 3)))
    assert not np.signbit(bodies.orientation).any()
    assert not np.signbit(bodies.angular_velocity).any()


def test_a_spin_stores_every_spin_and_gives_each_back() -> None:
    bodies = _spheres(3, 3)
    spins = np.array([[0.0, 0.0, 2.0], [0.0, -0.0, 0.0]])  # -0.0 is kept as it was
    bodies.append_spheres(np.zeros((2, 3)), np.zeros((2, 3)), spins, np.ones(2), np.ones(2), 0.4, 0)
    assert not bodies.still
    assert bodies.unrotated  # spheres are added unrotated
    np.testing.assert_array_equal(bodies.angular_velocity, np.vstack([np.zeros((3, 3)), spins]))
    assert np.signbit(bodies.angular_velocity[4, 1])
    assert not np.signbit(bodies.angular_velocity[:3]).any()
    bodies.append_spheres(
        np.zeros((1, 3)), np.zeros((1, 3)), np.zeros((1, 3)), np.ones(1), np.ones(1), 0.4, 0
    )
    assert bodies.angular_velocity.shape == (6, 3)
    np.testing.assert_array_equal(bodies.angular_velocity[5], np.zeros(3))


def test_a_turned_body_stores_every_orientation() -> None:
    # 2D: a box added turned after two unrotated spheres
    bodies = _spheres(2, 2)
    bodies.append_bodies(
        np.ones((1, 2)), np.zeros((1, 2)), np.array([0.3]), np.zeros(1), Box(0.5, 0.5).pieces(),
        SHAPE_CODES["box"], 1.0, 1.0, 0, 0,
    )  # fmt: skip
    assert not bodies.unrotated
    np.testing.assert_array_equal(bodies.orientation, [[0.0], [0.0], [0.3]])
    # 3D: the identity written back stores nothing; one turned sphere stores them all
    bodies = _spheres(3, 2)
    bodies.orientation = bodies.orientation
    assert bodies.unrotated
    turned = identity_orientations(2, 3)
    turned[1] = [0.0, 1.0, 0.0, 0.0]
    bodies.orientation = turned
    assert not bodies.unrotated
    np.testing.assert_array_equal(bodies.orientation, turned)


def test_a_state_set_back_to_rest_stores_nothing_again() -> None:
    # what an engine hands back (set_state): spins and turns if any, none stored if none
    bodies = _spheres(3, 4, spins=np.full((4, 3), 1.5))
    assert not bodies.still
    x, v = bodies.position, bodies.velocity
    bodies.set_state(x, v, identity_orientations(4, 3), np.zeros((4, 3)))
    assert bodies.still
    assert bodies.unrotated
    turned = identity_orientations(4, 3)
    turned[2] = [0.0, 0.0, 0.0, 1.0]
    bodies.set_state(x, v, turned, np.zeros((4, 3)))
    assert not bodies.unrotated
    np.testing.assert_array_equal(bodies.orientation, turned)


def test_identity_and_stillness_are_bit_for_bit() -> None:
    assert all_unrotated(identity_orientations(3, 3), 3)
    assert all_unrotated(identity_orientations(3, 2), 2)
    assert not all_unrotated(np.array([[-0.0]]), 2)
    assert not all_unrotated(np.array([[1.0, -0.0, 0.0, 0.0]]), 3)
    assert not all_unrotated(np.array([[-1.0, 0.0, 0.0, 0.0]]), 3)  # the same turn, other sign
    assert all_still(np.zeros((2, 3)))
    assert not all_still(np.array([[0.0, -0.0, 0.0]]))
    assert not all_still(np.array([[0.0, 5e-324, 0.0]]))
