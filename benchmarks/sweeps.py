"""How ``carom sweep`` scales with Dask workers, and what a task costs beyond its own work.

Three measurements, each in rounds that alternate the number of workers:

1. **Scaling**: the built-in ``eos-2d`` sweep (30 runs of 1000 hard disks, 0.1-1 s each) on a
   local cluster of 1 and of 2 workers. Wall time of the whole sweep (cluster start, kernel
   load, the runs, the table and Parquet; no plots), the sum of the tasks' own wall time, and
   the speed-up 1 worker / 2 workers.
2. **Start-up**: a sweep of one trivial run (``rebound``, one point): the fixed cost of
   starting a local cluster, loading the kernels in its workers and writing the table.
3. **Per-task overhead**: ``rebound`` over 200 points (each run a few milliseconds): (wall
   time - start-up - the tasks' own time) / tasks: what Dask and the table add per point.

Run:  python benchmarks/sweeps.py               (appends to benchmarks/RESULTS.md)
      python benchmarks/sweeps.py --rounds 1 --no-record
Needs the sweep extra: pip install -e '.[sweep]'.
"""

from __future__ import annotations

import argparse
import csv
import shutil
import statistics
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from edmd import record

from carom.sweeps import load_sweep, sweep
from carom.sweeps.spec import SweepSpec


def timed(spec: SweepSpec, workers: int) -> tuple[float, float, int]:
    """Wall time of a sweep [s], the sum of its tasks' own wall time [s], and its runs."""
    folder = Path(tempfile.mkdtemp(prefix="carom-sweep-bench-"))
    try:
        began = time.perf_counter()
        report = sweep(spec, folder / "out", workers=workers, plots=False, progress=False)
        wall = time.perf_counter() - began
        with (folder / "out" / "tasks.csv").open() as handle:
            own = sum(float(row["wall_s"]) for row in csv.DictReader(handle))
        assert report.failed == 0, f"{report.failed} runs failed"
        return wall, own, report.runs
    finally:
        shutil.rmtree(folder, ignore_errors=True)


def many_points(count: int) -> SweepSpec:
    """The rebound sweep over ``count`` restitutions: tasks of a few milliseconds."""
    spec = load_sweep("rebound")
    values = [round(0.05 + 0.95 * k / (count - 1), 12) for k in range(count)]
    return replace(spec, parameters={"world.walls.2": values}, text="")


def one_point() -> SweepSpec:
    spec = load_sweep("rebound")
    return replace(spec, parameters={"world.walls.2": [0.5]}, text="")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--tasks", type=int, default=200, help="points of the overhead sweep")
    parser.add_argument("--no-record", action="store_true", help="do not append to RESULTS.md")
    args = parser.parse_args()

    eos = load_sweep("eos-2d")
    timed(eos, 2)  # kernels compiled and cached before anything is timed
    scaling: dict[int, list[tuple[float, float]]] = {1: [], 2: []}
    startup: list[float] = []
    overhead: list[float] = []
    runs = 0
    for r in range(args.rounds):
        for workers in (1, 2) if r % 2 == 0 else (2, 1):
            wall, own, runs = timed(eos, workers)
            scaling[workers].append((wall, own))
            print(f"eos-2d, {workers} worker(s): {wall:.2f} s (tasks {own:.2f} s)", flush=True)
        start, _, _ = timed(one_point(), 2)
        wall, own, n = timed(many_points(args.tasks), 2)
        startup.append(start)
        overhead.append((wall - start - own / 2) / n)
        print(f"start-up {start:.2f} s; {n} tiny tasks {wall:.2f} s (own {own:.3f} s)", flush=True)

    med = {w: statistics.median(x[0] for x in scaling[w]) for w in scaling}
    own = {w: statistics.median(x[1] for x in scaling[w]) for w in scaling}
    body = "| workers | eos-2d wall time [s] | tasks' own time [s] | speed-up |\n"
    body += "|---|---|---|---|\n"
    for w in (1, 2):
        body += f"| {w} | {med[w]:.2f} | {own[w]:.2f} | {med[1] / med[w]:.2f} |\n"
    body += (
        f"\nStart-up (a one-run sweep on 2 workers): {statistics.median(startup):.2f} s. "
        f"Per-task overhead ({args.tasks} runs of a few ms on 2 workers): "
        f"{1e3 * statistics.median(overhead):.1f} ms per task.\n"
    )
    print(body)
    if not args.no_record:
        record(
            "carom sweep on Dask: 1 and 2 workers",
            body,
            (
                f"eos-2d: {runs} runs of 1000 hard disks; median of {args.rounds} rounds, "
                f"alternating the number of workers",
                "wall time: the whole sweep() call (local cluster started and closed, kernels "
                "loaded in the workers, table and Parquet written, no plots)",
                "per-task overhead: (wall - start-up - tasks' own time / 2 workers) / tasks",
            ),
        )


if __name__ == "__main__":
    main()
