"""Collision filters (issue 43, item 3): ``World.set_filter`` with category and mask bits and a
group, as Box2D's ``b2Filter``. A pair kept apart passes through: no contact, no exact impact,
no sweep; so a body filtered from the floor falls through it on the free-fall parabola.
"""

from __future__ import annotations

import numpy as np
import pytest

import carom
from carom.errors import CaromError

G = 9.81


def _floor_and_boxes(dim: int) -> carom.World:
    """A floor (body 0) and two unit boxes 1 m above it, side by side (bodies 1, 2)."""
    if dim == 2:
        from carom.shapes import Box

        world = carom.World(2, [10.0, 10.0], gravity=[0.0, -G], boundary="open")
        world.add_body(Box(10.0, 1.0), [5.0, -0.5], kind="static", restitution=0.0)
        world.add_body(Box(1.0, 1.0), [3.0, 1.5], restitution=0.0)
        world.add_body(Box(1.0, 1.0), [7.0, 1.5], restitution=0.0)
        return world
    from carom.shapes3d import Box as Box3D

    world = carom.World(3, [10.0] * 3, gravity=[0.0, 0.0, -G], boundary="open")
    world.add_body(Box3D([10.0, 10.0, 1.0]), [5.0, 5.0, -0.5], kind="static", restitution=0.0)
    world.add_body(Box3D([1.0, 1.0, 1.0]), [3.0, 5.0, 1.5], restitution=0.0)
    world.add_body(Box3D([1.0, 1.0, 1.0]), [7.0, 5.0, 1.5], restitution=0.0)
    return world


@pytest.mark.parametrize("dim", [2, 3])
def test_a_body_masked_from_the_floor_falls_through_it_on_the_parabola(dim: int) -> None:
    world = _floor_and_boxes(dim)
    world.set_filter(1, category=0b10)
    world.set_filter(0, mask=~0b10 & (2**64 - 1))  # the floor touches all but category 2
    for _ in range(90):
        world.step()
    t = world.time
    # body 1 in free fall from rest: z = 1.5 - g t^2 / 2 exactly (no contact, no impact)
    assert world.positions[1, -1] == pytest.approx(1.5 - 0.5 * G * t * t, abs=1e-12)
    # body 2 landed and rests on the floor (its centre half a box up, within the slop)
    assert abs(world.positions[2, -1] - 0.5) < 0.005
    assert world.contact_events().hit.size == 0  # (the landing was before this step)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_negative_group_keeps_its_members_apart_even_overlapping(dim: int) -> None:
    world = _floor_and_boxes(dim)
    at = world.positions[1].copy()
    at[0] += 0.5  # half into body 1: refused at the start without the group
    if dim == 2:
        from carom.shapes import Box

        world.add_body(Box(1.0, 1.0), at, restitution=0.0)
    else:
        from carom.shapes3d import Box as Box3D

        world.add_body(Box3D([1.0, 1.0, 1.0]), at, restitution=0.0)
    world.set_filter([1, 3], group=-4)
    for _ in range(60):
        world.step()
    # both land on the floor, still overlapping: neither pushed the other sideways
    x = world.positions[[1, 3], 0]
    assert x[1] - x[0] == pytest.approx(0.5, abs=1e-9)
    assert np.all(np.abs(world.positions[[1, 3], -1] - 0.5) < 0.005)


def test_a_positive_group_touches_whatever_its_bits() -> None:
    world = _floor_and_boxes(2)
    world.set_filter([0, 1], category=0b100, mask=0, group=3)  # no bits, same group
    world.set_filter(2, mask=0)  # body 2 touches nothing: it falls through
    world.run(until=1.5)
    assert abs(world.positions[1, 1] - 0.5) < 0.005
    assert world.positions[2, 1] < -5.0
    table = world.collision_filters
    assert table[1].tolist() == [0b100, 0, 3]
    assert table[2].tolist() == [1, 0, 0]


def test_a_fast_body_filtered_from_a_wall_goes_through_it() -> None:
    from carom.shapes import Box, Circle

    world = carom.World(2, [100.0, 10.0], boundary="open")
    world.add_body(Box(0.1, 10.0), [50.0, 5.0], kind="static")
    world.add_body(Circle(0.2), [10.0, 5.0], velocity=[300.0, 0.0])  # 5 m a step
    world.add_body(Circle(0.2), [10.0, 8.0], velocity=[300.0, 0.0])
    world.set_filter(1, category=0b10)
    world.set_filter(0, mask=1)
    for _ in range(12):  # 0.2 s: 60 m at 300 m/s
        world.step()
    # no contact, no exact impact and no sweep stopped it: x = 10 + 300 t exactly
    assert world.positions[1, 0] == pytest.approx(10.0 + 300.0 * world.time, rel=1e-15)
    assert world.positions[2, 0] < 50.0  # the one not filtered bounced off the wall


def test_filters_outlive_a_rebuild_and_new_bodies_start_with_the_defaults() -> None:
    from carom.shapes import Box

    world = _floor_and_boxes(2)
    world.set_filter(1, category=0b10, mask=0b1)
    world.step()
    world.add_body(Box(1.0, 1.0), [5.0, 3.0], restitution=0.0)  # (the engine is built again)
    table = world.collision_filters
    assert table.tolist() == [[1, -1, 0], [2, 1, 0], [1, -1, 0], [1, -1, 0]]
    world.set_filter(0, mask=~0b10 & (2**64 - 1))
    world.run(until=1.5)
    assert world.positions[1, 1] < -5.0  # through the floor, after the rebuild
    assert abs(world.positions[3, 1] - 0.5) < 0.005


@pytest.mark.parametrize(
    ("kwargs", "match"),
    [
        (
            {"category": -(2**63) - 1},
            r"category must lie in \[-9223372036854775808, 18446744073709551615\]",
        ),
        ({"mask": 2**64}, "mask must lie in"),
        ({"group": True}, "group must be a whole number"),
        ({"category": 1.5}, "category must be a whole number"),
    ],
)
def test_wrong_bits_are_refused_and_change_nothing(kwargs: dict[str, object], match: str) -> None:
    world = _floor_and_boxes(2)
    before = world.collision_filters
    with pytest.raises(CaromError, match=match):
        world.set_filter(1, **kwargs)  # type: ignore[arg-type]
    np.testing.assert_array_equal(world.collision_filters, before)
    with pytest.raises(CaromError, match="body 5 is not in the world"):
        world.set_filter([1, 5], category=2)


def test_filters_are_kept_in_a_checkpoint(tmp_path: object) -> None:
    from pathlib import Path

    world = _floor_and_boxes(2)
    world.set_filter(1, category=0b10)
    world.set_filter(0, mask=~0b10 & (2**64 - 1))
    world.step()
    path = Path(str(tmp_path)) / "filtered.npz"
    world.save(path)
    again = carom.World.load(path)
    np.testing.assert_array_equal(again.collision_filters, world.collision_filters)
    for w in (world, again):
        w.run(until=1.5)
    # the loaded world goes on bit for bit: body 1 through the floor in both
    np.testing.assert_array_equal(again.positions, world.positions)
    assert again.positions[1, 1] < -5.0
