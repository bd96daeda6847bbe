"""carom's 2D rigid engine beside Box2D v3 (C), pymunk and Box2D 2.3 on Box2D's benchmark
pyramids: ms per step on one core, interleaved round by round, and how steady the pyramid is.

The scenes are the built-in ``large-pyramid`` (100 rows, 5050 unit boxes, 60 Hz, carom at 4
substeps, 10 s) and ``many-pyramids`` (400 pyramids of 10 rows, 22,000 boxes, 5 s), sleep off.
Each engine is set up as its documentation recommends (docs/compare.md; Box2D v3 as its own
benchmark app sets it up, 60 Hz, 4 substeps, continuous on).

**Timing** (benchmarks/steppers.py): this process and every engine in it are pinned to one
core; each timed run steps the scene bare, only the step calls timed and nothing read between
steps; every engine runs once a round, the order rotating round by round; ``--rounds`` rounds
(5 by default). Box2D v3 is not on PyPI: given its source tree (``--box2d-v3 DIR``, a clone of
erincatto/box2d), this script builds it with cmake twice, its default (SSE2) build and its
``BOX2D_AVX2=ON`` build where the processor has AVX2, and runs carom's harness around its C
API (benchmarks/box2d_v3/pyramid.c) as a child process on the same core, interleaved with the
others. Reported: each engine's median ms per step and spread, and carom / peer round by round
(median, least-greatest): below 1 carom is faster.

**Accuracy**: one more run of the Python engines under ``carom compare``'s monitor (untimed
here: the monitor's reads between steps slow the next step, differently for each engine), and
Box2D v3's pyramid at the end of its run.

**Steadiness** (``--steady SECONDS``, the large pyramid; issue 46 item 4): the top box's
path in carom and in Box2D v3 (AVX2 build), step by step: how far it moved in all, its sideways
sway and its height's range after settling, where it settles off centre, and at the end the
largest turn and the largest speed of any box.

Run:  python benchmarks/rigid2d.py --box2d-v3 ~/src/box2d      (appends to RESULTS.md)
      python benchmarks/rigid2d.py --box2d-v3 ~/src/box2d --steady 20
      python benchmarks/rigid2d.py --scenes large-pyramid --until 2 --rounds 3 --no-record
Needs the compare extra: pip install -e '.[compare]'.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
import tomllib
from pathlib import Path
from typing import Any

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))

from edmd import record
from steppers import Box2DV3, bare_ms, interleave, monitored, one_core, ratios, spread

from carom.compare import compare, peer_scene
from carom.compare.engines import ENGINES
from carom.scene import Scene, find_scene

ENGINE_NAMES = ["carom", "pymunk", "box2d"]
#: the harness's name for each scene Box2D v3 runs
BOX2D_SCENES = {"large-pyramid": "large", "many-pyramids": "many"}
#: after these times [s] the pyramid has settled: sway is measured from SWAY_FROM to
#: SWAY_UNTIL, the height's range from HEIGHT_FROM to the end (issue 46)
SWAY_FROM, SWAY_UNTIL, HEIGHT_FROM = 2.0, 10.0, 3.0
#: Box2D v3's top box of the large pyramid at the start [m]: row 99, over its ground's centre
BOX2D_TOP = (0.0, 99.5)


def time_scene(name: str, until: float | None, rounds: int, v3: Box2DV3 | None) -> list[str]:
    """Time ``name`` in every engine, interleaved; return the table's rows."""
    scene = peer_scene(name, until)
    compare(peer_scene(name, 0.1), ["carom"])  # compile the kernels, untimed
    runs: dict[str, Any] = {e: (lambda e=e: bare_ms(e, scene)) for e in ENGINE_NAMES}
    if v3 is not None and name in BOX2D_SCENES:
        for kind in v3.builds:
            args = (BOX2D_SCENES[name], str(scene.until), "1")
            runs[f"box2d-v3 {kind}"] = lambda k=kind, a=args: v3.run(k, *a)["ms_per_step"]
    times = interleave(runs, rounds)
    return [
        f"| {name} | {e} | {spread(times[e])} | {spread(each)} |"
        for e, each in ratios(times).items()
    ]


def accuracy(name: str, until: float | None, v3: Box2DV3 | None) -> list[str]:
    """One monitored run of the Python engines (and Box2D v3's end state): their rows."""
    fields = ["top_drift_m", "final_rotation_deg", "max_overlap_m"]
    rows, runs = monitored(name, ENGINE_NAMES, until, fields)
    if v3 is not None and name == "large-pyramid":
        seconds = str(runs["carom"]["simulated_s"])
        end = v3.run(v3.builds[-1], "large", seconds, "1")
        rows.append(
            f"| {name} | Box2D v3 {v3.version} | {end['top_moved_m']:.3g} | "
            f"{end['max_turn_deg']:.3g} | - |"
        )
    return rows


def pyramid(rows: int) -> Scene:
    """The large pyramid's scene with ``rows`` rows (its ground, boxes and settings)."""
    data = tomllib.loads(find_scene("large-pyramid").read_text())
    data["pyramid"][0]["rows"] = rows
    return Scene.from_dict(data, source=f"large-pyramid, {rows} rows")


def small_drift(rows: int = 20, start: float = 2.0, end: float = 5.0) -> float:
    """How far [m] the top box of a ``rows``-row pyramid (unit boxes) moves from ``start`` to
    ``end`` [s] in carom, at the most (issue 46 item 4: under 1% of its size)."""
    path = carom_path(end, pyramid(rows))[0]
    later = path[path[:, 0] >= start - 1e-9]
    return float(np.hypot(*(later[:, 1:3] - later[0, 1:3]).T).max())


