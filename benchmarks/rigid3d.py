"""carom's 3D rigid-body engine beside pybullet, MuJoCo and Rapier on the 3D pyramid and the
tumbler, in one run.

The scenes are the built-in ``pyramid-3d`` (a square pyramid of 10 layers, 385 unit boxes,
friction 0.6, no sleep, 10 s) and ``tumbler-3d`` (216 convex rocks in a kinematic drum turning
at 25 deg/s, 10 s), run through ``carom compare``: each engine builds the same bodies and is
set up as its documentation recommends (docs/compare.md), at its own documented step (carom
and Rapier 60 Hz, pybullet 240 Hz, MuJoCo 500 Hz). ms per step is the time inside the
engines' step calls only, on one core (this process is pinned to one; Rapier is given one
thread). Each engine runs once per round; rounds alternate the order. ms per simulated second
is given beside it, since the steps differ.

Target (issue 14, item 9): carom ahead of every peer in ms per step, with carom's pyramid
standing (its top box moves less than 1% of its size in 10 s).

Run:  python benchmarks/rigid3d.py                      (appends to benchmarks/RESULTS.md)
      python benchmarks/rigid3d.py --scenes pyramid-3d --until 2 --no-record
      python benchmarks/rigid3d.py --engines carom rapier3d
Needs the compare extra: pip install -e '.[compare]'.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
from pathlib import Path
from typing import Any

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parent))

from edmd import record

from carom.compare import compare, peer_scene
from carom.compare.engines import ENGINES
from carom.compare.report import format_table

ENGINE_NAMES = ["carom", "pybullet", "mujoco", "rapier3d"]
#: the pyramid stands: its top box moves less than this fraction of its size (issue 14)
STANDS_DRIFT = 0.01


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=["pyramid-3d", "tumbler-3d"])
    parser.add_argument("--engines", nargs="+", default=ENGINE_NAMES, choices=ENGINE_NAMES)
    parser.add_argument("--until", type=float, help="simulated time [s]; default the scene's")
    parser.add_argument("--rounds", type=int, default=1, help="runs of each engine per scene")
    parser.add_argument("--no-record", action="store_true", help="do not append to RESULTS.md")
    args = parser.parse_args()
    names: list[str] = list(args.engines)
    if "carom" not in names:
        names.insert(0, "carom")
    missing = [ENGINES[n].missing() for n in names if ENGINES[n].missing() is not None]
    if missing:
        sys.exit("; ".join(str(m) for m in missing))
    if hasattr(os, "sched_setaffinity"):
        os.sched_setaffinity(0, {min(os.sched_getaffinity(0))})  # one core

    rows: list[str] = []
    verdict: list[str] = []
    for name in args.scenes:
        scene = peer_scene(name, args.until)
        compare(peer_scene(name, 0.1), ["carom"])  # compile the kernels, untimed
        times: dict[str, list[float]] = {e: [] for e in names}
        last: dict[str, dict[str, Any]] = {}
        for k in range(args.rounds):
            order = names if k % 2 == 0 else names[::-1]
            result = compare(scene, order)
            print(format_table(result) + "\n", flush=True)
            for engine, run in result.engines.items():
                times[engine].append(run["ms_per_step"])
                last[engine] = run
        ms = {e: statistics.median(t) for e, t in times.items()}
        per_second = {e: ms[e] / last[e]["dt_s"] for e in names}  # ms per simulated s
        for engine in names:
            run, m = last[engine], last[engine]["metrics"]
            rows.append(
                f"| {name} | {engine} {run['version']} | {1.0 / run['dt_s']:.4g} | "
                f"{ms[engine]:.3g} | {ms[engine] / ms['carom']:.3g} | {per_second[engine]:.4g} | "
                f"{per_second[engine] / per_second['carom']:.3g} | {m['top_drift_m']:.3g} | "
                f"{m['max_rotation_deg']:.3g} | {m['max_overlap_m']:.3g} | "
                f"{m['bodies_through_static']} |"
            )
        carom = last["carom"]["metrics"]
        peers = [e for e in names if e != "carom"]
        ahead = [e for e in peers if ms["carom"] < ms[e]]
        behind = [f"{e} ({ms[e] / ms['carom']:.3g})" for e in peers if e not in ahead]
        stands = carom["top_drift_per_size"] < STANDS_DRIFT
        if name == "pyramid-3d":
            verdict.append(
                f"- {name}: carom's pyramid {'stands' if stands else 'does not stand'} (top "
                f"box moved {carom['top_drift_per_size']:.3g} of its size; target < 0.01)"
            )
        verdict.append(
            f"- {name}: carom {ms['carom']:.3g} ms per step; ahead of "
            f"{', '.join(ahead) or 'no peer'}"
            + (f"; behind {', '.join(behind)} (peer / carom)" if behind else "")
            + f": target {'met' if not behind and (stands or name != 'pyramid-3d') else 'missed'}"
        )
    table = "\n".join(
        [
            "| scene | engine | Hz | ms / step | / carom | ms / simulated s | / carom "
            "| top moved [m] | largest turn [deg] | deepest overlap [m] | through |",
            "|---|---|---|---|---|---|---|---|---|---|---|",
            *rows,
        ]
    )
    print(table + "\n\n" + "\n".join(verdict))
    if args.no_record:
        return
    record(
        "rigid3d: carom beside pybullet, MuJoCo and Rapier",
        table + "\n\n" + "\n".join(verdict) + "\n",
    )


if __name__ == "__main__":
    main()
