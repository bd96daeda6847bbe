"""The ``carom`` command.

Exit codes: 0 success, 2 bad input or usage (one message, no traceback; ``--debug`` shows it),
130 interrupted.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import sys
import traceback
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from carom import __version__
from carom.errors import CaromError

__all__ = ["main"]


def _build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="carom",
        description=(
            "carom: exact, impulse-based collision response of rigid spheres. "
            "Run 'carom COMMAND --help' for the options of each command."
        ),
    )
    parser.add_argument("--version", action="version", version=f"carom {__version__}")
    parser.add_argument(
        "--debug", action="store_true", help="show the full traceback when something fails"
    )
    commands = parser.add_subparsers(dest="command", metavar="COMMAND", required=True)

    cases = commands.add_parser(
        "cases",
        help="the seven-case two-sphere study: carom against Hecker's impulse formula",
        description=(
            "Compute seven two-sphere collision cases (head-on and oblique; equal and unequal "
            "masses; towards each other and the same way; elastic to perfectly plastic) with "
            "carom's law and with Hecker's impulse formula, both with the contact normal and in "
            "its one-dimensional head-on reading. Every answer is compared with the exact "
            "one (rational arithmetic); the conclusion printed is derived from these numbers. "
            "With --out DIR, writes DIR/cases.csv, DIR/cases.json and one PNG per case."
        ),
    )
    cases.add_argument(
        "--out", type=Path, metavar="DIR", help="write cases.csv, cases.json and case-N.png here"
    )
    cases.add_argument(
        "--json", action="store_true", help="print the results as JSON instead of the table"
    )
    cases.add_argument(
        "--brief",
        action="store_true",
        help="print only the summary table, not every case's inputs and velocities",
    )
    cases.add_argument(
        "--force", action="store_true", help="replace DIR if it exists and is not empty"
    )
    cases.add_argument(
        "--no-figures",
        action="store_true",
        help="skip the PNG figures (they need the viz extra: matplotlib)",
    )
    cases.set_defaults(handler=_cmd_cases)

    scenes = commands.add_parser(
        "scenes",
        help="list the built-in scenes",
        description="List the scenes that ship with carom: name, title and what they show.",
    )
    scenes.set_defaults(handler=_cmd_scenes)

    run = commands.add_parser(
        "run",
        help="run a scene (a built-in name or a TOML file) and write its results",
        description=(
            "Run a scene exactly, event by event, and write DIR/trajectory.h5 (H5MD: positions "
            "and velocities every frame interval, read by OVITO and MDAnalysis), "
            "DIR/events.csv (every collision: time, bodies or wall, impulse, normal speeds "
            "before and after) and DIR/summary.json (observables, energy balance, momentum, "
            "counts, speed), and plots: energy and momentum against time, the collision rate, "
            "and for a gas the speed distribution against Maxwell-Boltzmann. "
            "Scene files are described in docs/scenes.md; 'carom scenes' lists the built-in "
            "ones. Nothing is written unless the whole run succeeds."
        ),
    )
    run.add_argument("scene", metavar="SCENE_OR_FILE", help="a built-in scene name or a path")
    run.add_argument("--out", type=Path, required=True, metavar="DIR", help="results go here")
    run.add_argument(
        "--until", type=float, metavar="T", help="simulated time [s] (default: the scene's)"
    )
    run.add_argument(
        "--no-events", action="store_true", help="do not log collisions (no events.csv)"
    )
    run.add_argument(
        "--no-trajectory", action="store_true", help="do not write trajectory.h5 (H5MD)"
    )
    run.add_argument(
        "--no-plots",
        action="store_true",
        help="skip energy.png, collision_rate.png and speeds.png (they need matplotlib)",
    )
    run.add_argument(
        "--force", action="store_true", help="replace DIR if it exists and is not empty"
    )
    run.set_defaults(handler=_cmd_run)
    return parser


def _cmd_run(args: argparse.Namespace) -> int:
    import time

    from carom.io.h5md import H5MDWriter, check_trajectory, need_h5py
    from carom.io.outdir import check_output, staged_output
    from carom.io.results import summary, write_events_csv, write_summary
    from carom.scene import find_scene, load_scene
    from carom.viz import require_matplotlib
    from carom.viz.run import RunHistory, write_run_plots
    from carom.world import Frame

    path = find_scene(args.scene)
    scene = load_scene(path)
    until = scene.run["until"] if args.until is None else args.until
    if not (until > 0 and until < float("inf")):
        raise CaromError(f"--until must be a positive number of seconds; got {args.until!r}")
    world = scene.build()
    check_output(args.out, force=args.force)
    # a missing extra is found before running, not after a whole run
    if not args.no_trajectory:
        need_h5py()
    if not args.no_plots:
        require_matplotlib()
    frame_dt = scene.run["frame_interval"]
    history = RunHistory()
    written = []
    with staged_output(args.out, force=args.force) as staging:
        writer = None if args.no_trajectory else H5MDWriter(staging / "trajectory.h5", world)
        writing = 0.0

        def record(frame: Frame) -> None:
            nonlocal writing
            mark = time.perf_counter()
            history.add(world, frame)
            if writer is not None:
                writer.write(frame, history.kinetic[-1])
            writing += time.perf_counter() - mark

        record(world.frame())
        began = time.perf_counter()
        try:
            for frame in world.frames(until, frame_dt, log=not args.no_events):
                record(frame)
            if frame_dt is None:
                record(world.frame())
        finally:
            if writer is not None:
                writer.close()
        wall = time.perf_counter() - began - writing
        if writer is not None:
            check_trajectory(staging / "trajectory.h5", world, writer.frames)
            written.append("trajectory.h5")
        start = {
            "kinetic_energy": history.kinetic[0],
            "potential_energy": history.potential[0],
            "momentum": history.momentum[0].tolist(),
        }
        data = summary(world, scene=str(path), start=start, wall_seconds=wall)
        if not args.no_events:
            write_events_csv(world, staging / "events.csv")
            written.append("events.csv")
        write_summary(data, staging / "summary.json")
        written.append("summary.json")
        if not args.no_plots:
            written += write_run_plots(staging, world, history, world.events["time"])
    title = scene.scene.get("title") or path.stem
    rate = world.stats.collisions / wall if wall > 0 else float("inf")
    print(
        f"{title}: {world.n_bodies} bodies, {until:g} s simulated, "
        f"{world.stats.collisions} collisions and {world.stats.wall_collisions} at walls "
        f"in {wall:.2f} s ({rate:.3g} collisions/s)"
    )
    print(f"wrote {', '.join(written)} to {args.out}/")
    return 0


def _cmd_scenes(args: argparse.Namespace) -> int:
    import textwrap

    from carom.scene import builtin_scenes, load_scene

    for name, path in builtin_scenes().items():
        scene = load_scene(path)
        title = scene.scene.get("title") or name
        print(f"{name}\n  {title}")
        description = scene.scene.get("description")
        if description:
            print(textwrap.indent(textwrap.fill(description, 76), "    "))
    return 0


def _cmd_cases(args: argparse.Namespace) -> int:
    from carom.cases import (
        MODELS,
        ROUND_OFF,
        conclusions,
        format_details,
        format_table,
        run_study,
    )
    from carom.io.outdir import check_output, staged_output

    if args.out is not None:
        check_output(args.out, force=args.force)
    records = run_study()
    findings = conclusions(records)
    document: dict[str, Any] = {
        "carom_version": __version__,
        "models": MODELS,
        "round_off": ROUND_OFF,
        "records": [r.to_dict() for r in records],
        "conclusions": findings,
    }
    if args.out is not None:
        figures = not args.no_figures and _have_matplotlib()
        with staged_output(args.out, force=args.force) as staging:
            (staging / "cases.json").write_text(json.dumps(document, indent=2) + "\n")
            _write_cases_csv(staging / "cases.csv", document["records"])
            if figures:
                from carom.viz.cases import plot_case

                for number in sorted({r.case for r in records}):
                    plot_case(
                        [r for r in records if r.case == number], staging / f"case-{number}.png"
                    )

    if args.json:
        print(json.dumps(document, indent=2))
    else:
        if not args.brief:
            print(format_details(records))
            print("Summary")
        print(format_table(records))
        print()
        print("Conclusions (derived from the numbers above):")
        for line in findings:
            print(f"  {line}")
    if args.out is not None:
        written = "cases.csv, cases.json" + (", case-1.png ... case-7.png" if figures else "")
        print(f"\nwrote {written} to {args.out}/", file=sys.stderr if args.json else sys.stdout)
    return 0


def _have_matplotlib() -> bool:
    """Whether figures can be drawn; says how to get them when not."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        print(
            "note: figures skipped, matplotlib is not installed "
            "(pip install 'carom[viz]', or pass --no-figures)",
            file=sys.stderr,
        )
        return False
    return True