def carom_path(
    seconds: float, scene_file: Scene | str = "large-pyramid"
) -> tuple[np.ndarray, tuple[float, float], float, float]:
    """carom's large pyramid (or ``scene_file``) for ``seconds``: the top box's ``t x y
    angle`` after each step, where it started [m], and at the end the largest turn of any box
    [deg] and the largest speed [m/s]."""
    scene = peer_scene(scene_file, seconds, name="pyramid")
    sim = ENGINES["carom"].start(scene)
    path = []
    for k in range(scene.steps(sim.dt)):
        sim.step()
        x, _, turn, _ = sim.state()
        path.append((sim.dt * (k + 1), x[-1, 0], x[-1, 1], turn[-1]))
    x, v, turn, _ = sim.state()
    dynamic = scene.model.inv_mass > 0.0
    largest_turn = float(np.degrees(np.abs(turn[dynamic]).max()))
    top = (float(scene.start.x[-1, 0]), float(scene.start.x[-1, 1]))
    return np.array(path), top, largest_turn, float(np.linalg.norm(v[dynamic], axis=1).max())


def measures(
    path: np.ndarray, start: tuple[float, float], turn_deg: float, speed: float
) -> dict[str, float]:
    """The steadiness measures of a top box's path (rows ``t x y angle``) from ``start``."""
    t, x, y = path[:, 0], path[:, 1], path[:, 2]
    swaying = (t >= SWAY_FROM) & (t <= SWAY_UNTIL)
    settled = t >= HEIGHT_FROM
    return {
        "moved [m]": float(np.hypot(x[-1] - start[0], y[-1] - start[1])),
        f"sway {SWAY_FROM:g}-{SWAY_UNTIL:g} s [m]": float(np.ptp(x[swaying])),
        f"height's range {HEIGHT_FROM:g} s on [mm]": 1e3 * float(np.ptp(y[settled])),
        "off centre at the end [m]": float(abs(x[-1] - start[0])),
        "largest turn at the end [deg]": turn_deg,
        "largest speed at the end [m/s]": speed,
    }


def steadiness(seconds: float, v3: Box2DV3 | None) -> str:
    """The large pyramid's steadiness in carom and Box2D v3, as a table."""
    found = {"carom": measures(*carom_path(seconds))}
    if v3 is not None:
        kind = v3.builds[-1]
        path = np.array(v3.trace(kind, "large", str(seconds), "1"))
        end = v3.run(kind, "large", str(seconds), "1")
        found[f"Box2D v3 {kind}"] = measures(
            path, BOX2D_TOP, end["max_turn_deg"], end["max_speed_m_s"]
        )
    names = list(found)
    lines = [f"| measure (large pyramid, {seconds:g} s) | " + " | ".join(names) + " |"]
    lines.append("|---" * (len(names) + 1) + "|")
    for key in found["carom"]:
        lines.append(f"| {key} | " + " | ".join(f"{found[n][key]:.3g}" for n in names) + " |")
    drift = small_drift()
    lines += [
        "",
        f"20-row pyramid (the same boxes and settings), carom: the top box moved {drift:.3g} m "
        f"at the most from 2 s to 5 s (target: under 0.01 m, 1% of its size): "
        f"{'met' if drift < 0.01 else 'missed'}",
    ]
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--scenes", nargs="+", default=["large-pyramid", "many-pyramids"])
    parser.add_argument("--until", type=float, help="simulated time [s]; default the scene's")
    parser.add_argument("--rounds", type=int, default=5, help="timed runs of each engine")
    parser.add_argument("--box2d-v3", type=Path, metavar="DIR", help="a Box2D v3 source tree")
    parser.add_argument("--steady", type=float, metavar="SECONDS", help="steadiness run [s]")
    parser.add_argument("--no-record", action="store_true", help="do not append to RESULTS.md")
    args = parser.parse_args()
    missing = [ENGINES[n].missing() for n in ENGINE_NAMES if ENGINES[n].missing() is not None]
    if missing:
        sys.exit("; ".join(str(m) for m in missing))
    core = one_core()
    with tempfile.TemporaryDirectory(prefix="box2d-v3-") as build:
        v3 = Box2DV3(args.box2d_v3, Path(build)) if args.box2d_v3 else None
        timing, checks = [], []
        for name in args.scenes:
            timing += time_scene(name, args.until, args.rounds, v3)
            checks += accuracy(name, args.until, v3)
        steady = steadiness(args.steady, v3) if args.steady else ""
    body = "\n".join(
        [
            f"ms per step on core {core}, {args.rounds} rounds interleaved, bare steps "
            "(median (least-greatest)); carom / peer round by round (below 1: carom faster):",
            "",
            "| scene | engine | ms / step | carom / engine |",
            "|---|---|---|---|",
            *timing,
            "",
            "The same scenes under the monitor (one run, untimed):",
            "",
            "| scene | engine | top moved [m] | largest turn at the end [deg] "
            "| deepest overlap [m] |",
            "|---|---|---|---|---|",
            *checks,
            "",
            steady,
        ]
    )
    print(body)
    if not args.no_record:
        record("rigid2d: carom beside Box2D v3, pymunk and Box2D 2.3", body.rstrip() + "\n")


if __name__ == "__main__":
    main()
