"""A change between steps builds the rigid engine again (a body added, a kind switched, gravity
or a material set); the engine built in its place takes over the running one's warm starts and
sleep (:func:`carom.engines.stepped.memory.carried`), so that the change leaves alone what it
does not touch: a ball shot into a game's world neither wakes nor shakes a resting stack."""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
import pytest

import carom
from carom.materials import Material
from carom.shapes import Box, Circle
from carom.shapes3d import Box as Box3
from carom.shapes3d import Sphere

G = 10.0  # [m/s^2]


def stack_2d(boundary: str = "open") -> carom.World:
    """Six boxes on a static floor (open box) or on the bottom wall (walled box)."""
    mat = Material(0.0, friction=0.6)
    world = carom.World(2, [40.0, 20.0], gravity=[0.0, -G], boundary=boundary, walls=mat)
    if boundary == "open":
        world.add_body(Box(40.0, 1.0), [20.0, -0.5], kind="static", material=mat)
    for k in range(6):
        world.add_body(Box(1.0, 1.0), [20.0, 0.5 + k], material=mat)
    return world


def stack_3d(boundary: str = "open") -> carom.World:
    mat = Material(0.0, friction=0.6)
    world = carom.World(3, [10.0] * 3, gravity=[0.0, 0.0, -G], boundary=boundary, walls=mat)
    if boundary == "open":
        world.add_body(Box3([10.0, 10.0, 1.0]), [5.0, 5.0, -0.5], kind="static", material=mat)
    for k in range(4):
        world.add_body(Box3([1.0, 1.0, 1.0]), [5.0, 5.0, 0.5 + k], material=mat)
    return world


def far_ball(world: carom.World) -> int:
    """A ball dropped well away from the stack, of a material of its own."""
    if world.dim == 2:
        return world.add_body(Circle(0.25), [4.0, 15.0], material=Material(0.5, friction=0.2))
    return world.add_body(Sphere(0.25), [1.0, 1.0, 8.0], material=Material(0.5, friction=0.2))


def motion(world: carom.World, n: int) -> tuple[np.ndarray, ...]:
    fr = world.frame()
    return (
        fr.positions[:n],
        fr.velocities[:n],
        np.asarray(fr.orientations)[:n],
        fr.angular_velocities[:n],
    )


def awake(world: carom.World, rows: range) -> list[bool]:
    return [world.body(i).awake for i in rows]


STACKS = [
    pytest.param(stack_2d, "open", id="2d-floor"),
    pytest.param(stack_2d, "walls", id="2d-walls"),
    pytest.param(stack_3d, "open", id="3d-floor"),
    pytest.param(stack_3d, "walls", id="3d-walls"),
]


@pytest.mark.parametrize(("stack", "boundary"), STACKS)
@pytest.mark.parametrize(
    "change",
    [
        pytest.param(lambda w: w.set_gravity(np.asarray(w.gravity)), id="same-gravity"),
        pytest.param(far_ball, id="ball-far-away"),
    ],
)
def test_a_change_away_from_a_settling_stack_leaves_it_bit_for_bit(
    stack: Callable[[str], carom.World], boundary: str, change: Callable[[carom.World], object]
) -> None:
    # the stack is still settling (awake, its contacts warm-started step to step): the engine
    # built again after the change starts from the same state and the same warm starts, the
    # pieces renumbered (with walls, theirs move up past the ball's), so its steps are the
    # same arithmetic as the running engine's: the same bits, not just close
    changed, kept = stack(boundary), stack(boundary)
    n = changed.n_bodies
    for world in (changed, kept):
        for _ in range(15):
            world.step()
    assert all(awake(changed, range(n - 4, n)))  # (the case: settling, not asleep)
    change(changed)
    for world in (changed, kept):
        for _ in range(30):
            world.step()
    for a, b in zip(motion(changed, n), motion(kept, n), strict=True):
        np.testing.assert_array_equal(a, b)


