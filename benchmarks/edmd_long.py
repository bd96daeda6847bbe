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
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=7200
    )
    result: dict[str, object] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[100_000, 1_000_000])
    parser.add_argument("--dims", type=int, nargs="+", default=[3, 2])
    parser.add_argument("--events", type=float, default=200.0, help="events a body")
    parser.add_argument("--windows", type=int, default=4)
    parser.add_argument("--rounds", type=int, default=2)
    parser.add_argument("--no-record", action="store_true", help="do not append to RESULTS.md")
    args = parser.parse_args()

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
