"""Removing a body between steps (issue 43, item 2), and a ray's category mask (item 4).

A removed body keeps its index and its place in the arrays, frozen; nothing touches it, no ray
sees it, and its index is refused from then on. It is built on the collision filters: its
category and mask are zeroed, so the same pair filtering that lets a masked body pass through
the floor lets everything pass through it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import carom
from carom.errors import CaromError

G = 9.81


def _stack() -> carom.World:
    """Two unit boxes stacked on a floor (bodies 1 below, 2 above), settled."""
    from carom.shapes import Box

    world = carom.World(2, [10.0, 10.0], gravity=[0.0, -G], boundary="open")
    world.add_body(Box(10.0, 1.0), [5.0, -0.5], kind="static", restitution=0.0)
    world.add_body(Box(1.0, 1.0), [5.0, 0.5], restitution=0.0)
    world.add_body(Box(1.0, 1.0), [5.0, 1.5], restitution=0.0)
    for _ in range(30):
        world.step()
    return world


def test_removing_the_lower_box_drops_the_upper_one_onto_the_floor() -> None:
    world = _stack()
    below = world.positions[1].copy()
    world.remove_body(1)
    assert world.alive.tolist() == [True, False, True]
    for _ in range(60):
        world.step()
        if 2 in {int(e["b"]) for e in world.contact_events().end}:
            ended = True
    np.testing.assert_array_equal(world.positions[1], below)  # frozen where it was
    assert abs(world.positions[2, 1] - 0.5) < 0.005  # the upper box now rests on the floor
    assert ended
    # rays pass through the removed box and meet the one behind it
    hit = world.ray_cast([0.0, 0.5], [1.0, 0.0])
    assert hit is not None
    assert hit.body == 2


@pytest.mark.parametrize(
    "call",
    [
        lambda w: w.body(1),
        lambda w: w.apply_impulses([2, 1], [1.0, 0.0]),
        lambda w: w.remove_body(1),
        lambda w: w.set_filter(1, category=2),
    ],
)
def test_a_removed_index_is_refused(call: object) -> None:
    world = _stack()
    world.remove_body(1)
    with pytest.raises(CaromError, match="body 1 was removed"):
        call(world)  # type: ignore[operator]


def test_the_ledger_closes_across_a_removal() -> None:
    world = _stack()
    world.body(1).velocity = [0.5, 0.0]
    e0 = world.engine.energy()  # type: ignore[union-attr]
    c0 = world.counters()
    m, spin = world.masses[1], world.body(1).angular_velocity
    kinetic = 0.5 * m * 0.25 + 0.5 * (m * 2.0 / 12.0) * spin**2  # a unit box: I = m / 6
    world.remove_body(1)  # its kinetic energy leaves as work done on it
    for _ in range(60):
        world.step()
    c = world.counters()
    e = world.engine.energy()  # type: ignore[union-attr]
    work = c.work_done - c0.work_done
    lost = c.energy_lost - c0.energy_lost
    given = c.energy_given - c0.energy_given
    # E0 + work = E + lost - given over what followed, to round-off of the energies
    assert abs(e0 + work - (e + lost - given)) < 1e-12 * e0
    assert work == pytest.approx(-kinetic, rel=1e-12)


def test_a_removal_outlives_a_rebuild_and_a_checkpoint(tmp_path: Path) -> None:
    from carom.shapes import Box

    world = _stack()
    world.remove_body(1)
    world.add_body(Box(1.0, 1.0), [8.0, 0.5], restitution=0.0)  # (the engine is built again)
    world.save(tmp_path / "removed.npz")
    again = carom.World.load(tmp_path / "removed.npz")
    assert again.alive.tolist() == [True, False, True, True]
    for w in (world, again):
        w.run(until=world.time + 1.0)
    np.testing.assert_array_equal(again.positions, world.positions)
    assert abs(world.positions[2, 1] - 0.5) < 0.005


def test_a_ray_sees_only_the_categories_in_its_mask() -> None:
    world = _stack()
    world.set_filter(2, category=0b100)
    origin, down = [5.0, 5.0], [0.0, -1.0]
    hit = world.ray_cast(origin, down)
    assert hit is not None
    assert hit.body == 2  # the top box first
    hit = world.ray_cast(origin, down, mask=0b1)  # past category 4: the lower box
    assert hit is not None
    assert hit.body == 1
    hits = world.ray_casts([origin] * 3, down, mask=0b100)
    assert hits["body"].tolist() == [2, 2, 2]
    everything = world.ray_cast(origin, down, mask=-1)  # (two's complement: every bit)
    assert everything is not None
    assert everything.body == 2
    with pytest.raises(CaromError, match="mask must lie in"):
        world.ray_cast(origin, down, mask=2**64)


def test_a_removed_body_ends_its_contacts_at_the_next_step() -> None:
    # the stack sleeps after a while; a removed body moves no more, so a pair of it would
    # otherwise count as a sleeping pair, touching for ever
    world = _stack()
    for _ in range(60):
        world.step()
    assert not world.body(2).awake
    world.remove_body(2)
    world.step()
    ended = {(int(e["a"]), int(e["b"])) for e in world.contact_events().end}
    assert ended == {(1, 2)}
    world.step()
    assert world.contact_events().end.size == 0


def test_frames_say_which_bodies_are_in_the_world() -> None:
    world = _stack()
    assert world.frame().alive is None  # every body is
    world.remove_body(1)
    frame = world.frame()
    assert frame.alive is not None
    assert frame.alive.tolist() == [True, False, True]
    frames = list(world.frames(world.time + 0.1, 0.05))
    assert len(frames) == 2
    for f in frames:
        assert f.alive is not None
        assert f.alive.tolist() == [True, False, True]
    recording = world.record([world.time + 0.05, world.time + 0.1])
    assert recording.alive is not None
    assert recording.alive.tolist() == [True, False, True]
    assert recording.frame(1).alive is recording.alive
    # the removed body's rows hold where it stopped
    np.testing.assert_array_equal(recording.positions[:, 1], [frame.positions[1]] * 2)
