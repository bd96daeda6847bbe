"""carom's event-driven engine against DynamO, the same runs, interleaved, on one pinned core.

DynamO (Bannerman, Sargant and Lue 2011; github.com/toastedcrumpets/DynamO) is the reference
event-driven simulator of hard spheres. Both simulate N elastic hard spheres of unit diameter
and mass at packing fraction phi in a periodic cube, started on the same FCC lattice
(N = 4 C^3), T = 1; both melt it (``MELT`` collisions a sphere, not timed), then run a timed
window of the same number of collisions. DynamO times its own window (its ``Misc/Timing``
``RuntimeSeconds``, from the run's start after the configuration is read; collisions are its
``TwoParticleEvents``); carom's window is timed around ``World.run`` in its own process. Each
round runs DynamO, then carom, as separate processes pinned to the same core (``taskset``),
nothing of carom's running while DynamO's window runs; the ratio is taken round by round and
reported as its median and spread, with each one's collisions per second, microseconds per
collision, and the growth of the cost per collision from the smallest N.

DynamO is built when asked, from its public repository (``--build DIR``: git clone with its
``stator`` submodule, CMake ``Release`` with ``-march=native``, the ``dynarun`` and
``dynamod`` programs); it needs
Boost (program_options, filesystem, system, test, iostreams), bzip2 and Eigen 3 (Debian:
``apt-get install libboost-program-options-dev libboost-filesystem-dev libboost-system-dev
libboost-test-dev libboost-iostreams-dev libbz2-dev libeigen3-dev``). Never in ``make test``.

In 2D DynamO has no mode: ``--disks`` times carom's own hard disks (packing ``--eta``, a
square lattice of SIDE^2 disks) the same way, for the growth of their cost per collision
against DynamO's in 3D. ``--shells D ...`` times carom alone on the same gases with each
neighbour-shell thickness D [diameters] in turn (rounds interleaved over the thicknesses): the
default's check at the sizes where memory, not arithmetic, sets the cost.

Run:  python benchmarks/dynamo.py --build ~/src/dynamo          (once)
      python benchmarks/dynamo.py --dynamo ~/src/dynamo/build [--cells 7 20 40 63]
            [--phi 0.3 0.45] [--rounds 3] [--core 1] [--no-record]
      python benchmarks/dynamo.py --disks [32 180 508 1000] [--eta 0.5] [--rounds 3]
      python benchmarks/dynamo.py --shells 0.35 0.5 0.6 0.8 [--cells 63] [--phi 0.3]
"""

from __future__ import annotations

import argparse
import bz2
import json
import math
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import xml.etree.ElementTree as ET
from pathlib import Path

from edmd import record  # benchmarks/edmd.py, beside this file

#: DynamO's repository
REPOSITORY = "https://github.com/toastedcrumpets/DynamO.git"
#: collisions a sphere to melt the lattice before timing (not timed)
MELT = 20
#: collisions in a timed window: this many a sphere, and at least ``WINDOW_MIN``
WINDOW_PER_SPHERE = 5
WINDOW_MIN = 2_000_000

