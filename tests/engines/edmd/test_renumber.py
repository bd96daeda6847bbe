"""Renumbering a running engine's bodies along the Morton curve (carom.engines.edmd.renumber):
a permutation of every per-body array, with every body number mapped, that changes no bit of
a run however the run is cut into calls or checkpoints."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
import pytest

import carom
from carom.engines.base import PARTNER_BODY
from carom.engines.edmd import driver
from carom.engines.edmd.calendar import I_SIZE, IN_HEAP, NOWHERE
from carom.engines.edmd.codes import EV_PAIR
from carom.engines.edmd.driver import EdmdEngine
from carom.engines.edmd.ordering import morton_keys
from carom.engines.edmd.renumber import renumber
from carom.engines.edmd.state import SCHED_KIND, SCHED_OTHER
from carom.scene import find_scene, load_scene
from tests.worlds import gas, rough_disks

EPS = float(np.finfo(np.float64).eps)


WORLDS: dict[str, Callable[[], carom.World]] = {
    "3D periodic gas": lambda: gas(3, 6, 0.3, seed=5, e=0.95),
    "2D walled gas": lambda: gas(2, 12, 0.5, seed=2, boundary="walls", e=0.9),
    "rough disks falling": lambda: rough_disks(7),
    "galton board (static pegs)": lambda: load_scene(find_scene("galton-board")).build(),
}
#: the galton board's balls collide about 10^5 times a second of its time: with the JIT only
NAMES = [
    pytest.param(name, marks=[pytest.mark.needs_jit] if "galton" in name else []) for name in WORLDS
]


@pytest.fixture
def renumbered(monkeypatch: pytest.MonkeyPatch) -> list[bool]:
    """Engines built in the test renumber their bodies after every N events (N bodies); the
    list collects what each renumbering returned (whether a body changed number)."""
    monkeypatch.setattr(driver, "RENUMBER_MIN_BODIES", 0)
    monkeypatch.setattr(driver, "RENUMBER_EVENTS_PER_BODY", 1)
    results: list[bool] = []

    def spy(*args: Any) -> bool:
        results.append(renumber(*args))
        return results[-1]

    monkeypatch.setattr(driver, "renumber", spy)
    return results


def _engine(world: carom.World) -> EdmdEngine:
    engine = world.engine
    assert isinstance(engine, EdmdEngine)
    return engine


@pytest.mark.parametrize("name", NAMES)
def test_a_run_renumbered_as_it_goes_is_bit_identical(name: str, renumbered, tmp_path) -> None:  # type: ignore[no-untyped-def]
    make = WORLDS[name]
    # the run as it was: these engines are built with renumbering off (the fixture's
    # settings apply only to engines built after this point is passed)
    with pytest.MonkeyPatch.context() as off:
        off.setattr(driver, "RENUMBER_MIN_BODIES", 1 << 62)
        straight = make()
        straight.run(until=straight.time + 6.0, log=True)
        assert _engine(straight).renumber_every == 0
    # the same run renumbered after every N events, cut into calls of uneven length, saved
    # and resumed half-way: every renumbering happens after the same event, and none changes
    # a bit
    world = make()
    start = world.time
    for step in (0.3, 1.1, 1.7):
        world.run(until=start + step, log=True)
    world.save(tmp_path / "mid.npz")
    resumed = carom.World.load(tmp_path / "mid.npz")
    for step in (2.9, 4.0, 6.0):
        resumed.run(until=start + step, log=True)
    assert _engine(resumed).renumber_every == resumed.n_bodies
    assert any(renumbered), "no body changed number: the test would prove nothing"
    assert resumed.time == straight.time
    np.testing.assert_array_equal(resumed.positions, straight.positions)
    np.testing.assert_array_equal(resumed.velocities, straight.velocities)
    np.testing.assert_array_equal(resumed.orientations, straight.orientations)
    np.testing.assert_array_equal(resumed.angular_velocities, straight.angular_velocities)
    # the log: the same collisions at the same times with the same speeds; a pair's two
    # bodies may come the other way round (the one with the lower engine number is taken
    # first), and then the impulse on the first is the other's, exactly negated, and the
    # contact point, measured from the other side, can differ in its last bits
    got, want = _pairs_ordered(resumed.collisions), _pairs_ordered(straight.collisions)
    for field in ("time", "kind", "body", "partner", "impulse", "un_before", "un_after"):
        np.testing.assert_array_equal(got[field], want[field], err_msg=field)
    np.testing.assert_allclose(got["point"], want["point"], rtol=0, atol=16 * EPS * 10.0)
    assert resumed.stats.collisions == straight.stats.collisions
    # every count but that of events, which includes stale predictions: where events fall
    # at the same time (the galton board's balls start in rows), the order they are taken
    # in decides which of them go stale
    assert _engine(resumed).counters()._replace(events=0) == _engine(straight).counters()._replace(
        events=0
    )


def _pairs_ordered(log: np.ndarray) -> np.ndarray:
    """The collision log with each pair's bodies in increasing order, the impulse on the
    first (carom.engines.base.COLLISION_DTYPE)."""
    log = log.copy()
    swap = (log["kind"] == PARTNER_BODY) & (log["body"] > log["partner"])
    log["body"][swap], log["partner"][swap] = log["partner"][swap], log["body"][swap]
    log["impulse"][swap] = -log["impulse"][swap]
    return log


def _as_caller_sees(engine: EdmdEngine) -> dict[str, Any]:
    """Everything in an engine's model and state that depends on its numbering, written in
    the caller's numbering (rows by caller's body, body numbers mapped to the caller's)."""
    model, state, order = engine.model, engine.state, engine.order
    n = order.shape[0]

    def rows(array: np.ndarray | None) -> np.ndarray | None:
        if array is None:
            return None
        out = np.empty_like(array)
        out[order] = array
        return out

    seen: dict[str, Any] = {}
    for name in ("mobile", "radius", "mass", "inv_mass", "q", "material"):
        seen["model." + name] = rows(getattr(model, name))
    for name in ("kin", "acc", "support", "w", "orient", "orient_t", "last_coll", "shell",
                 "nbr_count", "nbr_mark", "cell", "slot", "ev_time", "counter"):  # fmt: skip
        seen[name] = rows(getattr(state, name))
    cal_next, cal_prev, cal_loc, cur_where = (state.cal_body[:, k] for k in range(4))
    seen["cal_loc"] = rows(cal_loc)
    sched = state.sched.copy()
    pair = sched[:, SCHED_KIND] == EV_PAIR
    sched[pair, SCHED_OTHER] = order[sched[pair, SCHED_OTHER]]
    seen["sched"] = rows(sched)
    # lists in their order, cell rows in theirs
    seen["nbr"] = [list(order[state.nbr[e, : state.nbr_count[e]]]) for e in np.argsort(order)]
    seen["cell_body"] = [
        list(order[state.cell_body[c, : state.cell_count[c]]])
        for c in range(state.cell_count.shape[0])
    ]
    # the calendar: each bucket's list front to back (its links checked both ways), and the
    # current bucket's heap as (time, body) in the order it pops
    buckets = []
    for head in state.cal_head:
        bucket, previous, body = [], -1, int(head)
        while body >= 0:
            assert cal_prev[body] == previous
            assert cal_loc[body] not in (IN_HEAP, NOWHERE)
            bucket.append(int(order[body]))
            previous, body = body, int(cal_next[body])
        buckets.append(bucket)
    seen["buckets"] = buckets
    size = int(state.cal_i[I_SIZE])
    heap = state.cur_heap[:size]
    np.testing.assert_array_equal(cur_where[heap], np.arange(size))
    assert (cal_loc[heap] == IN_HEAP).all()
    seen["heap"] = sorted(zip(state.cur_key[:size].tolist(), order[heap].tolist(), strict=True))
    seen["top"] = float(state.cur_key[0]) if size else np.inf  # (equal times: either body)
    seen["scalars"] = (state.cal_f.tolist(), state.cal_i.tolist(), state.counts.tolist())
    assert sorted(order.tolist()) == list(range(n))
    return seen


