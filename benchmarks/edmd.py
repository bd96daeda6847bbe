"""Benchmark of the event-driven engine: collisions per second against system size.

Hard spheres at packing fraction 0.3 (3D) and hard disks at 0.5 (2D), periodic, unit
diameter and mass, T = 1, started on a lattice and melted before timing. For each size:
collisions/s and events/s on one core (the engine is single-threaded), the time per collision
relative to the smallest size (log N growth would be 1 + log(N/N0)/log(N0) at most), the
engine's memory per particle (every array of the model and state, the fixed-size event log
excluded), and the process's peak resident memory so far (the sizes run in order, in one
process). The first-call compile time is measured apart, in fresh processes: with an empty
kernel cache, and loading from the cache.

Run:  python benchmarks/edmd.py                   (all sizes, appends to benchmarks/RESULTS.md)
      python benchmarks/edmd.py --sizes 1000 10000 --no-record
"""

from __future__ import annotations

import argparse
import datetime as dt
import math
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

import carom
from carom.scene import layouts

HERE = Path(__file__).resolve().parent
RESULTS = HERE / "RESULTS.md"
TARGET = 7e5  # collisions/s per core at N = 1e4 in 3D (issue: exact engine)


def lattice_gas(dim: int, n: int, packing: float, seed: int = 1) -> carom.World:
    """About ``n`` spheres (the nearest lattice size) of unit diameter at ``packing``."""
    return layouts.lattice_gas(dim, round(n ** (1 / dim)), packing, seed=seed)


def memory_per_particle(world: carom.World) -> float:
    """Bytes of every model and state array, per particle (the event log excluded)."""
    engine = world.engine
    assert engine is not None
    total = 0
    for value in engine.model._asdict().values():
        total += getattr(value, "nbytes", 0)
    for name, value in engine.state._asdict().items():
        if not name.startswith("log_") and value is not None:  # (None: not held, e.g. no spins)
            total += value.nbytes
    return total / world.n_bodies


def measure(dim: int, n: int, packing: float, repeats: int) -> dict[str, float]:
    world = lattice_gas(dim, n, packing)
    # melt: about 3 collisions per particle (rate ~10 per unit time at these densities)
    world.run(until=0.3, log=False)
    count = world.n_bodies
    target = max(300_000, 2 * count)
    # time per collision is what we report; pick the run length from a short probe
    world.stats.reset()
    world.run(until=world.time + 0.5, log=False)
    rate = max(world.stats.collisions, 1) / 0.5
    span = target / rate
    best: dict[str, float] = {}
    for _ in range(repeats):
        world.stats.reset()
        start = time.perf_counter()
        world.run(until=world.time + span, log=False)
        elapsed = time.perf_counter() - start
        result = {
            "collisions_per_s": world.stats.collisions / elapsed,
            "events_per_s": world.stats.events_processed / elapsed,
            "collisions": float(world.stats.collisions),
            "seconds": elapsed,
        }
        if not best or result["collisions_per_s"] > best["collisions_per_s"]:
            best = result
    best["n"] = float(count)
    best["bytes_per_particle"] = memory_per_particle(world)
    best["peak_mb"] = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    best["events_per_collision"] = best["events_per_s"] / best["collisions_per_s"]
    return best


def compile_times() -> tuple[float, float]:
    """Seconds to first result in a fresh process: cold kernel cache, then warm."""
    snippet = (
        "import time; t = time.perf_counter(); import carom\n"
        "w = carom.World(3, [4.0, 4.0, 4.0], 'periodic')\n"
        "w.add_spheres([[1.0, 1.0, 1.0], [2.5, 1.0, 1.0]], [[1.0, 0, 0], [0, 0, 0]], radius=0.5)\n"
        "w.run(until=1.0)\nprint(time.perf_counter() - t)"
    )
    with tempfile.TemporaryDirectory() as cache:
        env = {**os.environ, "NUMBA_CACHE_DIR": cache}
        out = []
        for _ in range(2):
            proc = subprocess.run(
                [sys.executable, "-c", snippet], capture_output=True, text=True, env=env, check=True
            )
            out.append(float(proc.stdout.strip().splitlines()[-1]))
    return out[0], out[1]


