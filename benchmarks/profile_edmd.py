"""Where the event loop spends its time, in CPU cycles, phase by phase.

Wall-clock timings on shared machines vary by about 15% run to run, and perf cannot see into
Numba's JIT code. This tool builds a copy of ``carom.engines.edmd.loop.run_frames`` with the
CPU's cycle counter (LLVM ``readcyclecounter``) read around each phase, runs it on a melted
hard-sphere gas, and prints nanoseconds per collision for: processing a pair event (advance
both bodies, apply the impulse), a shell event (advance, rebuild the neighbour list),
predictions, calendar updates, and the rest. It is a development tool; its figures are not
recorded in RESULTS.md.

Run:  python benchmarks/profile_edmd.py [--sizes 1000 10000 100000] [--dim 3] [--packing 0.3]
      python benchmarks/profile_edmd.py --checkpoints melted.npz   (a saved gas, as it is)
"""

from __future__ import annotations

import argparse
import inspect
import time
from pathlib import Path
from typing import Any

import llvmlite.ir as llvm_ir
import numpy as np
from numba import njit, types
from numba.core import cgutils
from numba.extending import intrinsic

from carom import World
from carom.engines.edmd import codes, loop, neighbours
from carom.scene import layouts


@intrinsic
def _cycles(typingctx: Any) -> Any:
    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        fnty = llvm_ir.FunctionType(llvm_ir.IntType(64), [])
        fn = cgutils.get_or_insert_function(builder.module, fnty, "llvm.readcyclecounter")
        return builder.call(fn, [])

    return types.int64(), codegen


@njit
def cycles() -> int:
    return _cycles()  # type: ignore[no-any-return]


# Text anchors in loop.run_frames where counters go; if it changes, these say so loudly.
ANCHORS = {
    "        kind = ev_kind[i]\n        j = -1": (
        "        c0 = _cycles()\n        kind = ev_kind[i]\n        j = -1"
    ),
    "        # re-schedule the bodies whose motion changed": (
        "        c1 = _cycles()\n"
        "        if kind == EV_SHELL:\n            cyc[1] += c1 - c0\n"
        "        elif j >= 0:\n            cyc[0] += c1 - c0\n"
        "        else:\n            cyc[2] += c1 - c0\n"
        "        # re-schedule the bodies whose motion changed"
    ),
    "            calendar_update(ev_time, body, cal)": (
        "            c2 = _cycles()\n"
        "            calendar_update(ev_time, body, cal)\n"
        "            c3 = _cycles()\n            cyc[3] += c2 - c1\n            cyc[4] += c3 - c2\n"
        "            c1 = c3"
    ),
    "        i = calendar_top(ev_time, cal)": (
        "        c4 = _cycles()\n        i = calendar_top(ev_time, cal)"
    ),
    "        T = ev_time[i] if i >= 0 else INF\n": (
        "        T = ev_time[i] if i >= 0 else INF\n        cyc[4] += _cycles() - c4\n"
    ),
}


def instrumented_run() -> Any:
    """``loop.run_frames`` with cycle counters added at the anchors, compiled fresh; it takes
    ``(handle, t_stop, max_events, log_on, cyc)`` and samples no frame."""
    source = inspect.getsource(loop.run_frames.py_func)
    source = source.split("\n", 1)[1]  # drop the decorator
    head, body = source.split(") -> int:\n", 1)
    if not head.startswith("def run_frames("):
        raise SystemExit("loop.run_frames changed: its signature; update instrumented_run")
    source = (
        "def run_prof(h, times, max_events, log_on, sample, done, t_out, x_out, v_out,"
        " orient_out, w_out, cyc):\n" + body
    )
    for anchor, replacement in ANCHORS.items():
        if anchor not in source:
            raise SystemExit(f"run_frames changed: anchor not found: {anchor!r}; update ANCHORS")
        source = source.replace(anchor, replacement)
    namespace: dict[str, Any] = {
        **vars(loop),
        "_cycles": _cycles,
        "EV_SHELL": codes.EV_SHELL,
        "rebuild_shell": neighbours.rebuild_shell,
    }
    exec(compile(source, "<instrumented run_frames>", "exec"), namespace)
    loop_prof = njit(error_model="numpy")(namespace["run_prof"])
    done = np.zeros(1, np.int64)
    times, none = np.zeros(1), np.zeros((1, 1, 3))

    def run_prof(h: Any, t_stop: float, max_events: int, log_on: bool, cyc: Any) -> Any:
        times[0], done[0] = t_stop, 0
        return loop_prof(
            h,
            times,
            max_events,
            log_on,
            False,
            done,
            times,
            none,
            none,
            none,
            none,
            cyc,
        )

    return run_prof


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1_000, 10_000, 100_000])
    parser.add_argument("--dim", type=int, default=3)
    parser.add_argument("--packing", type=float, default=0.3)
    parser.add_argument(
        "--checkpoints", type=Path, nargs="+", default=[], help="saved gases, instead of --sizes"
    )
    args = parser.parse_args()
    run_prof = instrumented_run()
    cycles()
    names = [
        "pair event (advance, impulse)",
        "shell event (advance, rebuild)",
        "wall or stale event",
        "predictions",
        "event calendar",
    ]
    worlds = [lambda path=path: World.load(path) for path in args.checkpoints] or [
        lambda n=n: layouts.lattice_gas(args.dim, round(n ** (1 / args.dim)), args.packing, seed=1)
        for n in args.sizes
    ]
    for make in worlds:
        world = make()
        world.run(until=world.time + 0.3, log=False)
        n = world.n_bodies
        engine = world.build()
        state = engine.state
        counters = np.zeros(8, np.int64)
        run_prof(engine.handle, state.clock[0] + 0.01, 10**12, False, counters)  # compile
        counters[:] = 0
        before = state.counts.copy()
        start_wall, start = time.perf_counter(), cycles()
        run_prof(
            engine.handle, state.clock[0] + (1.0 if n < 50_000 else 0.3), 10**12, False, counters
        )
        total, wall = cycles() - start, time.perf_counter() - start_wall
        collisions = int(state.counts[codes.C_PAIR] - before[codes.C_PAIR])
        ns = wall / total * 1e9
        print(
            f"N = {world.n_bodies:,}: {collisions / wall:.3g} collisions/s, "
            f"{total * ns / collisions:.0f} ns per collision"
        )
        for k, name in enumerate(names):
            print(f"   {name:32s} {counters[k] * ns / collisions:7.0f} ns")
        rest = total - int(counters[:5].sum())
        print(f"   {'the rest (loop)':32s} {rest * ns / collisions:7.0f} ns")


if __name__ == "__main__":
    main()