def _write_cases_csv(path: Path, records: list[dict[str, Any]]) -> None:
    """One row per case, restitution and model (the exact answer is the model 'exact')."""
    columns = [
        "case",
        "title",
        "e",
        "model",
        "m1",
        "m2",
        "x1_x",
        "x1_y",
        "x2_x",
        "x2_y",
        "v1_x",
        "v1_y",
        "v2_x",
        "v2_y",
        "v1_after_x",
        "v1_after_y",
        "v2_after_x",
        "v2_after_y",
        "error",
        "momentum_error",
        "ke_before",
        "ke_after",
        "ke_lost",
        "energy_error",
        "separation_speed",
        "relative_speed_after",
        "angle_deg",
        "gap_after_1s",
    ]
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(columns)
        for rec in records:
            outcomes = {"exact": rec["exact"], **rec["models"]}
            for model, out in outcomes.items():
                row = [
                    rec["case"],
                    rec["title"],
                    rec["e"],
                    model,
                    rec["m1"],
                    rec["m2"],
                    *rec["x1"],
                    *rec["x2"],
                    *rec["v1"],
                    *rec["v2"],
                    *out["v1_after"],
                    *out["v2_after"],
                ]
                row += [out[c] for c in columns[len(row) :]]
                writer.writerow(
                    ["" if v is None else repr(v) if isinstance(v, float) else v for v in row]
                )


def main(argv: Sequence[str] | None = None) -> int:
    """Run the carom command; return the exit code."""
    parser = _build_parser()
    args = parser.parse_args(argv)
    try:
        code: int = args.handler(args)
        return code
    except CaromError as exc:
        if args.debug:
            traceback.print_exc()
        print(f"carom: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print("carom: interrupted; nothing was written", file=sys.stderr)
        return 130
    except BrokenPipeError:
        # the reader went away (carom cases | head): stop quietly, as other tools do
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 0
