"""The build's passes over ranges of bodies on threads (carom.engines.edmd.threads): the same
bits as on one thread, for the whole engine (its lists, cells, first events and overlap
check) and for the run that follows."""

from __future__ import annotations

import numpy as np
import pytest

import carom
from carom.engines.edmd import threads
from tests.worlds import gas, rough_disks


def test_ranges_cover_the_bodies_in_order_and_raise_the_first_error(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    monkeypatch.setattr(threads, "range_count", lambda n: 4)
    assert threads.in_ranges(lambda lo, hi, k: (lo, hi, k), 10, "x") == [
        (0, 2, "x"),
        (2, 5, "x"),
        (5, 7, "x"),
        (7, 10, "x"),
    ]

    def fails(lo: int, hi: int) -> int:
        if lo > 0:
            raise ValueError(f"range {lo}")
        return lo

    with pytest.raises(ValueError, match="range 2"):  # the first range's error of three
        threads.in_ranges(fails, 10)
    monkeypatch.undo()
    # below THREAD_BODIES bodies, one range, on the calling thread
    assert threads.range_count(threads.THREAD_BODIES - 1) == 1


def _state_bits(world: carom.World) -> dict[str, bytes]:
    engine = world.engine
    assert engine is not None
    scratch = {"scan", "scan_body", "near", "nbr_old"}  # (each pass has its own)
    return {
        name: np.ascontiguousarray(value).tobytes()
        for name, value in engine.state._asdict().items()
        if isinstance(value, np.ndarray) and name not in scratch
    }


WORLDS = {
    "3D periodic gas": lambda: gas(3, 6, 0.3, seed=1),
    "2D walled gas": lambda: gas(2, 14, 0.5, seed=2, boundary="walls", e=0.9),
    "rough disks under gravity": lambda: rough_disks(10),
}


@pytest.mark.parametrize("name", list(WORLDS))
def test_an_engine_built_on_many_ranges_is_the_same_to_the_bit(
    name: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    one = WORLDS[name]()
    one.prepare()
    monkeypatch.setattr(threads, "range_count", lambda n: min(5, n))
    many = WORLDS[name]()
    many.prepare()
    built = _state_bits(one)
    assert _state_bits(many) == built
    for world in (one, many):
        world.run(until=world.time + 0.5, log=False)
    assert one.positions.tobytes() == many.positions.tobytes()
    assert one.velocities.tobytes() == many.velocities.tobytes()
    assert one.stats.collisions == many.stats.collisions > 0


def test_an_overlap_found_in_a_later_range_is_refused(monkeypatch: pytest.MonkeyPatch) -> None:
    # the overlap check runs over ranges too: the first overlapping pair of the first range
    # that has one is named, as with one range
    monkeypatch.setattr(threads, "range_count", lambda n: min(4, n))
    world = gas(3, 4, 0.3, seed=3, boundary="walls")
    corner = world.bodies.position.max(axis=0)
    world.add_spheres([corner + 0.01], radius=0.5)
    with pytest.raises(carom.CaromError, match="overlap by"):
        world.build()