@pytest.mark.parametrize("name", NAMES)
def test_renumbering_permutes_every_array_and_maps_every_number(name: str) -> None:
    world = WORLDS[name]()
    world.run(until=world.time + 3.0)
    engine = _engine(world)
    before = _as_caller_sees(engine)
    order_before = engine.order.copy()
    changed = renumber(engine.model, engine.state, engine.order)
    after = _as_caller_sees(engine)
    assert changed == (not np.array_equal(engine.order, order_before))
    assert before.keys() == after.keys()
    for key in before:
        value, again = before[key], after[key]
        if isinstance(value, np.ndarray):
            np.testing.assert_array_equal(again, value, err_msg=key)
        else:
            assert again == value, key
    # bodies now come in the Morton order of their cells (ties: as they were), so a second
    # renumbering changes nothing
    ncell = engine.model.ncell
    cells = np.stack(np.unravel_index(engine.state.cell, tuple(ncell)), axis=1)
    keys = morton_keys(cells)
    assert (np.diff(keys.astype(np.float64)) >= 0).all()
    order_now = engine.order.copy()
    assert not renumber(engine.model, engine.state, engine.order)
    np.testing.assert_array_equal(engine.order, order_now)


@pytest.mark.needs_jit
def test_only_large_engines_renumber() -> None:
    # below RENUMBER_MIN_BODIES every array of a gas stays in the caches (docs/engine.md);
    # above it the bodies are renumbered every RENUMBER_EVENTS_PER_BODY events a body
    small = gas(3, 6, 0.3, seed=1)
    small.prepare()
    assert _engine(small).renumber_every == 0
    large = gas(2, 128, 0.5, seed=1)
    large.prepare()
    assert large.n_bodies >= driver.RENUMBER_MIN_BODIES
    assert _engine(large).renumber_every == driver.RENUMBER_EVENTS_PER_BODY * large.n_bodies
