"""The event loop (carom.engines.edmd.loop.run_frames, through the engine's handle) and its
driver, tested directly: why it returns, the clock, the log buffer emptied whenever it fills,
and events in time order."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from numba import njit

from carom.engines.base import FrameArrays
from carom.engines.edmd import codes, driver, lookahead, loop
from carom.engines.edmd.loop import run_frames
from carom.engines.edmd.state import KIN_V, KIN_WIDTH
from carom.scene.layouts import lattice_gas
from tests.processes import fresh_python


def run(engine: driver.EdmdEngine, t_stop: float, max_events: int, log_on: bool) -> int:
    """One call of the loop, up to ``t_stop``, sampling nothing; its status."""
    none = FrameArrays.empty(1, 1, 3)
    done = np.zeros(1, dtype=np.int64)
    times = np.array([t_stop])
    return int(run_frames(engine.handle, times, max_events, log_on, False, done, *none))


def test_it_stops_after_max_events_and_at_t_stop() -> None:
    world = lattice_gas(3, 5, 0.3, seed=1)
    engine = world.build()
    assert run(engine, np.inf, 7, False) == codes.MAX_EVENTS
    assert engine.counters().events == 7
    t = engine.time
    assert run(engine, t + 0.25, 10**9, False) == codes.DONE
    assert engine.time == t + 0.25  # the clock reads t_stop exactly, whatever the last event


def test_a_full_log_buffer_returns_and_the_driver_empties_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    def collisions(capacity: int) -> np.ndarray:
        monkeypatch.setattr(driver, "LOG_CAPACITY", capacity)
        world = lattice_gas(2, 8, 0.4, seed=2)
        world.run(until=3.0, log=True)
        assert world.engine is not None
        assert world.engine.state.log_time.shape == (capacity,)
        return world.collisions

    small, roomy = collisions(4), collisions(1 << 16)
    assert len(roomy) > 100  # the small buffer filled dozens of times
    assert small.tobytes() == roomy.tobytes()  # and nothing was lost or reordered
    assert np.all(np.diff(roomy["time"]) >= 0.0)  # processed in time order


def test_a_full_buffer_is_reported_by_the_loop() -> None:
    world = lattice_gas(2, 8, 0.4, seed=2)
    engine = world.build()
    engine.state = engine.state._replace(
        log_time=np.zeros(2),
        log_a=np.zeros(2, np.int64),
        log_b=np.zeros(2, np.int64),
        log_impulse=np.zeros((2, 3)),
        log_un=np.zeros((2, 2)),
        log_point=np.zeros((2, 3)),
        log_normal=np.zeros((2, 3)),
    )
    assert run(engine, 10.0, 10**9, True) == codes.LOG_FULL
    assert int(engine.state.log_n[0]) == 2


def test_stale_predictions_are_counted_not_processed() -> None:
    # a dense gas: many predicted partners collide with someone else first
    world = lattice_gas(3, 6, 0.4, seed=3)
    world.run(until=2.0)
    assert world.engine is not None
    counts = world.engine.state.counts
    assert counts[codes.C_STALE] > 0
    processed = counts[codes.C_PAIR] + counts[codes.C_WALL] + counts[codes.C_SHELL]
    assert counts[codes.C_EVENTS] == processed + counts[codes.C_STALE]


LOOKAHEAD_RUN = """
import json, os
from carom.engines.edmd import loop
# prefetch the next events' data at every size (read at compile time), every level a step
# ahead (deep) or only the next events' rows
loop.LOOKAHEAD_BODIES = 0
loop.DEEP_LOOKAHEAD_BODIES = 0 if os.environ["DEPTH"] == "deep" else 1 << 40
from carom.scene.layouts import lattice_gas
dim = int(os.environ["DIM"])
world = lattice_gas(dim, 6 if dim == 3 else 15, 0.3 if dim == 3 else 0.5, seed=4)
world.run(until=3.0, log=False)
print(json.dumps({"positions": world.positions.tolist(), "velocities": world.velocities.tolist(),
                  "compiled": sum(loop.run_frames.stats.cache_misses.values())}))
"""


@pytest.mark.needs_jit
@pytest.mark.parametrize(("dim", "depth"), [(3, "deep"), (3, "rows"), (2, "deep")])
def test_prefetching_the_next_events_changes_no_bit(tmp_path: Path, dim: int, depth: str) -> None:
    # Above LOOKAHEAD_BODIES the loop asks for the likely next events' data ahead, and above
    # DEEP_LOOKAHEAD_BODIES for each level of it a step ahead (carom.engines.edmd.lookahead).
    # A prefetch reads nothing into the computation, so a loop compiled to do either at every
    # size (in a fresh process with an empty kernel cache) must give this process's bits,
    # where 216 spheres or 225 disks are below both thresholds.
    world = lattice_gas(dim, 6 if dim == 3 else 15, 0.3 if dim == 3 else 0.5, seed=4)
    assert world.n_bodies < loop.LOOKAHEAD_BODIES
    # its own cache: it compiles everything itself, with its setting
    ahead = fresh_python(LOOKAHEAD_RUN, DIM=str(dim), DEPTH=depth, NUMBA_CACHE_DIR=str(tmp_path))
    assert ahead["compiled"] == 1  # its own loop, not this one's from a cache
    world.run(until=3.0, log=False)
    np.testing.assert_array_equal(np.array(ahead["positions"]), world.positions)
    np.testing.assert_array_equal(np.array(ahead["velocities"]), world.velocities)


@njit
def _cell_coordinate(kin, dt, box, periodic, cell_size, ncell):  # type: ignore[no-untyped-def]
    return lookahead._cell_coordinate(kin, 0, 0, dt, box, periodic, cell_size, ncell)


@pytest.mark.parametrize("periodic", [False, True])
def test_the_cells_asked_for_are_on_the_grid_whatever_the_motion(periodic: bool) -> None:
    # The deep lookahead reads the counts and rows of the cells around where a body will be
    # (lookahead.ask_for_cells), extrapolated from its record: the coordinate must name a
    # cell of the grid whatever the record holds, even motion no engine state holds.
    kin = np.zeros((1, KIN_WIDTH))
    box, ncell = np.full(3, 10.0), np.full(3, 5)
    cell_size = box / ncell  # 2 m cells
    for x0, v0, dt in [
        (3.0, 1.0, 0.5),  # at 3.5 m: cell 1
        (3.0, math.nan, 1.0),
        (3.0, math.inf, 1.0),
        (3.0, -math.inf, 1.0),
        (3.0, 1e308, 1e10),
        (-50.0, 0.0, 0.0),
        (50.0, 0.0, 0.0),
    ]:
        kin[0, 0], kin[0, KIN_V] = x0, v0
        with np.errstate(all="ignore"):  # (without the JIT: NumPy scalars, which warn)
            c = _cell_coordinate(kin, dt, box, periodic, cell_size, ncell)
        assert 0 <= c < 5, (x0, v0, dt)
    kin[0, 0], kin[0, KIN_V] = 3.0, 1.0
    assert _cell_coordinate(kin, 0.5, box, periodic, cell_size, ncell) == 1
    assert _cell_coordinate(kin, 8.0, box, periodic, cell_size, ncell) == (0 if periodic else 4)
