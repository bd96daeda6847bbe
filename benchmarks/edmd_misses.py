"""Cache misses an event of the event-driven engine, counted by Valgrind's cache simulator, for
this source tree and another, on the same melted gas: a measure of memory traffic that does
not drift.

Past the caches the engine's cost per collision is mostly waiting on memory, and on a virtual
machine whose speed drifts 10-30% from one process to the next, a layout change worth 5% is
lost in the timings. Valgrind's ``callgrind --cache-sim=yes`` runs the same machine code on a
simulated cache (L1 data and last level, as this machine's by default: 32 KB 8-way and 32 MB
16-way) and counts every access and miss; the same events from the same checkpoint give the
same counts on every run. Software prefetches are not simulated (a prefetched line is counted
as a miss where it is read), so the counts measure traffic, not the latency that prefetching
hides.

A periodic FCC gas of hard spheres of unit diameter (N = 4 cells^3, packing ``--phi``) is
built and melted once (``--melt`` collisions a sphere) and saved, by the other tree if one is
given (the older, as a rule: a newer carom reads an older checkpoint); each tree
then loads it under Valgrind with the instrumentation off, runs a few events (kernels loaded),
and counts ``--events`` events with it on (``callgrind_control -i on``). Both trees run the
same events to the bit (a checkpoint of an older layout is read by the newer tree).

Needs Valgrind (Debian: ``apt-get install valgrind``); about a minute per 10^5 events.
Never in ``make test``.

Run:  git worktree add /tmp/base REV
      python benchmarks/edmd_misses.py --other /tmp/base/src [--cells 40] [--phi 0.3]
            [--events 200000] [--no-record]
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

from edmd import record  # benchmarks/edmd.py, beside this file

HERE = Path(__file__).resolve().parent
SRC = HERE.parent / "src"
#: Valgrind's event names, in the order of its summary line
EVENTS = ("Ir", "Dr", "Dw", "I1mr", "D1mr", "D1mw", "ILmr", "DLmr", "DLmw")

MELT = textwrap.dedent(
    """
    import math, sys
    import numpy as np
    import carom
    cells, phi, melt, path = int(sys.argv[1]), float(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
    a = (4.0 / (6.0 * phi / math.pi)) ** (1.0 / 3.0)  # the FCC cell's side
    base = np.array([[0, 0, 0], [0.5, 0.5, 0], [0.5, 0, 0.5], [0, 0.5, 0.5]])
    grid = np.stack(np.meshgrid(*[np.arange(cells)] * 3, indexing="ij"), -1).reshape(-1, 1, 3)
    x = ((grid + base[None]).reshape(-1, 3) + 0.25) * a
    n = x.shape[0]
    v = np.random.default_rng(1).standard_normal((n, 3))
    v -= v.mean(axis=0)
    v *= math.sqrt(3.0 * (n - 1) / (v * v).sum())
    world = carom.World(3, [cells * a] * 3, "periodic")
    world.add_spheres(x, v, radius=0.5)
    while world.stats.collisions < melt * n / 2:
        world.run(until=world.time + 1.0, log=False)
    world.save(path)
    """
)

COUNT = textwrap.dedent(
    """
    import os, sys, time
    import carom
    path, events, ready, go = sys.argv[1], int(sys.argv[2]), sys.argv[3], sys.argv[4]
    world = carom.World.load(path)
    world.run_events(1000)  # (the engine built, its kernels loaded)
    open(ready, "w").write(str(os.getpid()))
    while not os.path.exists(go):  # (the instrumentation is switched on meanwhile)
        time.sleep(0.05)
    world.stats.reset()
    world.run_events(events)
    print("collisions", world.stats.collisions, flush=True)
    os._exit(0)
    """
)


def count(src: Path, checkpoint: Path, events: int, folder: Path, cache: list[str]) -> dict:
    """Valgrind's counts over ``events`` events of the tree ``src`` from ``checkpoint``."""
    stamp = time.monotonic_ns()
    ready, go = folder / f"ready-{stamp}", folder / f"go-{stamp}"
    out = folder / "callgrind.out"
    env = os.environ | {"PYTHONPATH": str(src)}
    command = [
        "valgrind", "--tool=callgrind", "--instr-atstart=no", "--cache-sim=yes", *cache,
        f"--callgrind-out-file={out}", sys.executable, "-c", COUNT, str(checkpoint),
        str(events), str(ready), str(go),
    ]  # fmt: skip
    with subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True) as run:  # fmt: skip
        while not ready.exists():
            if run.poll() is not None:
                raise SystemExit(f"valgrind stopped before the count:\n{run.stderr.read()}")
            time.sleep(0.5)
        # (returns once the process has taken the command: it polls for `go` meanwhile)
        subprocess.run(["callgrind_control", "-i", "on", ready.read_text()], check=True,
                       capture_output=True)  # fmt: skip
        go.touch()
        stdout, stderr = run.communicate()
    collected = [line for line in stderr.splitlines() if "Collected :" in line]
    if run.returncode != 0 or not collected:
        raise SystemExit(f"valgrind failed ({run.returncode}):\n{stderr[-2000:]}")
    values = [int(v) for v in collected[-1].split(":", 1)[1].split()]
    counts = dict(zip(EVENTS, values, strict=True))
    counts["collisions"] = int(stdout.split()[-1])
    return counts


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--other", type=Path, help="another tree's src/ directory")
    parser.add_argument("--cells", type=int, default=40)
    parser.add_argument("--phi", type=float, default=0.3)
    parser.add_argument("--melt", type=float, default=20.0)
    parser.add_argument("--events", type=int, default=200_000)
    parser.add_argument("--d1", default="32768,8,64", help="L1 data cache: bytes,ways,line")
    parser.add_argument("--ll", default="33554432,16,64", help="last level: bytes,ways,line")
    parser.add_argument("--no-record", action="store_true")
    args = parser.parse_args()
    cache = [f"--D1={args.d1}", f"--LL={args.ll}"]
    trees = [("this", SRC)] + ([("other", args.other)] if args.other is not None else [])
    n = 4 * args.cells**3
    lines = [
        "| tree | instructions / event | L1 misses / event | last-level misses / event | "
        "collisions |",
        "|---|---|---|---|---|",
    ]
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        checkpoint = folder / "melted.npz"
        # melted and saved by the other tree when there is one: a newer carom reads an older
        # checkpoint, not the other way round
        env = os.environ | {"PYTHONPATH": str(trees[-1][1])}
        subprocess.run(
            [sys.executable, "-c", MELT, str(args.cells), str(args.phi), str(args.melt),
             str(checkpoint)],
            check=True, env=env,
        )  # fmt: skip
        for name, src in trees:
            c = count(src, checkpoint, args.events, folder, cache)
            line = (
                f"| {name} ({src}) | {c['Ir'] / args.events:.0f} | "
                f"{(c['D1mr'] + c['D1mw']) / args.events:.2f} | "
                f"{(c['DLmr'] + c['DLmw']) / args.events:.2f} | {c['collisions']} |"
            )
            print(line, flush=True)
            lines.append(line)
    body = "\n".join(
        [
            f"Valgrind's cache simulator ({' '.join(cache)}), {args.events} events of N = {n} "
            f"hard spheres at phi = {args.phi}, melted {args.melt:g} collisions a sphere:",
            "",
            *lines,
        ]
    )
    if not args.no_record:
        record("edmd_misses: cache misses an event, simulated", body + "\n")


if __name__ == "__main__":
    main()
