"""Long runs of the event-driven engine: cost per collision as bodies diffuse, with the
bodies renumbered along the Morton curve as the run goes and without (issue 16, item 1: keep
bodies near in space near in memory during the run, not only at the start).

The engine numbers bodies along a Morton curve when it is built; as a gas runs, bodies
diffuse away from the neighbours they started with. Each arm runs the lattice gas of
benchmarks/edmd.py (3D packing 0.3, 2D 0.5) in a fresh process, melts it, then runs
``--events`` events a body in ``--windows`` equal spans of time and reports the microseconds
per collision in each span. ``fixed`` turns renumbering off (the numbering of the build is
kept); ``renumbered`` is the engine as it is. The arms alternate, ``--rounds`` times; both
process the same events (renumbering changes no bit), so the ratio of their times is the gain.

Run:  python benchmarks/edmd_long.py                       (appends to benchmarks/RESULTS.md)
      python benchmarks/edmd_long.py --sizes 100000 --dims 3 --events 100 --no-record
"""

from __future__ import annotations

import argparse
import json
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from edmd import record

ARMS = ("fixed", "renumbered")

CHILD = """
import json, resource, sys, time
sys.path.insert(0, {here!r})
from edmd import lattice_gas
import carom.engines.edmd.driver as driver
if {arm!r} == "fixed":
    driver.RENUMBER_MIN_BODIES = 1 << 62  # the build's numbering kept
warm = lattice_gas({dim}, 64, {packing})
warm.run(until=0.1, log=False)  # kernels loaded (or compiled), not timed
world = lattice_gas({dim}, {n}, {packing})
world.run(until=0.3, log=False)  # melted: about 3 collisions a body
# the span of time that holds `events` events a body, from a short probe
start = world.engine.state.counts[0]
world.run(until=world.time + 0.2, log=False)
rate = (world.engine.state.counts[0] - start) / 0.2
span = {events} * world.n_bodies / rate / {windows}
windows = []
for _ in range({windows}):
    before = world.stats.collisions
    began = time.perf_counter()
    world.run(until=world.time + span, log=False)
    seconds = time.perf_counter() - began
    windows.append(seconds / (world.stats.collisions - before) * 1e6)
counts = world.engine.state.counts
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
print(json.dumps(dict(
    n=world.n_bodies, windows=windows, events=int(counts[0]), collisions=int(counts[1]),
    peak=peak,
)))
"""


DRIFT = """
import sys
sys.path.insert(0, {here!r})
from edmd import lattice_gas
import carom.engines.edmd.driver as driver
driver.RENUMBER_MIN_BODIES = 1 << 62  # the build's numbering kept while the bodies drift
world = lattice_gas({dim}, {n}, {packing})
world.run(until=0.3, log=False)
start = world.engine.state.counts[0]
world.run(until=world.time + 0.2, log=False)
rate = (world.engine.state.counts[0] - start) / 0.2
world.run(until=world.time + {events} * world.n_bodies / rate, log=False)
world.save({path!r})
print(rate, world.n_bodies)
"""

PROBE = """
import json, resource, sys, time
sys.path.insert(0, {here!r})
from edmd import lattice_gas
import carom
import carom.engines.edmd.driver as driver
from carom.engines.edmd.renumber import renumber
# the kernels loaded (or compiled), renumbering's too: a small gas renumbered every N events
driver.RENUMBER_MIN_BODIES, driver.RENUMBER_EVENTS_PER_BODY = 0, 1
warm = lattice_gas({dim}, 64, {packing})
warm.run(until=1.0, log=False)
driver.RENUMBER_MIN_BODIES = 1 << 62  # no renumbering while timed
world = carom.World.load({path!r})
world.prepare()
engine = world.engine
renumbering = 0.0
if {arm!r} == "renumbered":
    began = time.perf_counter()
    renumber(engine.model, engine.state, engine.order)
    renumbering = time.perf_counter() - began
before = world.stats.collisions
began = time.perf_counter()
world.run(until=world.time + {span}, log=False)
seconds = time.perf_counter() - began
print(json.dumps(dict(us=seconds / (world.stats.collisions - before) * 1e6,
                      collisions=world.stats.collisions - before, renumbering=renumbering,
                      peak=resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024)))
"""


def _child(code: str) -> str:
    """The last line a fresh Python process running ``code`` prints."""
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=7200
    )
    return done.stdout.strip().splitlines()[-1]


