"""Contact events after each step (issue 43, item 3): ``World.contact_events()`` with
``begin``, ``end`` and ``hit`` structured arrays, and ``World.hit_threshold``.

A box dropped on a floor is the closed form: free flight is exact and the impact is solved at
its exact time, so the hit's time is ``sqrt(2 h / g)`` and its speed ``sqrt(2 g h)``.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.errors import CaromError
from carom.materials import Material

G = 9.81
DROP = 0.5  # [m] from the box's underside to the floor


def _drop(dim: int, restitution: float) -> carom.World:
    """A unit box whose underside is DROP above a floor (body 0), falling from rest."""
    mat = Material(restitution=restitution)
    if dim == 2:
        from carom.shapes import Box

        world = carom.World(2, [10.0, 10.0], gravity=[0.0, -G], boundary="open")
        world.add_body(Box(10.0, 1.0), [5.0, -0.5], kind="static", material=mat)
        world.add_body(Box(1.0, 1.0), [5.0, 0.5 + DROP], material=mat)
        return world
    from carom.shapes3d import Box as Box3D

    world = carom.World(3, [10.0] * 3, gravity=[0.0, 0.0, -G], boundary="open")
    world.add_body(Box3D([10.0, 10.0, 1.0]), [5.0, 5.0, -0.5], kind="static", material=mat)
    world.add_body(Box3D([1.0, 1.0, 1.0]), [5.0, 5.0, 0.5 + DROP], material=mat)
    return world


def _until_event(world: carom.World, field: str, steps: int = 120) -> tuple[int, np.ndarray]:
    """Step until the events have a ``field`` row; return the step and that array."""
    for k in range(steps):
        world.step()
        events = getattr(world.contact_events(), field)
        if events.size:
            return k, events
    raise AssertionError(f"no {field} event in {steps} steps")


@pytest.mark.parametrize("dim", [2, 3])
def test_a_dropped_box_hits_at_the_closed_form_time_and_speed(dim: int) -> None:
    world = _drop(dim, restitution=0.0)
    assert world.contact_events().begin.size == 0  # nothing before the first step
    _, hit = _until_event(world, "hit")
    assert hit.size == 1
    (event,) = hit
    assert (event["a"], event["b"]) == (0, 1)
    # free fall from rest through DROP: t = sqrt(2 DROP / g), v = sqrt(2 g DROP). The exact
    # impacts advance a pair until its gap is under a thousandth of the slop (5e-6 m; measured
    # here 1.2e-9 m), so the time is within gap / v and the speed within gap / (2 DROP)
    gap = 1e-3 * 0.005
    speed = math.sqrt(2 * G * DROP)
    assert event["time"] == pytest.approx(math.sqrt(2 * DROP / G), abs=gap / speed)
    assert event["speed"] == pytest.approx(speed, rel=gap / (2 * DROP))
    up = np.zeros(dim)
    up[-1] = 1.0
    np.testing.assert_allclose(event["normal"], up, atol=1e-15)  # from the floor to the box
    assert abs(event["point"][-1]) < gap  # on the floor's top face, to the gap
    assert np.all(np.abs(event["point"][:-1] - 5.0) <= 0.5 + 1e-12)  # under the box
    begin = world.contact_events().begin
    assert [(int(e["a"]), int(e["b"])) for e in begin] == [(0, 1)]


@pytest.mark.parametrize("dim", [2, 3])
def test_a_resting_box_makes_no_events_and_ends_when_it_leaves(dim: int) -> None:
    world = _drop(dim, restitution=0.0)
    _until_event(world, "begin")
    for _ in range(60):  # resting: touching every step, so neither begin nor end
        world.step()
        events = world.contact_events()
        assert events.begin.size == events.end.size == events.hit.size == 0
    up = np.zeros(dim)
    up[-1] = 5.0
    world.body(1).velocity = up
    _, end = _until_event(world, "end", steps=5)
    assert [(int(e["a"]), int(e["b"])) for e in end] == [(0, 1)]


def test_an_elastic_bounce_begins_and_ends_at_once() -> None:
    world = _drop(2, restitution=1.0)
    _, begin = _until_event(world, "begin")
    assert begin.size == 1
    # the impact solved within the step sends it up at the speed it came: it has left by the
    # next step (it rises 3.1 m/s x 1/60 s = 5 cm, beyond the slop)
    world.step()
    events = world.contact_events()
    assert [(int(e["a"]), int(e["b"])) for e in events.end] == [(0, 1)]
    assert events.begin.size == 0


def test_the_hit_threshold_is_the_users() -> None:
    fast = math.sqrt(2 * G * DROP)  # 3.13 m/s
    world = _drop(2, restitution=0.0)
    world.hit_threshold = fast * 1.01
    _until_event(world, "begin")
    assert world.contact_events().hit.size == 0  # the landing was slower than asked
    world = _drop(2, restitution=0.0)
    world.hit_threshold = fast * 0.99
    _, hit = _until_event(world, "hit")
    assert hit.size == 1
    assert world.hit_threshold == fast * 0.99
    with pytest.raises(CaromError, match="hit_threshold must be a positive finite speed"):
        world.hit_threshold = -1.0
    assert world.hit_threshold == fast * 0.99


def test_a_wall_of_the_box_is_minus_one() -> None:
    from carom.shapes import Circle

    world = carom.World(2, [10.0, 10.0], gravity=[0.0, 0.0], boundary="walls")
    world.add_body(Circle(0.5), [5.0, 5.0], velocity=[6.0, 0.0])
    _, hit = _until_event(world, "hit")
    (event,) = hit
    assert (event["a"], event["b"]) == (-1, 0)
    # the ball meets the wall x = 10 when its centre reaches 9.5: t = 4.5 / 6 s, to the gap
    # the exact impacts close to (a thousandth of the 5 mm slop) over the speed
    assert event["time"] == pytest.approx(4.5 / 6.0, abs=5e-6 / 6.0)
    assert event["speed"] == pytest.approx(6.0, rel=1e-15)  # no force: the speed is kept
    np.testing.assert_allclose(event["normal"], [-1.0, 0.0], atol=1e-15)  # from wall to ball


def test_events_are_structured_arrays() -> None:
    world = _drop(3, restitution=0.0)
    _until_event(world, "hit")
    events = world.contact_events()
    assert events.begin.dtype.names == ("a", "b", "point", "normal")
    assert events.end.dtype.names == ("a", "b")
    assert events.hit.dtype.names == ("a", "b", "time", "point", "normal", "speed")
    assert events.hit["point"].shape == (1, 3)


def test_the_pairs_compared_step_to_step_are_numpys_set_operations() -> None:
    from carom.engines.stepped.events import compare

    # the merge of this step's pairs (repeats allowed) against the last step's (sorted),
    # where a last pair of bodies neither of which moves persists (it sleeps), against
    # NumPy's unique / setdiff1d on random pairs
    rng = np.random.default_rng(3)
    n = 101
    for _ in range(300):
        new = rng.integers(0, 60, rng.integers(0, 40)).astype(np.int64)
        last = np.unique(rng.integers(0, 60, rng.integers(0, 40))).astype(np.int64)
        moving = rng.random(100) < 0.5
        now, began, row, ended = compare(new, last, moving, n)
        asleep = [
            k for k in last if not ((k // n >= 1 and moving[k // n - 1]) or moving[k % n - 1])
        ]
        expected = np.unique(np.concatenate([new, np.array(asleep, np.int64)]))
        np.testing.assert_array_equal(now, expected)
        np.testing.assert_array_equal(began, np.setdiff1d(np.unique(new), last))
        np.testing.assert_array_equal(ended, np.setdiff1d(last, expected))
        np.testing.assert_array_equal(new[row], began)
        if began.size:  # each began pair's row is its first in this step's keys
            assert all(
                int(np.flatnonzero(new == k)[0]) == r for k, r in zip(began, row, strict=True)
            )
