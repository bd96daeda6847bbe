"""Interleaved A/B of an engine: this tree against another carom source tree.

Each round measures both trees in fresh processes, one after the other (the order alternates
from round to round), so that the machine's drift over minutes falls on both alike; with
``--concurrent``, at the same time, each pinned to its own core (swapped from round to round),
so that both see the same seconds of a noisy virtual machine (on this VM class the ratio's
spread fell from +-40% to +-5% this way). The
workload is benchmarks/edmd.py's: a periodic lattice gas (3D packing 0.3, 2D 0.5), melted,
then timed for about 3e5 collisions, best of ``--repeats``. Only API that every carom since
the first engine has is used, so any two commits can be compared.

``--workload rigid`` measures the time-stepped rigid engines instead: the built-in scenes
``pyramid`` (2D) and ``pyramid-3d`` (or ``--scenes``), built, their kernels loaded, then
stepped for a simulated second (60 steps), best of ``--repeats``, in steps per second;
``--dims`` picks the scenes.

``--workload melted`` times the gas where the large-N costs show: a periodic FCC gas of hard
spheres at packing 0.3 and N about ``--sizes`` (4 cells^3), melted 10 collisions a sphere by
the other tree (benchmarks/edmd_misses.py's gas) and saved; each measurement loads it, runs
20000 events, then times ``--events`` events, best of ``--repeats``. Both trees run the same
events to the bit.

Run:  git worktree add /tmp/base REV     (or: git archive REV | tar -x -C /tmp/base)
      python benchmarks/ab.py /tmp/base/src --rounds 3 --sizes 1000 10000
      python benchmarks/ab.py /tmp/base/src --workload rigid --rounds 5 --concurrent
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

from edmd import commit, machine  # benchmarks/edmd.py, beside this file
from edmd_misses import MELT

HERE = Path(__file__).resolve().parent
SRC = HERE.parent / "src"

SNIPPET = """
import json, sys, time
try:
    from carom.scene.layouts import lattice_gas
except ImportError:
    from carom.generators import lattice_gas
dim, n, repeats = int(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3])
packing = 0.3 if dim == 3 else 0.5
world = lattice_gas(dim, round(n ** (1 / dim)), packing, seed=1)
world.run(until=0.3, log=False)
world.stats.reset()
world.run(until=world.time + 0.5, log=False)
span = max(300_000, 2 * world.n_bodies) / (max(world.stats.collisions, 1) / 0.5)
best = 0.0
for _ in range(repeats):
    world.stats.reset()
    start = time.perf_counter()
    world.run(until=world.time + span, log=False)
    best = max(best, world.stats.collisions / (time.perf_counter() - start))
print(json.dumps({"collisions_per_s": best, "n": world.n_bodies}))
"""


RIGID = """
import json, sys, time
from carom.scene import find_scene, load_scene
dim, repeats, name = int(sys.argv[1]), int(sys.argv[3]), sys.argv[4]
best = 0.0
for _ in range(repeats):
    world = load_scene(find_scene(name)).build()
    world.prepare()
    start = time.perf_counter()
    world.run(until=1.0)
    best = max(best, world.counters()[0] / (time.perf_counter() - start))
print(json.dumps({"collisions_per_s": best, "n": world.n_bodies}))
"""
MELTED = """
import json, sys, time
import carom
repeats, path, events = int(sys.argv[3]), sys.argv[4], int(sys.argv[5])
world = carom.World.load(path)
world.run_events(20_000)  # (the engine built, its kernels loaded, the caches warm)
best = 0.0
for _ in range(repeats):
    world.stats.reset()
    start = time.perf_counter()
    world.run_events(events)
    best = max(best, world.stats.collisions / (time.perf_counter() - start))
