"""carom's 3D rigid engine beside Rapier, MuJoCo and pybullet on the 3D pyramid and the
tumbler: ms per step on one core, interleaved round by round.

The scenes are the built-in ``pyramid-3d`` (a square pyramid of 10 layers, 385 unit boxes,
friction 0.6, no sleep, 10 s) and ``tumbler-3d`` (216 convex rocks in a kinematic drum turning
at 25 deg/s, 10 s). Each engine is set up by ``carom compare`` as its documentation recommends
(docs/compare.md), at its own documented step (carom and Rapier 60 Hz, pybullet 240 Hz,
MuJoCo 500 Hz); Rapier is given one thread. By default the pyramid runs in carom and Rapier only:
pybullet and MuJoCo take 80-90 ms a step on it (RESULTS.md), six minutes a run; ``--engines``
runs them on it too.

**Timing** (benchmarks/steppers.py): this process is pinned to one core; each timed run steps
the scene bare, only the step calls timed and nothing read between steps (a monitor reading
the state between timed steps slowed Rapier's next step by x1.05-1.30 and carom's by
x0.94-1.08, issue 46); every engine runs once a round, the order rotating round by round;
``--rounds`` rounds (5 by default). Reported: each engine's median ms per step and spread,
ms per simulated second (the steps differ), and carom / peer round by round (median,
least-greatest; below 1 carom is faster), per step and per simulated second.

**Accuracy**: one more run of every engine under ``carom compare``'s monitor, untimed here:
the top box's move, the largest turn, the deepest overlap, bodies through the drum.

Run:  python benchmarks/rigid3d.py                      (appends to benchmarks/RESULTS.md)
      python benchmarks/rigid3d.py --scenes pyramid-3d --until 2 --rounds 3 --no-record
      python benchmarks/rigid3d.py --engines carom rapier3d
Needs the compare extra: pip install -e '.[compare]'.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
sys.path.insert(0, str(Path(__file__).resolve().parent))

from edmd import record
from steppers import bare_ms, interleave, monitored, one_core, ratios, spread

from carom.compare import compare, peer_scene
from carom.compare.engines import ENGINES

ENGINE_NAMES = ["carom", "pybullet", "mujoco", "rapier3d"]
#: the engines each scene runs in unless ``--engines`` says
DEFAULT_ENGINES = {"pyramid-3d": ["carom", "rapier3d"], "tumbler-3d": ENGINE_NAMES}
#: the pyramid stands: its top box moves less than this fraction of its size (issue 14)
STANDS_DRIFT = 0.01


def time_scene(name: str, names: list[str], until: float | None, rounds: int) -> list[str]:
    """Time ``name`` in the engines ``names``, interleaved; the table's rows."""
    scene = peer_scene(name, until)
    compare(peer_scene(name, 0.1), ["carom"])  # compile the kernels, untimed
    steps = {e: ENGINES[e].rigid_dt(scene) for e in names}  # [s]
    times = interleave({e: (lambda e=e: bare_ms(e, scene)) for e in names}, rounds)
    rows = []
    for e, per_step in ratios(times).items():
        # per simulated second: ms / dt, carom's over the peer's
        per_second = [r * steps[e] / steps["carom"] for r in per_step]
        rows.append(
            f"| {name} | {e} | {1.0 / steps[e]:.4g} | {spread(times[e])} | "
            f"{spread([t / steps[e] for t in times[e]])} | {spread(per_step)} | "
            f"{spread(per_second)} |"
        )
    return rows


def accuracy(name: str, names: list[str], until: float | None) -> tuple[list[str], bool]:
    """One monitored run of every engine: its rows, and whether carom's pyramid stands."""
    fields = ["top_drift_m", "max_rotation_deg", "max_overlap_m", "bodies_through_static"]
    rows, runs = monitored(name, names, until, fields)
    stands = runs["carom"]["metrics"]["top_drift_per_size"] < STANDS_DRIFT
    return rows, stands


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=["pyramid-3d", "tumbler-3d"])
    parser.add_argument("--engines", nargs="+", choices=ENGINE_NAMES, help="default: per scene")
    parser.add_argument("--until", type=float, help="simulated time [s]; default the scene's")
    parser.add_argument("--rounds", type=int, default=5, help="timed runs of each engine")
    parser.add_argument("--no-record", action="store_true", help="do not append to RESULTS.md")
    args = parser.parse_args()
    chosen = {
        name: ["carom"]
        + [e for e in args.engines or DEFAULT_ENGINES.get(name, ENGINE_NAMES) if e != "carom"]
        for name in args.scenes
    }
    missing = {ENGINES[n].missing() for e in chosen.values() for n in e} - {None}
    if missing:
        sys.exit("; ".join(sorted(str(m) for m in missing)))
    core = one_core()
    timing: list[str] = []
    checks: list[str] = []
    verdict: list[str] = []
    for name in args.scenes:
        timing += time_scene(name, chosen[name], args.until, args.rounds)
        rows, stands = accuracy(name, chosen[name], args.until)
        checks += rows
        if name == "pyramid-3d":
            verdict.append(f"- {name}: carom's pyramid {'stands' if stands else 'falls'}")
    body = "\n".join(
        [
            f"On core {core}, {args.rounds} rounds interleaved, bare steps (median "
            "(least-greatest)); carom / engine round by round (below 1: carom faster):",
            "",
            "| scene | engine | Hz | ms / step | ms / simulated s | carom / engine, per step "
            "| carom / engine, per simulated s |",
            "|---|---|---|---|---|---|---|",
            *timing,
            "",
            "The same scenes under the monitor (one run, untimed):",
            "",
            "| scene | engine | top moved [m] | largest turn [deg] | deepest overlap [m] "
            "| through |",
            "|---|---|---|---|---|---|",
            *checks,
            "",
            *verdict,
        ]
    )
    print(body)
    if not args.no_record:
        record("rigid3d: carom beside Rapier, MuJoCo and pybullet", body.rstrip() + "\n")


if __name__ == "__main__":
    main()