#: carom's run, in its own process: spheres of unit diameter on an FCC lattice of ``cells``^3
#: cells at packing ``phi`` (3D), or disks on a square lattice of ``cells``^2 (2D, where
#: DynamO has no mode), melted, then timed over a window of collisions
CAROM = textwrap.dedent(
    """
    import json, math, sys, time
    import numpy as np
    import carom
    dim, cells, phi, melt, window, shell = json.loads(sys.argv[1])
    if dim == 3:
        rho = 6.0 * phi / math.pi  # spheres of unit diameter: phi = pi rho / 6
        a = (4.0 / rho) ** (1.0 / 3.0)  # the FCC cell's side
        base = np.array([[0, 0, 0], [0.5, 0.5, 0], [0.5, 0, 0.5], [0, 0.5, 0.5]]) + 0.25
    else:
        a = math.sqrt(math.pi / (4.0 * phi))  # the lattice spacing: eta = pi / (4 a^2)
        base = np.array([[0.5, 0.5]])
    grid = np.stack(np.meshgrid(*[np.arange(cells)] * dim, indexing="ij"), -1)
    x = (grid.reshape(-1, 1, dim) + base[None]).reshape(-1, dim) * a
    n = x.shape[0]
    rng = np.random.default_rng(1)
    v = rng.standard_normal((n, dim))
    v -= v.mean(axis=0)
    v *= math.sqrt(dim * (n - 1) / (v * v).sum())  # T = 1, no drift
    world = carom.World(dim, [cells * a] * dim, "periodic", shell_thickness=shell)
    world.add_spheres(x, v, radius=0.5)
    world.run_events(1)  # (the engine built, its kernels loaded)
    # melt: step the clock until the count is reached
    world.stats.reset()
    while world.stats.collisions < melt * n / 2:
        world.run(until=world.time + 1.0, log=False)
    world.stats.reset()
    world.run(until=world.time + 1.0, log=False)
    per_time = world.stats.collisions / 1.0
    span = window / per_time
    world.stats.reset()
    start = time.perf_counter()
    world.run(until=world.time + span, log=False)
    elapsed = time.perf_counter() - start
    stats = world.stats
    print(json.dumps({"n": n, "collisions": stats.collisions, "events": stats.events_processed,
                      "seconds": elapsed}))
    """
)


def build(where: Path) -> Path:
    """Clone DynamO into ``where`` and build its programs (module docstring); return the
    build folder."""
    if not (where / "CMakeLists.txt").exists():
        subprocess.run(["git", "clone", "--recursive", REPOSITORY, str(where)], check=True)
    out = where / "build"
    # its best build for the machine: Release (-O3) for this processor's instructions
    subprocess.run(
        ["cmake", "-S", str(where), "-B", str(out), "-DCMAKE_BUILD_TYPE=Release",
         "-DCMAKE_CXX_FLAGS=-march=native"],
        check=True,
    )  # fmt: skip
    jobs = str(os.cpu_count() or 1)
    subprocess.run(
        ["cmake", "--build", str(out), "--target", "dynarun", "dynamod", "-j", jobs], check=True
    )
    return out


def pinned(core: int) -> list[str]:
    return ["taskset", "-c", str(core)]


