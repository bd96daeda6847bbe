"""Building the event-driven engine at scale: seconds and peak memory, each size in a fresh
process (issue 16, item 2: 10^6 spheres built in under 1 s, peak under 600 MB with the
interpreter).

For each dimension and size, a child process imports carom, loads the engine's kernels (a
warm cache: a first child compiles them), places the lattice gas of benchmarks/edmd.py
(3D packing 0.3, 2D 0.5) and times ``World.prepare()``: the engine built, every neighbour
list and every body's first event. Peak memory is the child's maximum resident set
(``ru_maxrss``) before the build, after it, and after a short run.

With ``--checkpoint``, the child then saves the world (``World.save``), and a second fresh
process loads it and runs on: seconds, file size and peak memory of both, the loading process's
peak against the building one's.

Run:  python benchmarks/edmd_build.py                 (appends to benchmarks/RESULTS.md)
      python benchmarks/edmd_build.py --sizes 100000 --dims 3 --no-record
      python benchmarks/edmd_build.py --sizes 1000000 --checkpoint
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from edmd import record

CHILD = """
import json, os, resource, sys, time
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
result = dict(n=world.n_bodies, build=build, before=before, after=after, run=peak())
if {checkpoint!r}:
    began = time.perf_counter()
    world.save({checkpoint!r})
    saved = time.perf_counter() - began
    result.update(save=saved, saved=peak(), size=os.path.getsize({checkpoint!r}))
print(json.dumps(result))
"""

LOAD = """
import json, resource, sys, time
sys.path.insert(0, {here!r})
from edmd import lattice_gas
import carom

def peak():
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024

warm = lattice_gas({dim}, 64, {packing})
warm.prepare()  # the kernels loaded, as in the building process
before = peak()
began = time.perf_counter()
world = carom.World.load({checkpoint!r})
load = time.perf_counter() - began
after = peak()
world.run(until=world.time + 0.02)
print(json.dumps(dict(load=load, before=before, after=after, run=peak())))
"""


def _child(code: str) -> dict[str, float]:
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=3600
    )
    result: dict[str, float] = json.loads(done.stdout.strip().splitlines()[-1])
    return result


def measure(dim: int, n: int, checkpoint: str = "") -> dict[str, float]:
    """Build (and with ``checkpoint``, a path, save there, then load in another process)."""
    packing = 0.3 if dim == 3 else 0.5
    here = str(Path(__file__).resolve().parent)
    result = _child(CHILD.format(here=here, dim=dim, n=n, packing=packing, checkpoint=checkpoint))
    if checkpoint:
        loaded = _child(LOAD.format(here=here, dim=dim, packing=packing, checkpoint=checkpoint))
        result |= {f"load_{k}": v for k, v in loaded.items()}
        Path(checkpoint).unlink()
    return result


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[10_000, 100_000, 1_000_000])
    parser.add_argument("--dims", type=int, nargs="+", default=[3, 2])
    parser.add_argument("--no-record", action="store_true", help="do not append to RESULTS.md")
    parser.add_argument(
        "--checkpoint", action="store_true", help="also save the world and load it again"
    )
    args = parser.parse_args()
    path = str(Path(tempfile.gettempdir()) / f"edmd_build_{os.getpid()}.npz")

    measure(args.dims[0], 1_000)  # a first child compiles the kernels if the cache is cold
    lines = [
        "| dim | N | engine build [s] | peak before build [MB] | peak after build [MB] | "
        "peak after a short run [MB] |",
        "|---|---|---|---|---|---|",
    ]
    if args.checkpoint:
        lines[0] += (
            " save [s] | peak after save [MB] | file [MB] | load [s] | peak after load [MB] | "
            "peak after load and run [MB] |"
        )
        lines[1] += "---|" * 6
    for dim in args.dims:
        for n in args.sizes:
            r = measure(dim, n, path if args.checkpoint else "")
            row = (
                f"| {dim} | {int(r['n']):,} | {r['build']:.2f} | {r['before']:.0f} | "
                f"{r['after']:.0f} | {r['run']:.0f} |"
            )
            if args.checkpoint:
                row += (
                    f" {r['save']:.2f} | {r['saved']:.0f} | {r['size'] / 2**20:.0f} | "
                    f"{r['load_load']:.2f} | {r['load_after']:.0f} | {r['load_run']:.0f} |"
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
                *(
                    [
                        "--checkpoint: the built world saved after the run (World.save), then "
                        "loaded and run in a fresh process (World.load); peaks are ru_maxrss"
                    ]
                    if args.checkpoint
                    else []
                ),
            ),
        )


if __name__ == "__main__":
    main()