def machine() -> str:
    cpu = platform.processor() or platform.machine()
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                cpu = line.split(":", 1)[1].strip()
                break
    except OSError:
        pass
    import numba

    return (
        f"{cpu}, {os.cpu_count()} cores, {platform.system()} {platform.release()}; "
        f"Python {platform.python_version()}, NumPy {np.__version__}, Numba {numba.__version__}"
    )


def record(title: str, body: str, details: tuple[str, ...] = ()) -> None:
    """Append a run to RESULTS.md: a heading with ``title`` and the time, the machine, the
    commit and the command that ran (this script and its arguments), ``details`` (one line
    each), then ``body``."""
    command = " ".join(["python", f"benchmarks/{Path(sys.argv[0]).name}", *sys.argv[1:]])
    stamp = dt.datetime.now(dt.UTC).strftime("%Y-%m-%d %H:%M UTC")
    with RESULTS.open("a") as handle:
        handle.write(f"\n## {title}, {stamp}\n\n")
        handle.write(f"- machine: {machine()}\n- commit: {commit()}\n- command: `{command}`\n")
        for line in details:
            handle.write(f"- {line}\n")
        handle.write("\n" + body)


def commit() -> str:
    try:
        return subprocess.run(
            ["git", "rev-parse", "--short", "HEAD"],
            capture_output=True,
            text=True,
            cwd=HERE,
            check=True,
        ).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1_000, 10_000, 100_000, 1_000_000])
    parser.add_argument("--dims", type=int, nargs="+", default=[3, 2])
    parser.add_argument("--repeats", type=int, default=3, help="best of this many timings")
    parser.add_argument("--no-record", action="store_true", help="do not append to RESULTS.md")
    args = parser.parse_args()

    cold, warm = compile_times()
    rows = []
    for dim in args.dims:
        packing = 0.3 if dim == 3 else 0.5
        base = None
        for n in args.sizes:
            r = measure(dim, n, packing, args.repeats)
            per = 1.0 / r["collisions_per_s"]
            base = base if base is not None else (per, r["n"])
            growth = per / base[0]
            log_bound = 1 + math.log(r["n"] / base[1]) / math.log(base[1])
            rows.append((dim, packing, r, growth, log_bound))
            print(
                f"{dim}D phi={packing} N={int(r['n']):>8,}: {r['collisions_per_s']:.3g} coll/s, "
                f"{r['events_per_s']:.3g} events/s, {r['events_per_collision']:.2f} events/coll,"
                f" {r['bytes_per_particle']:.0f} B/particle, peak {r['peak_mb']:.0f} MB, "
                f"time/coll x{growth:.2f} "
                f"(log N bound x{log_bound:.2f})",
                flush=True,
            )

    header = (
        "| dim | packing | N | collisions/s | events/s | events/collision | "
        "time per collision vs smallest N | log N bound | bytes/particle | peak RSS so far [MB] |"
    )
    lines = [header, "|---|---|---|---|---|---|---|---|---|---|"]
    for dim, packing, r, growth, bound in rows:
        lines.append(
            f"| {dim} | {packing} | {int(r['n']):,} | {r['collisions_per_s']:.3g} | "
            f"{r['events_per_s']:.3g} | {r['events_per_collision']:.2f} | x{growth:.2f} | "
            f"x{bound:.2f} | {r['bytes_per_particle']:.0f} | {r['peak_mb']:.0f} |"
        )
    three_d = [r for d, _, r, _, _ in rows if d == 3 and 5_000 <= r["n"] <= 20_000]
    verdict = ""
    if three_d:
        rate = three_d[0]["collisions_per_s"]
        verdict = (
            f"\nTarget 7e5 collisions/s at N = 1e4 in 3D: measured {rate:.3g}, "
            f"{'met' if rate >= TARGET else f'missed by a factor {TARGET / rate:.1f}'}.\n"
        )
    report = "\n".join(lines)
    print()
    print(report)
    print(
        f"\nfirst result in a fresh process: {cold:.1f} s with an empty kernel cache, "
        f"{warm:.2f} s from the cache"
    )
    print(verdict)
    if args.no_record:
        return
    record(
        "edmd: event-driven engine",
        report + "\n" + verdict,
        (
            f"compile: {cold:.1f} s to the first result with an empty kernel cache, "
            f"{warm:.2f} s from the cache (excluded below)",
        ),
    )


if __name__ == "__main__":
    main()
