"""Changing a running world: gravity, materials, and bodies added beside a compressed stack
(issue 44: what carom play's sliders and shots do)."""

from __future__ import annotations

import numpy as np
import pytest

import carom
from carom.errors import CaromError
from carom.materials import Material
from carom.shapes import Box, Circle


def _stack(rows: int = 8) -> carom.World:
    world = carom.World(2, [40.0, 20.0], gravity=[0.0, -10.0], boundary="open")
    mat = Material(0.0, friction=0.6)
    world.add_body(Box(40.0, 1.0), [20.0, -0.5], kind="static", material=mat)
    for k in range(rows):
        world.add_body(Box(1.0, 1.0), [20.0, 0.5 + k], material=mat)
    return world


def test_gravity_changes_from_the_next_step() -> None:
    world = _stack(1)
    ball = world.add_body(Circle(0.25), [5.0, 15.0], velocity=[1.0, 0.0])
    for _ in range(10):
        world.step()
    x0, v0 = world.body(ball).position, world.body(ball).velocity
    world.set_gravity([0.0, -2.0])
    np.testing.assert_array_equal(world.gravity, [0.0, -2.0])
    for _ in range(12):
        world.step()
    t = 12 / 60
    # free flight is exact: x0 + v0 t + g t^2 / 2 under the new gravity
    expected = x0 + v0 * t + 0.5 * np.array([0.0, -2.0]) * t * t
    np.testing.assert_allclose(world.body(ball).position, expected, rtol=0, atol=1e-12)
    with pytest.raises(CaromError, match="gravity"):
        world.set_gravity([0.0, float("nan")])
    np.testing.assert_array_equal(world.gravity, [0.0, -2.0])


def test_a_material_is_replaced_for_every_body_of_it() -> None:
    world = _stack(2)
    world.step()
    world.set_material(0, Material(0.5, friction=0.1))
    assert world.materials[0] == Material(0.5, friction=0.1)
    world.step()  # built again with it
    with pytest.raises(CaromError, match="no material 3"):
        world.set_material(3, Material(0.5))
    with pytest.raises(CaromError, match=r"a carom\.Material"):
        world.set_material(0, 0.5)  # type: ignore[arg-type]


def test_a_body_added_beside_a_compressed_stack_is_taken() -> None:
    # a stack of boxes settles into overlaps deeper than the linear slop (the soft contacts
    # give); a body added far from it between steps rebuilds the engine, which must take the
    # stack as the running engine had it, and refuse only what the addition made deeper
    world = _stack(20)
    for _ in range(60):
        world.step()
    engine = world.engine
    assert engine is not None
    depth = engine.deepest_overlap()[2]  # type: ignore[attr-defined]
    assert depth > world.rigid_settings.linear_slop  # (the case: deeper than the slop)
    ball = world.add_body(Circle(0.25), [5.0, 10.0])
    world.step()
    assert world.overlap_kept == depth
    assert world.body(ball).position[1] < 10.0
    # a box put deep into the stack is still refused when the engine is built again
    world.add_body(Box(1.0, 1.0), [20.2, 3.5])
    with pytest.raises(CaromError, match="deepest overlap the running engine had"):
        world.step()


def test_a_sleeping_compressed_stack_takes_a_new_gravity() -> None:
    # the stack settles deeper than the linear slop and falls asleep: its overlaps are the
    # running engine's all the same, so the engine built again under a new gravity (which
    # wakes it) takes them; it once refused them ("overlap by 0.0133 m ... move them apart")
    world = _stack(20)
    world.run(until=4.0)
    engine = world.engine
    assert engine is not None
    assert not any(world.body(i).awake for i in range(1, 21))
    assert engine.deepest_overlap()[2] == 0.0  # type: ignore[attr-defined]  # (asleep)
    depth = engine.deepest_overlap(asleep=True)[2]  # type: ignore[attr-defined]
    assert depth > world.rigid_settings.linear_slop  # (the case)
    world.set_gravity([0.0, -12.0])
    world.step()
    assert world.overlap_kept == depth
    assert all(world.body(i).awake for i in range(1, 21))