@pytest.mark.parametrize(("stack", "boundary"), STACKS)
def test_a_sleeping_stack_sleeps_through_a_ball_added_and_wakes_when_it_lands(
    stack: Callable[[str], carom.World], boundary: str
) -> None:
    world = stack(boundary)
    n = world.n_bodies
    first = n - (6 if world.dim == 2 else 4)
    world.run(until=world.time + 3.0)
    assert not any(awake(world, range(first, n)))  # (the case: asleep)
    before = motion(world, n)
    ball = far_ball(world)
    start = world.body(ball).position
    for _ in range(6):
        world.step()
    # asleep, the stack has not moved at all
    assert not any(awake(world, range(first, n)))
    for a, b in zip(motion(world, n), before, strict=True):
        np.testing.assert_array_equal(a, b)
    # and the ball falls freely meanwhile: g t^2 / 2 (the step's integration is exact for
    # constant gravity up to round-off of a few ulps of the height)
    t = 6 * world.rigid_settings.dt
    assert world.body(ball).position[-1] == pytest.approx(start[-1] - 0.5 * G * t * t, abs=1e-12)
    # a box dropped onto the top of the stack wakes it through their contact
    top = world.body(n - 1).position
    above = top + (np.array([0.0, 1.5]) if world.dim == 2 else np.array([0.0, 0.0, 1.5]))
    world.add_body(Box(1.0, 1.0) if world.dim == 2 else Box3([1.0, 1.0, 1.0]), above)
    woke = []
    for _ in range(40):  # (it lands after about 0.32 s: 19 steps)
        world.step()
        woke.append(all(awake(world, range(first, n))))
    assert not woke[0]
    assert any(woke)


@pytest.mark.parametrize(("stack", "boundary"), STACKS[::2])
@pytest.mark.parametrize(
    "change",
    [
        pytest.param(lambda w: w.set_gravity(-0.5 * np.asarray(w.gravity)), id="gravity-turned-up"),
        pytest.param(lambda w: w.set_material(0, Material(0.0, friction=0.0)), id="friction-off"),
    ],
)
def test_a_change_of_the_laws_wakes_the_sleepers(
    stack: Callable[[str], carom.World], boundary: str, change: Callable[[carom.World], object]
) -> None:
    # sleep was earned under the old laws: gravity or friction changed, it is not carried
    # (warm starts are: a guess the solver corrects)
    world = stack(boundary)
    n = world.n_bodies
    first = n - (6 if world.dim == 2 else 4)
    world.run(until=world.time + 3.0)
    assert not any(awake(world, range(first, n)))
    z0 = world.body(n - 1).position[-1]
    change(world)
    world.step()
    assert all(awake(world, range(first, n)))
    if world.gravity[-1] > 0:  # gravity upward: the stack lifts off
        for _ in range(30):
            world.step()
        assert world.body(n - 1).position[-1] > z0 + 0.1


def test_a_body_switched_to_kinematic_wakes_its_island() -> None:
    # the stack's lowest box made kinematic: its sleep is not carried (it is no longer
    # dynamic), and the boxes above, asleep on it, wake through their contact with it
    world = stack_2d()
    world.run(until=3.0)
    n = world.n_bodies
    assert not any(awake(world, range(1, n)))
    world.set_kind(1, "kinematic")
    world.body(1).velocity = [0.0, 1.0]  # it rises at 1 m/s, whatever it meets
    for _ in range(30):
        world.step()
    # half a second: the boxes above ride up with it (1 m/s over 0.5 s), awake
    assert world.body(n - 1).position[1] > 5.5 + 0.4


def test_a_refused_rebuild_leaves_the_handover_for_the_next() -> None:
    # a box put deep into the sleeping stack is refused; once it is taken out again, the
    # engine built then still takes the running one's sleep: the stack has not moved
    world = stack_2d()
    world.run(until=3.0)
    n = world.n_bodies
    before = motion(world, n)
    box = world.add_body(Box(1.0, 1.0), [20.2, 3.5])
    with pytest.raises(carom.CaromError, match="overlap"):
        world.step()
    world.remove_body(box)
    world.step()
    assert not any(awake(world, range(1, n)))
    for a, b in zip(motion(world, n), before, strict=True):
        np.testing.assert_array_equal(a, b)
