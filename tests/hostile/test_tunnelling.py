"""No tunnelling in the rigid engines at any finite speed (issue 45, item 1).

A 5 cm ball in a 1 m walled box with no gravity, e = 1, launched at 10^3, 10^6 and 10^100 m/s,
in 2D and 3D: it stays inside and keeps its speed. At 10^3 m/s (about 25 wall impacts a step
at 60 Hz) every impact is solved exactly within the step, so the ball's path is the mirror
billiard's closed form; faster, an island reaches its cap of impacts a step and ends the step
at its last impact, and the solver's continuous collision keeps the ball from running through a
wall it was touching: inside to the linear slop, speed kept to round-off. Two bullets fired at
each other bounce apart.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.engines.stepped.settings import RigidSettings
from carom.shapes import Circle
from carom.shapes3d import Sphere

RADIUS = 0.05
SIDE = 1.0
#: the rigid engines' linear slop [m] (RigidSettings): the solver lets contacts sink this far,
#: and continuous collision puts a body back where it was no deeper than one slop more
SLOP = RigidSettings().linear_slop


def _ball_in_a_box(dim: int, speed: float) -> carom.World:
    elastic = carom.Material(1.0)
    world = carom.World(dim, [SIDE] * dim, gravity=[0.0] * dim, walls=elastic)
    direction = np.array([1.0, 0.37, 0.21][:dim])
    shape = Circle(RADIUS) if dim == 2 else Sphere(RADIUS)
    world.add_body(shape, [0.5] * dim, velocity=speed * direction, mass=1.0, material=elastic)
    return world


def _fold(s: np.ndarray) -> np.ndarray:
    """The mirror billiard's closed form: a point moving freely on the line, folded into
    [RADIUS, SIDE - RADIUS] by reflections at both ends (each wall impact with e = 1)."""
    span = SIDE - 2.0 * RADIUS
    u = np.mod(s - RADIUS, 2.0 * span)
    return RADIUS + np.where(u <= span, u, 2.0 * span - u)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("speed", [1e3, 1e6, 1e100])
def test_a_ball_in_a_walled_box_stays_inside_at_any_speed(dim: int, speed: float) -> None:
    world = _ball_in_a_box(dim, speed)
    times = np.linspace(0.0, 1.0, 31)
    rec = world.record(times)
    assert world.reached
    x = rec.positions[:, 0]
    # inside: the centre within RADIUS of the walls, to the slop the solver allows (twice:
    # sunk one slop at most, and put back no deeper than where a step began)
    assert np.all(x >= RADIUS - 2 * SLOP)
    assert np.all(x <= SIDE - RADIUS + 2 * SLOP)
    v = rec.velocities[:, 0]
    speeds = np.linalg.norm(v, axis=1)
    start = speeds[0]
    # every impact with e = 1 on a wall flips one component: |v| kept to round-off (a few
    # ulps an impact, hundreds of impacts a step at most)
    assert np.max(np.abs(speeds / start - 1.0)) < 1e-12
    assert np.all(np.isfinite(x))


@pytest.mark.parametrize("dim", [2, 3])
def test_at_a_thousand_metres_a_second_every_impact_is_exact(dim: int) -> None:
    # 1000 m/s at 60 Hz: 16.7 m a step, about 25 wall impacts in each; all are solved at
    # their times of impact, so each coordinate follows the folded free flight
    world = _ball_in_a_box(dim, 1e3)
    times = np.linspace(0.0, 1.0, 11)
    rec = world.record(times)
    v0 = 1e3 * np.array([1.0, 0.37, 0.21][:dim])
    expected = _fold(0.5 + np.outer(rec.times, v0))
    # the times of impact are found to 1e-9 of the reach (conservative advancement), over
    # about 1500 impacts a second along x: the path stays within a micrometre
    np.testing.assert_allclose(rec.positions[:, 0], expected, atol=1e-6)
    assert world.counters().wall_collisions > 1000


@pytest.mark.parametrize("dim", [2, 3])
def test_two_bullets_bounce_apart(dim: int) -> None:
    # two balls fired at each other at 1e4 m/s, 0.4 m apart: they meet within the first step
    # (each flies 167 m in it) and must come back off each other, never pass
    elastic = carom.Material(1.0)
    world = carom.World(dim, [4.0] * dim, gravity=[0.0] * dim, walls=elastic)
    shape = Circle(RADIUS) if dim == 2 else Sphere(RADIUS)
    at = [2.0] * dim
    for x, u in ((1.8, 1e4), (2.2, -1e4)):
        position = list(at)
        position[0] = x
        velocity = [0.0] * dim
        velocity[0] = u
        world.add_body(shape, position, velocity=velocity, mass=1.0, material=elastic)
    rec = world.record(np.linspace(0.0, 0.5, 31))
    left, right = rec.positions[:, 0, 0], rec.positions[:, 1, 0]
    # they keep their order along x at every frame (passing through would swap them)
    assert np.all(left < right)
    # momentum along x is zero throughout; |v| of each kept (equal masses, e = 1)
    np.testing.assert_allclose(rec.velocities[:, 0, 0] + rec.velocities[:, 1, 0], 0.0, atol=1e-9)
    np.testing.assert_allclose(np.abs(rec.velocities[:, :, 0]), 1e4, rtol=1e-12)
    assert math.isfinite(float(np.max(np.abs(rec.positions))))