print(json.dumps({"collisions_per_s": best, "n": world.n_bodies}))
"""
#: what is timed: the event-driven gas (collisions/s), the same from a melted checkpoint, or
#: the rigid pyramids (steps/s)
WORKLOADS = {"edmd": SNIPPET, "melted": MELTED, "rigid": RIGID}
#: the melted workload's checkpoint for each N, and events timed a repeat (``--events``)
CHECKPOINTS: dict[int, Path] = {}
EVENTS = [1_000_000]
WORKLOAD = ["edmd"]
#: the rigid workload's scene in 2D and in 3D (``--scenes``)
SCENES = {2: "pyramid", 3: "pyramid-3d"}


def _start(src: Path, dim: int, n: int, repeats: int, cpu: int | None) -> subprocess.Popen[str]:
    pin = ["taskset", "-c", str(cpu)] if cpu is not None else []
    snippet = WORKLOADS[WORKLOAD[0]]
    return subprocess.Popen(
        [*pin, sys.executable, "-c", snippet, str(dim), str(n), str(repeats)]
        + ([str(CHECKPOINTS[n]), str(EVENTS[0])] if n in CHECKPOINTS else [SCENES[dim]]),
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONPATH": str(src)},
    )


def _rate(proc: subprocess.Popen[str]) -> float:
    out, _ = proc.communicate()
    if proc.returncode:
        raise SystemExit(f"a measurement failed (exit code {proc.returncode})")
    return float(json.loads(out.strip().splitlines()[-1])["collisions_per_s"])


def measure(src: Path, dim: int, n: int, repeats: int) -> float:
    """Collisions per second of the tree at ``src``, alone."""
    return _rate(_start(src, dim, n, repeats, None))


def measure_together(
    trees: list[tuple[str, Path]], dim: int, n: int, repeats: int
) -> dict[str, float]:
    """Both trees at once, the first on core 0 and the second on core 1."""
    procs = [(name, _start(src, dim, n, repeats, cpu)) for cpu, (name, src) in enumerate(trees)]
    return {name: _rate(proc) for name, proc in procs}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("other", type=Path, help="the other tree's src/ directory")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--sizes", type=int, nargs="+", default=[1_000, 10_000])
    parser.add_argument("--dims", type=int, nargs="+", default=[3, 2])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument(
        "--concurrent", action="store_true", help="both trees at once, one per core (pinned)"
    )
    parser.add_argument("--record", action="store_true", help="append to benchmarks/RESULTS.md")
    parser.add_argument("--workload", choices=sorted(WORKLOADS), default="edmd")
    parser.add_argument("--events", type=int, default=EVENTS[0], help="melted: events timed")
    parser.add_argument(
        "--scenes", nargs=2, metavar=("SCENE_2D", "SCENE_3D"), help="the rigid workload's scenes"
    )
    args = parser.parse_args()
    WORKLOAD[0] = args.workload
    if args.scenes:
        SCENES.update({2: args.scenes[0], 3: args.scenes[1]})
    if args.workload == "rigid":
        args.sizes = [1]  # the scene is the size
    if args.workload == "melted":
        args.dims = [3]
        EVENTS[0] = args.events
        args.sizes = [4 * round((n / 4) ** (1 / 3)) ** 3 for n in args.sizes]
        folder = Path(tempfile.mkdtemp(prefix="carom-ab-"))
        for n in args.sizes:
            CHECKPOINTS[n] = folder / f"melted-{n}.npz"
            cells = str(round((n / 4) ** (1 / 3)))
            subprocess.run(
                [sys.executable, "-c", MELT, cells, "0.3", "10", str(CHECKPOINTS[n])],
                check=True,
                env={**os.environ, "PYTHONPATH": str(args.other)},
            )
    for src in (SRC, args.other):  # compile (or load) each tree's kernels before timing
        if args.workload != "melted":
            measure(src, 3, 1000, 1)
            measure(src, 2, 1000, 1)
    rows = []
    for r in range(args.rounds):
        what = "steps" if args.workload == "rigid" else "collisions"
        for dim in args.dims:
            for n in args.sizes:
                order = [("this", SRC), ("other", args.other)]
                if r % 2:
                    order.reverse()
                if args.concurrent:
                    got = measure_together(order, dim, n, args.repeats)
                else:
                    got = {name: measure(src, dim, n, args.repeats) for name, src in order}
                ratio = got["this"] / got["other"]
                rows.append((r + 1, dim, n, got["this"], got["other"], ratio))
                print(
                    f"round {r + 1}, {dim}D, N = {n}: this {got['this']:.3g}, other "
                    f"{got['other']:.3g} {what}/s, "
                    f"ratio {ratio:.3f}",
                    flush=True,
                )
    summary = []
    for dim in args.dims:
        for n in args.sizes:
            ratios = sorted(q for _, d, m, _, _, q in rows if (d, m) == (dim, n))
            median = statistics.median(ratios)
            summary.append((dim, n, median, ratios[0], ratios[-1]))
            print(
                f"{dim}D, N = {n}: median this / other {median:.3f} "
                f"(from {ratios[0]:.3f} to {ratios[-1]:.3f} over {len(ratios)} rounds)"
            )
    if args.record:
        unit = "steps/s" if args.workload == "rigid" else "coll/s"
        stamp = dt.datetime.now(dt.UTC).strftime("%Y-%m-%d %H:%M UTC")
        lines = [
            f"\n## {args.workload} interleaved A/B, {stamp}\n",
            f"- command: `python benchmarks/ab.py {args.other} --workload {args.workload} "
            f"--rounds {args.rounds} "
            f"{'--concurrent ' if args.concurrent else ''}"
            f"--sizes {' '.join(map(str, args.sizes))} --dims {' '.join(map(str, args.dims))}`",
            f"- machine: {machine()}",
            f"- this: {SRC} at {commit()} (and any uncommitted change); other: {args.other}\n",
            f"| round | dim | N | this [{unit}] | other [{unit}] | this / other |",
            "|---|---|---|---|---|---|",
        ]
        lines += [
            f"| {r} | {d} | {n:,} | {a:.3g} | {b:.3g} | {q:.3f} |" for r, d, n, a, b, q in rows
        ]
        lines += ["", "| dim | N | median this / other | lowest | highest |"]
        lines += ["|---|---|---|---|---|"]
        lines += [f"| {d} | {n:,} | {m:.3f} | {a:.3f} | {b:.3f} |" for d, n, m, a, b in summary]
        with (HERE / "RESULTS.md").open("a") as handle:
            handle.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    main()
