"""The event loop (carom.engines.edmd.loop.run_frames, through the engine's handle) and its
driver, tested directly: why it returns, the clock, the log buffer emptied whenever it fills,
and events in time order."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from carom.engines.base import FrameArrays
from carom.engines.edmd import codes, driver, loop
from carom.engines.edmd.loop import run_frames
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
