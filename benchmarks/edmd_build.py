"""Building the event-driven engine at scale: seconds and peak memory, each size in a fresh
process (issue 16, item 2: 10^6 spheres built in under 1 s, peak under 600 MB with the
interpreter).

For each dimension and size, a child process imports carom, loads the engine's kernels (a
warm cache: a first child compiles them), places the lattice gas of benchmarks/edmd.py
(3D packing 0.3, 2D 0.5) and times ``World.prepare()``: the engine built, every neighbour
list and every body's first event. Peak memory is the child's maximum resident set
(``ru_maxrss``) before the build, after it, and after a short run.

Run:  python benchmarks/edmd_build.py                 (appends to benchmarks/RESULTS.md)
      python benchmarks/edmd_build.py --sizes 100000 --dims 3 --no-record
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from edmd import record

CHILD = """
import json, resource, sys, time
sys.path.insert(0, {here!r})
from edmd import lattice_gas
import carom.engines.edmd.loop  # (the kernels' module: imported, not yet loaded)

def peak():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

warm = lattice_gas({dim}, 64, {packing})
warm.prepare()  # the kernels loaded (or compiled) on a small world, not timed
world = lattice_gas({dim}, {n}, {packing})
before = peak()
began = time.perf_counter()
world.prepare()
build = time.perf_counter() - began
after = peak()
world.run(until=world.time + 0.02)
print(json.dumps(dict(n=world.n_bodies, build=build, before=before, after=after, run=peak())))
"""


def measure(dim: int, n: int) -> dict[str, float]:
    packing = 0.3 if dim == 3 else 0.5
    code = CHILD.format(here=str(Path(__file__).resolve().parent), dim=dim, n=n, packing=packing)
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=3600
    )
    result: dict[str, float] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10_000, 100_000, 1_000_000])
    parser.add_argument("--dims", type=int, nargs="+", default=[3, 2])
    parser.add_argument("--no-record", action="store_true", help="do not append to RESULTS.md")
    args = parser.parse_args()

    measure(args.dims[0], 1_000)  # a first child compiles the kernels if the cache is cold
    lines = [
        "| dim | N | engine build [s] | peak before build [MB] | peak after build [MB] | "
        "peak after a short run [MB] |",
        "|---|---|---|---|---|---|",
    ]
    for dim in args.dims:
        for n in args.sizes:
            r = measure(dim, n)
            row = (
                f"| {dim} | {int(r['n']):,} | {r['build']:.2f} | {r['before']:.0f} | "
                f"{r['after']:.0f} | {r['run']:.0f} |"
            )
            print(row, flush=True)
            lines.append(row)
    body = "\n".join(lines) + "\n"
    print(body)
    if not args.no_record:
        record(
            "Building the event-driven engine: seconds and peak memory",
            body,
            (
                "each size in a fresh process, kernels loaded before timing; lattice gas, 3D "
                "packing 0.3, 2D 0.5; build = World.prepare(); peak = ru_maxrss",
                "target (issue 16, item 2): 10^6 spheres built in under 1 s, peak under 600 MB",
            ),
        )


if __name__ == "__main__":
    main()
