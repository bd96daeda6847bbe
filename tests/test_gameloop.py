"""Stepping a world by hand (issue 43, item 1): ``World.step(dt=None)``, ``World.steps``.

Stepping by hand and ``run`` take the same engine steps, so they give the same bits at the
same times; another ``dt`` is one step of that length in the rigid engines (free flight in it
exact: the parabola to round-off) and exactly ``dt`` of events in the event-driven engine.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.errors import CaromError

G = 9.81


def _boxes(dim: int) -> carom.World:
    """Three boxes dropped on a floor, turned, so that they hit, slide and come to rest."""
    if dim == 2:
        from carom.shapes import Box

        world = carom.World(2, [10.0, 10.0], gravity=[0.0, -G], boundary="open")
        world.add_body(Box(10.0, 1.0), [5.0, -0.5], kind="static")
        for k in range(3):
            world.add_body(Box(1.0, 0.5), [4.0 + k, 1.0 + 0.8 * k], angle=0.3 * k)
        return world
    from carom.shapes3d import Box as Box3D

    world = carom.World(3, [10.0] * 3, gravity=[0.0, 0.0, -G], boundary="open")
    world.add_body(Box3D([10.0, 10.0, 1.0]), [5.0, 5.0, -0.5], kind="static")
    for k in range(3):
        half = 0.15 * k
        turn = [math.cos(half), math.sin(half), 0.0, 0.0]
        world.add_body(Box3D([1.0, 0.5, 0.3]), [4.0 + k, 5.0, 1.0 + 0.8 * k], orientation=turn)
    return world


@pytest.mark.parametrize("dim", [2, 3])
def test_stepping_by_hand_gives_the_bits_of_a_run(dim: int) -> None:
    by_hand, run = _boxes(dim), _boxes(dim)
    for _ in range(90):
        by_hand.step()
    run.run(until=90 / 60)
    assert by_hand.steps == run.steps == 90
    assert by_hand.time == run.time
    for read in ("positions", "velocities", "orientations", "angular_velocities"):
        np.testing.assert_array_equal(getattr(by_hand, read), getattr(run, read), err_msg=read)
    # and on from there, mixed: a run after steps by hand is the same run
    by_hand.run(until=2.0)
    run.run(until=2.0)
    np.testing.assert_array_equal(by_hand.positions, run.positions)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_step_of_another_length_is_one_step_of_it(dim: int) -> None:
    world = _boxes(dim)
    start = world.positions.copy()
    world.step(0.01)
    assert world.steps == 1
    assert world.time == 0.01
    # free fall over the step, exact: z = z0 - g t^2 / 2, to round-off of z0 (a few ulps)
    fall = start[1:, -1] - 0.5 * G * 0.01**2
    np.testing.assert_allclose(world.positions[1:, -1], fall, rtol=0, atol=4e-16 * 3)
    np.testing.assert_allclose(world.velocities[1:, -1], -G * 0.01, rtol=1e-15)
    # later steps are whole steps from there
    world.step()
    world.step()
    assert world.steps == 3
    assert world.time == pytest.approx(0.01 + 2 / 60, rel=1e-15)


def test_the_event_driven_engine_steps_exactly_dt_and_needs_one() -> None:
    world = carom.World(2, box=[1.0, 1.0])
    world.add_spheres([[0.3, 0.5], [0.7, 0.5]], [[1.0, 0.0], [-1.0, 0.0]], radius=0.05)
    with pytest.raises(CaromError, match="no step of its own"):
        world.step()
    assert world.time == 0.0
    assert world.steps == 0
    # the gap of 0.3 m closes at 2 m/s: the impact at 0.15 s, inside the second step
    world.step(0.1)
    np.testing.assert_array_equal(world.velocities, [[1.0, 0.0], [-1.0, 0.0]])
    world.step(0.1)
    assert world.steps == 2
    assert world.time == pytest.approx(0.2, rel=1e-15)
    # equal masses, elastic: the velocities exchanged, and each ball 0.05 s back from contact
    np.testing.assert_array_equal(world.velocities, [[-1.0, 0.0], [1.0, 0.0]])
    np.testing.assert_allclose(world.positions[:, 0], [0.40, 0.60], rtol=0, atol=1e-15)


@pytest.mark.parametrize(
    "dt", [0.0, -0.01, math.nan, math.inf, "0.01", True, None, 1e-12, 1e300], ids=repr
)
def test_a_step_that_cannot_be_taken_is_refused_and_nothing_moves(dt: object) -> None:
    world = _boxes(2)
    world.step()
    before = world.positions.copy(), world.time, world.steps
    if dt is None:  # a step of its own is fine in the rigid engine: refused in the other
        world = carom.World(2, box=[1.0, 1.0])
        world.add_spheres([[0.5, 0.5]], [[1.0, 0.0]], radius=0.05)
        before = world.positions.copy(), world.time, world.steps
    with pytest.raises(CaromError, match=r"dt|step"):
        world.step(dt)  # type: ignore[arg-type]
    np.testing.assert_array_equal(world.positions, before[0])
    assert (world.time, world.steps) == before[1:]