def dynamo_start(programs: Path, cells: int, phi: float, folder: Path, core: int) -> Path:
    """DynamO's FCC lattice of 4 cells^3 spheres at ``phi``, melted by ``MELT`` collisions a
    sphere; the melted configuration's file."""
    rho = 6.0 * phi / math.pi
    start, melted = folder / "start.xml.bz2", folder / "melted.xml.bz2"
    subprocess.run(
        [str(programs / "dynamod"), "-m", "0", "-C", str(cells), "-d", repr(rho), "-o",
         str(start)],
        check=True, capture_output=True,
    )  # fmt: skip
    n = 4 * cells**3
    subprocess.run(
        [*pinned(core), str(programs / "dynarun"), str(start), "-c", str(MELT * n // 2), "-o",
         str(melted), "--out-data-file", str(folder / "melt-data.xml.bz2")],
        check=True, capture_output=True,
    )  # fmt: skip
    return melted


def dynamo_window(programs: Path, melted: Path, window: int, folder: Path, core: int) -> dict:
    """One timed window of DynamO from ``melted``: its collisions and its own seconds."""
    data = folder / "window-data.xml.bz2"
    subprocess.run(
        [*pinned(core), str(programs / "dynarun"), str(melted), "-c", str(window), "-o",
         str(folder / "end.xml.bz2"), "--out-data-file", str(data)],
        check=True, capture_output=True,
    )  # fmt: skip
    root = ET.fromstring(bz2.decompress(data.read_bytes()))
    timing = root.find("Misc/Timing")
    duration = root.find("Misc/Duration")
    if timing is None or duration is None:
        raise SystemExit(f"{data} has no Misc/Timing or Misc/Duration: not DynamO's output?")
    return {
        "collisions": int(duration.attrib["TwoParticleEvents"]),
        "seconds": float(timing.attrib["RuntimeSeconds"]),
    }


def carom_window(
    cells: int, phi: float, window: int, core: int, dim: int = 3, shell: float | None = None
) -> dict:
    """One timed window of carom (``CAROM``), in its own pinned process (melted there
    first), with neighbour shells ``shell`` thick [diameters] (None: the default)."""
    ran = subprocess.run(
        [*pinned(core), sys.executable, "-c", CAROM,
         json.dumps([dim, cells, phi, MELT, window, shell])],
        check=True, capture_output=True, text=True,
    )  # fmt: skip
    out: dict = json.loads(ran.stdout.strip().splitlines()[-1])
    return out


def _spread_us(seconds: list[float]) -> str:
    """Costs per collision [s] as ``median (min-max)`` in microseconds."""
    return (
        f"{1e6 * statistics.median(seconds):.2f} "
        f"({1e6 * min(seconds):.2f}-{1e6 * max(seconds):.2f})"
    )


def disks(sides: list[int], eta: float, rounds: int, core: int) -> list[str]:
    """carom's hard disks at ``eta``, each size in ``rounds`` pinned processes (rounds
    interleaved over the sizes); table lines with the cost per collision and its growth."""
    seconds: dict[int, list[float]] = {side: [] for side in sides}
    n_of: dict[int, int] = {}
    for _ in range(rounds):
        for side in sides:
            n = side * side
            window = max(WINDOW_MIN, WINDOW_PER_SPHERE * n)
            out = carom_window(side, eta, window, core, dim=2)
            n_of[side] = out["n"]
            seconds[side].append(out["seconds"] / out["collisions"])
    first = statistics.median(seconds[sides[0]])
    lines = [
        "| eta | N | carom us/coll (median, range) | growth from the first N |",
        "|---|---|---|---|",
    ]
    for side in sides:
        cost = statistics.median(seconds[side])
        lines.append(
            f"| {eta} | {n_of[side]} | {_spread_us(seconds[side])} | x{cost / first:.2f} |"
        )
        print(lines[-1], flush=True)
    return lines


def shells(
    thicknesses: list[float], cells: list[int], phis: list[float], rounds: int, core: int
) -> list[str]:
    """carom's spheres with each neighbour-shell thickness in turn (each window in its own
    pinned process; rounds interleaved over the thicknesses); table lines with the cost per
    collision and the events a collision (shell exits and stale predictions besides)."""
    lines = [
        "| phi | N | shell [diameters] | carom us/coll (median, range) | events / collision |",
        "|---|---|---|---|---|",
    ]
    for phi in phis:
        for side in cells:
            n = 4 * side**3
            window = max(WINDOW_MIN, WINDOW_PER_SPHERE * n)
            seconds: dict[float, list[float]] = {d: [] for d in thicknesses}
            events: dict[float, list[float]] = {d: [] for d in thicknesses}
            for _ in range(rounds):
                for d in thicknesses:
                    out = carom_window(side, phi, window, core, shell=d)
                    seconds[d].append(out["seconds"] / out["collisions"])
                    events[d].append(out["events"] / out["collisions"])
            for d in thicknesses:
                lines.append(
                    f"| {phi} | {n} | {d} | {_spread_us(seconds[d])} | "
                    f"{statistics.median(events[d]):.3f} |"
                )
                print(lines[-1], flush=True)
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--build", type=Path, help="clone and build DynamO there, then stop")
    parser.add_argument("--dynamo", type=Path, help="DynamO's build folder (dynarun, dynamod)")
    parser.add_argument("--cells", type=int, nargs="+", default=[7, 20, 40, 63])
    parser.add_argument("--phi", type=float, nargs="+", default=[0.3, 0.45])
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--core", type=int, default=1)
    parser.add_argument("--no-record", action="store_true")
    parser.add_argument(
        "--disks", type=int, nargs="*", metavar="SIDE",
        help="instead: carom's hard disks (2D) on SIDE^2 lattices (default 32 180 508 1000)",
    )  # fmt: skip
    parser.add_argument("--eta", type=float, default=0.5, help="the disks' packing")
    parser.add_argument(
        "--shells", type=float, nargs="+", metavar="D",
        help="instead: carom alone with neighbour shells D diameters thick, in turn",
    )  # fmt: skip
    args = parser.parse_args()
    if args.build is not None:
        print(build(args.build))
        return
    if args.shells is not None:
        lines = shells(args.shells, args.cells, args.phi, args.rounds, args.core)
        body = "\n".join(
            [
                f"carom's spheres with each neighbour-shell thickness, {args.rounds} rounds "
                f"(each window in its own process, core {args.core}, the thicknesses in turn); "
                f"windows of max({WINDOW_MIN:,}, {WINDOW_PER_SPHERE} N) collisions after {MELT} "
                "a sphere:",
                "",
                *lines,
            ]
        )
        if not args.no_record:
            record("dynamo --shells: carom's neighbour-shell thickness at large N", body + "\n")
        return
    if args.disks is not None:
        sides = args.disks or [32, 180, 508, 1000]
        lines = disks(sides, args.eta, args.rounds, args.core)
        body = "\n".join(
            [
                f"carom's hard disks, {args.rounds} rounds (each size in its own process, "
                f"core {args.core}); windows of max({WINDOW_MIN:,}, {WINDOW_PER_SPHERE} N) "
                f"collisions after {MELT} a disk:",
                "",
                *lines,
            ]
        )
        if not args.no_record:
            record(
                "dynamo --disks: carom's hard disks, the growth of the cost per collision",
                body + "\n",
            )
        return
    if args.dynamo is None:
        parser.error("give --dynamo BUILD_FOLDER (or --build DIR first)")
    lines = [
        "| phi | N | DynamO coll/s | carom coll/s | carom / DynamO (median, range) | "
        "DynamO us/coll | carom us/coll |",
        "|---|---|---|---|---|---|---|",
    ]
    for phi in args.phi:
        for cells in args.cells:
            n = 4 * cells**3
            window = max(WINDOW_MIN, WINDOW_PER_SPHERE * n)
            with tempfile.TemporaryDirectory() as tmp:
                folder = Path(tmp)
                melted = dynamo_start(args.dynamo, cells, phi, folder, args.core)
                theirs, ours, ratios = [], [], []
                for _ in range(args.rounds):
                    d = dynamo_window(args.dynamo, melted, window, folder, args.core)
                    c = carom_window(cells, phi, window, args.core)
                    theirs.append(d["collisions"] / d["seconds"])
                    ours.append(c["collisions"] / c["seconds"])
                    ratios.append(ours[-1] / theirs[-1])
            line = (
                f"| {phi} | {n} | {min(theirs):.3g}-{max(theirs):.3g} | "
                f"{min(ours):.3g}-{max(ours):.3g} | {statistics.median(ratios):.2f} "
                f"({min(ratios):.2f}-{max(ratios):.2f}) | "
                f"{1e6 / statistics.median(theirs):.2f} | {1e6 / statistics.median(ours):.2f} |"
            )
            print(line, flush=True)
            lines.append(line)
    body = "\n".join(
        [
            f"carom against DynamO, {args.rounds} interleaved rounds, core {args.core}; "
            f"windows of max({WINDOW_MIN:,}, {WINDOW_PER_SPHERE} N) collisions after "
            f"{MELT} a sphere:",
            "",
            *lines,
        ]
    )
    if not args.no_record:
        record("dynamo: the event-driven engine against DynamO", body + "\n")


if __name__ == "__main__":
    main()