def drifted(dim: int, n: int, events: float, probe: float, rounds: int, path: Path) -> str:
    """Run a gas ``events`` events a body with the build's numbering, save it, then time
    ``probe`` events a body from the checkpoint with that numbering (``fixed``) and with the
    bodies renumbered first (``renumbered``), arms alternating: a table row."""
    packing = 0.3 if dim == 3 else 0.5
    here = str(Path(__file__).resolve().parent)
    code = DRIFT.format(here=here, dim=dim, n=n, packing=packing, events=events, path=str(path))
    rate_text, bodies = _child(code).split()
    n, rate = int(bodies), float(rate_text)
    span = probe * n / rate
    runs: dict[str, list[dict[str, float]]] = {arm: [] for arm in ARMS}
    for _ in range(rounds):
        for arm in ARMS:
            code = PROBE.format(here=here, dim=dim, packing=packing, path=str(path), arm=arm,
                                span=span)  # fmt: skip
            runs[arm].append(json.loads(_child(code)))
    times = {arm: [r["us"] for r in runs[arm]] for arm in ARMS}
    fixed, again = statistics.median(times["fixed"]), statistics.median(times["renumbered"])
    renumbering = statistics.median(r["renumbering"] for r in runs["renumbered"])
    return (
        f"| {dim} | {n:,} | {events:.0f} | {probe:.0f} | "
        f"{', '.join(f'{t:.2f}' for t in times['fixed'])} | "
        f"{', '.join(f'{t:.2f}' for t in times['renumbered'])} | {fixed / again:.3f} | "
        f"{renumbering:.2f} | {max(r['peak'] for r in runs['fixed']):.0f} | "
        f"{max(r['peak'] for r in runs['renumbered']):.0f} |"
    )


def measure(arm: str, dim: int, n: int, events: float, windows: int) -> dict[str, object]:
    packing = 0.3 if dim == 3 else 0.5
    code = CHILD.format(
        here=str(Path(__file__).resolve().parent),
        arm=arm,
        dim=dim,
        n=n,
        packing=packing,
        events=events,
        windows=windows,
    )
    result: dict[str, object] = json.loads(_child(code))
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100_000, 1_000_000])
    parser.add_argument("--dims", type=int, nargs="+", default=[3, 2])
    parser.add_argument("--events", type=float, default=200.0, help="events a body")
    parser.add_argument("--windows", type=int, default=4)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--no-record", action="store_true", help="do not append to RESULTS.md")
    parser.add_argument(
        "--drifted",
        type=float,
        metavar="PROBE",
        help="instead: drift --events a body, then time PROBE events a body from there, "
        "with the drifted numbering and renumbered, arms alternating --rounds times",
    )
    args = parser.parse_args()
    if args.drifted is not None:
        rows = [
            "| dim | N | events a body drifted | events a body timed | fixed [µs/coll] | "
            "renumbered [µs/coll] | fixed / renumbered (medians) | one renumbering [s] | "
            "peak, fixed [MB] | peak, renumbered [MB] |",
            "|---|---|---|---|---|---|---|---|---|---|",
        ]
        with tempfile.TemporaryDirectory() as tmp:
            for dim in args.dims:
                for n in args.sizes:
                    row = drifted(dim, n, args.events, args.drifted, args.rounds,
                                  Path(tmp) / "drifted.npz")  # fmt: skip
                    print(row, flush=True)
                    rows.append(row)
        if not args.no_record:
            record(
                "Long runs: a drifted numbering against the same bodies renumbered",
                "\n".join(rows) + "\n",
                (
                    "each timing a fresh process loading the same checkpoint; arms alternating; "
                    "no renumbering while timed",
                ),
            )
        return

    measure("renumbered", args.dims[0], 1_000, 1.0, 1)  # compiles the kernels if need be
    lines = [
        "| dim | N | events a body | arm | µs per collision, span by span (medians) | "
        "whole run [µs/coll] | fixed / renumbered | peak [MB] |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for dim in args.dims:
        for n in args.sizes:
            runs: dict[str, list[dict[str, object]]] = {arm: [] for arm in ARMS}
            for _ in range(args.rounds):
                for arm in ARMS:
                    runs[arm].append(measure(arm, dim, n, args.events, args.windows))
            assert runs["fixed"][0]["collisions"] == runs["renumbered"][0]["collisions"]
            whole = {
                arm: statistics.median(
                    statistics.fmean(r["windows"])
                    for r in runs[arm]  # type: ignore[arg-type]
                )
                for arm in ARMS
            }
            for arm in ARMS:
                spans = [
                    statistics.median(r["windows"][k] for r in runs[arm])  # type: ignore[index]
                    for k in range(args.windows)
                ]
                r0 = runs[arm][0]
                ratio = f"{whole['fixed'] / whole['renumbered']:.3f}" if arm == ARMS[1] else ""
                row = (
                    f"| {dim} | {int(r0['n']):,} | {int(r0['events']) / int(r0['n']):.0f} | "  # type: ignore[call-overload]
                    f"{arm} | {', '.join(f'{s:.2f}' for s in spans)} | {whole[arm]:.2f} | "
                    f"{ratio} | {max(float(r['peak']) for r in runs[arm]):.0f} |"  # type: ignore[arg-type]
                )
                print(row, flush=True)
                lines.append(row)
    body = "\n".join(lines) + "\n"
    if not args.no_record:
        record(
            "Long runs: renumbering bodies as they diffuse",
            body,
            (
                f"{args.rounds} rounds, arms alternating, each a fresh process; "
                f"{args.windows} spans of equal time after melting",
            ),
        )


if __name__ == "__main__":
    main()
