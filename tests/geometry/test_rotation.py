"""carom.geometry.rotation.turn against the closed forms of a rotation at constant spin, and
the event-driven engine's orientations: exact through rough collisions that change the spin."""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.geometry.rotation import turn

EPS = float(np.finfo(np.float64).eps)


def test_a_2d_angle_advances_by_spin_times_time() -> None:
    orient = np.array([[0.3, 0.0, 0.0, 0.0]])
    turn(orient, 0, 0.0, 0.0, 2.5, 0.4, 2)
    assert orient[0, 0] == 0.3 + 2.5 * 0.4  # one multiplication and one addition, as written


def test_a_quaternion_turns_by_the_angle_about_the_spin_axis() -> None:
    # from the identity, spin w for dt: q = (cos(|w| dt / 2), sin(|w| dt / 2) w / |w|)
    w = np.array([0.3, -1.2, 0.5])
    dt = 0.7
    orient = np.array([[1.0, 0.0, 0.0, 0.0]])
    turn(orient, 0, *w, dt, 3)
    speed = float(np.linalg.norm(w))
    expected = [math.cos(speed * dt / 2), *(math.sin(speed * dt / 2) * w / speed)]
    # libm's cos and sin are within an ulp, the product with the identity adds one rounding
    np.testing.assert_allclose(orient[0], expected, rtol=0, atol=4 * EPS)


def test_turns_about_one_axis_add_up() -> None:
    # two turns at the same spin make one turn for the summed time (rotations about one axis
    # commute); a full turn of 2 pi is -1 times the start (the quaternion's double cover)
    w = np.array([0.0, 0.0, 2.0])
    orient = np.array([[1.0, 0.0, 0.0, 0.0]])
    for _ in range(4):
        turn(orient, 0, *w, math.pi / 4, 3)  # four quarter-turns of pi/2 each
    # four turns, each a few roundings (as above), and pi / 4 itself rounded: 16 eps
    np.testing.assert_allclose(orient[0], [-1.0, 0.0, 0.0, 0.0], rtol=0, atol=16 * EPS)


def test_orientation_through_a_spin_changing_collision_2d() -> None:
    # a rough disk (beta = 1) hits a fixed peg off-centre: its spin jumps at the collision
    # time t1; before, the angle grows at w0, after at w1. The engine turns it to t1 at the
    # old spin before changing it, so the angle at T is w0 t1 + w1 (T - t1)
    world = carom.World(2, [4.0, 4.0])
    rough = carom.Material(1.0, beta=1.0)
    world.add_static_spheres([[2.0, 2.0]], radius=0.5, material=rough)
    world.add_spheres(
        [[1.0, 2.3]], [[1.0, 0.0]], radius=0.25, material=rough, angular_velocities=[0.7]
    )
    world.run(until=1.5, log=True)
    (hit,) = world.collisions
    t1 = float(hit["time"])
    w1 = float(world.angular_velocities[1, 2])
    assert w1 != 0.7  # the spin did change
    # two products and a sum on angles under 2 rad, each rounded by an ulp (4.4e-16): 8 eps
    assert world.orientations[1] == pytest.approx(0.7 * t1 + w1 * (1.5 - t1), rel=0, abs=8 * EPS)
    assert world.orientations[0] == 0.0  # the peg never turns


def test_orientations_survive_a_checkpoint(tmp_path) -> None:  # type: ignore[no-untyped-def]
    world = carom.World(3, [1.0, 1.0, 1.0])
    rng = np.random.default_rng(1)
    world.add_spheres(
        [[0.3, 0.5, 0.5], [0.7, 0.5, 0.52]],
        [[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]],
        radius=0.1,
        material=carom.Material(0.9, beta=0.5),
        angular_velocities=rng.normal(size=(2, 3)),
    )
    world.run(until=0.5)
    world.save(tmp_path / "w.npz")
    loaded = carom.World.load(tmp_path / "w.npz")
    world.run(until=1.0)
    loaded.run(until=1.0)
    assert loaded.orientations.tobytes() == world.orientations.tobytes()
    # every turn is a product with a unit quaternion, which keeps the norm to an ulp or so
    np.testing.assert_allclose(np.linalg.norm(world.orientations, axis=1), 1.0, atol=4 * EPS)
