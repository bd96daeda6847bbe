"""The ``carom`` command.

Exit codes: 0 success, 1 a sweep finished with failed points (their messages are in its
table), 2 bad input or usage (one message, no traceback; ``--debug`` shows it), 130
interrupted (Ctrl-C), 143 stopped by SIGTERM (carom run and carom sweep).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import traceback
from collections.abc import Sequence
from pathlib import Path

from carom import __version__
from carom._text import plural, printable
from carom.errors import CaromError
from carom.limits import LARGEST, SMALLEST

__all__ = ["main"]


def _build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="carom",
        description=(
            "carom: impulse-based collision response of rigid bodies: spheres and disks "
            "simulated exactly, event by event; bodies of any shape in 2D and 3D, step by "
            "step. "
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
            "counts, speed), plots (energy and momentum against time, the collision rate, "
            "and for a gas the speed distribution against Maxwell-Boltzmann) and "
            "DIR/animation.mp4. Scene files are described in docs/scenes.md; 'carom scenes' "
            "lists the built-in ones; a scene's [outputs] table chooses the files, the options "
            "below override it. Nothing is written to DIR unless the whole run succeeds: the "
            "run works in .DIR.carom-run/ beside it, where Ctrl-C leaves a checkpoint that "
            "--resume continues from."
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
        "--animation",
        choices=("mp4", "gif", "none"),
        help="the film of the frames: animation.mp4 (the scene's default), .gif, or none",
    )
    run.add_argument(
        "--force",
        action="store_true",
        help="replace DIR if it exists and is not empty; discard an interrupted run of DIR",
    )
    run.add_argument(
        "--resume",
        action="store_true",
        help="continue the interrupted run of DIR from its checkpoint (same results as an "
        "uninterrupted run)",
    )
    run.add_argument(
        "--checkpoint-every",
        type=float,
        default=60.0,
        metavar="SECONDS",
        help="wall-clock time between checkpoints (default 60); Ctrl-C always writes one",
    )
    run.add_argument("--quiet", action="store_true", help="no progress bar")
    run.set_defaults(handler=_cmd_run)

    view = commands.add_parser(
        "view",
        help="replay a run in the rerun viewer (timeline, spheres, velocities, energy)",
        description=(
            "Write DIR/recording.rrd from the trajectory that 'carom run' wrote to DIR: the "
            "box, every body as a shaded sphere coloured by speed, velocity arrows and the "
            "energies, on a timeline of frames and simulated time. It opens in the rerun "
            "viewer when a display is available; elsewhere, the path is printed, to open "
            "with 'rerun DIR/recording.rrd' on a desktop. Needs the view extra: "
            "pip install 'carom[view]'."
        ),
    )
    view.add_argument("folder", type=Path, metavar="DIR", help="a 'carom run' output directory")
    view.add_argument(
        "--no-open", action="store_true", help="only write the recording, do not start the viewer"
    )
    view.set_defaults(handler=_cmd_view)

    play = commands.add_parser(
        "play",
        help="run a scene live in the browser: drag bodies, shoot balls, tune it as it runs",
        description=(
            "Start a local server that runs SCENE (a built-in scene's name or a scene file; "
            "default pyramid) in real time and serves a page that draws it: drag bodies "
            "with the mouse, shoot balls, pause, step, slow down, reset, pick another scene, "
            "change gravity, restitution, friction and substeps as it runs, and draw "
            "contacts, joints, islands and the broad phase's boxes (docs/play.md). Bound to "
            "this machine (127.0.0.1) unless --host says otherwise; Ctrl-C stops it. Needs "
            "the play extra: pip install 'carom[play]'."
        ),
    )
    play.add_argument("scene", nargs="?", default="pyramid", metavar="SCENE")
    play.add_argument("--port", type=int, default=8765, help="default 8765; 0 picks a free one")
    play.add_argument(
        "--host",
        default="127.0.0.1",
        metavar="ADDR",
        help="the address to listen on (default 127.0.0.1; 0.0.0.0 lets other machines in)",
    )
    play.add_argument("--no-open", action="store_true", help="do not open the page in a browser")
    play.set_defaults(handler=_cmd_play)

    compare = commands.add_parser(
        "compare",
        help="the same scene in carom, pymunk, pybullet and MuJoCo, measured side by side",
        description=(
            "Run SCENE (a built-in name or a .toml file) in carom and its peers, each set up "
            "as its documentation recommends, and measure every engine the same way: "
            "post-collision velocities against the closed form (two spheres, Newton's "
            "cradle, a bouncing ball), energy error, deepest penetration, tunnelling, and "
            "wall time for the same simulated time. Prints a table; with --out, writes "
            "compare.json (every setting of every engine), compare.txt and compare.png. "
            "The peers come with the compare extra: pip install 'carom[compare]'."
        ),
    )
    compare.add_argument("scene", metavar="SCENE", help="built-in scene name or .toml file")
    compare.add_argument(
        "--engines",
        metavar="LIST",
        help="comma-separated engines (carom, pymunk, pybullet, mujoco); default: every "
        "installed engine for the scene's dimension",
    )
    compare.add_argument("--out", type=Path, metavar="DIR", help="write the results here")
    compare.add_argument(
        "--until", type=float, metavar="SECONDS", help="simulated time (default: the scene's)"
    )
    compare.add_argument("--no-plot", action="store_true", help="no compare.png")
    compare.add_argument("--quiet", action="store_true", help="no progress bars")
    compare.add_argument(
        "--force", action="store_true", help="replace DIR if it exists and is not empty"
    )
    compare.set_defaults(handler=_cmd_compare)

    sweep = commands.add_parser(
        "sweep",
        help="run a scene over a grid of parameters and seeds on Dask, and plot observables",
        description=(
            "Run every point of a parameter sweep (a base scene, the keys to vary, the seeds "
            "and the observables: docs/sweeps.md) as a task on Dask: a local cluster of "
            "--workers processes, or the workers of the scheduler at --scheduler. Rows land in "
            "DIR/results.csv (and results.parquet with pyarrow) as points finish, so Ctrl-C or "
            "a crash loses nothing done and --resume runs only what is missing. A failing "
            "point is a row with its message; the others go on. Writes a plot of each "
            "observable against the parameter, with the closed form where carom knows it. "
            "Built-in sweeps: " + ", ".join(_builtin_sweep_names()) + ". Needs the sweep "
            "extra: pip install 'carom[sweep]'."
        ),
    )
    sweep.add_argument("sweep", metavar="SWEEP", help="a sweep file, or a built-in sweep's name")
    sweep.add_argument("--out", type=Path, required=True, metavar="DIR", help="results go here")
    sweep.add_argument(
        "--workers",
        type=int,
        metavar="N",
        help="worker processes of the local cluster (default: one per core)",
    )
    sweep.add_argument(
        "--scheduler",
        metavar="ADDRESS",
        help="run on an existing Dask cluster: its scheduler's address, e.g. tcp://host:8786",
    )
    sweep.add_argument(
        "--resume",
        action="store_true",
        help="continue the sweep in DIR: run only the points it has no result for",
    )
    sweep.add_argument(
        "--force", action="store_true", help="replace DIR if it exists and is not empty"
    )
    sweep.add_argument("--no-plots", action="store_true", help="no plot-*.png")
    sweep.add_argument("--quiet", action="store_true", help="no progress bar")
    sweep.set_defaults(handler=_cmd_sweep)

    showcase = commands.add_parser(
        "showcase",
        help="the two-sphere study, a few scenes and a sweep, with DIR/index.html showing them",
        description=(
            "Run the seven-case two-sphere study; the scenes case-1 ... case-7, "
            "newtons-cradle, billiards-break, hard-sphere-gas, rod-drop, card-house, pyramid "
            "and tumbler; and the eos-2d sweep on a local Dask cluster (with the sweep extra); "
            "write their results under DIR (cases/, scenes/NAME/, sweeps/NAME/) and "
            "DIR/index.html, one page linking and showing every figure, film and table. This "
            "is what 'make demo' runs."
        ),
    )
    showcase.add_argument("--out", type=Path, default=Path("out"), metavar="DIR")
    showcase.add_argument(
        "--force", action="store_true", help="replace DIR if it exists and is not empty"
    )
    showcase.set_defaults(handler=_cmd_showcase)
    return parser


def _check_seconds(option: str, value: float | None) -> None:
    """Refuse an option that is given but is not a number of seconds within the limits."""
    if value is not None and not (SMALLEST <= value <= LARGEST):
        raise CaromError(
            f"{option} must be a number of seconds from {SMALLEST:g} to {LARGEST:g}; got {value!r}"
        )


def _cmd_compare(args: argparse.Namespace) -> int:
    from carom.compare import compare
    from carom.compare.report import format_table, write_comparison
    from carom.io.outdir import check_output, staged_output

    _check_seconds("--until", args.until)
    engines = None
    if args.engines is not None:
        engines = [e.strip() for e in args.engines.split(",") if e.strip()]
        if not engines:
            raise CaromError("--engines needs at least one engine name, e.g. carom,pymunk")
    plot = args.out is not None and not args.no_plot and _have_matplotlib()
    if args.out is not None:
        check_output(args.out, force=args.force)  # refuse before minutes of simulation
    result = compare(
        args.scene,
        engines,
        until=args.until,
        progress=False if args.quiet else None,
    )
    print(format_table(result))
    if args.out is not None:
        with staged_output(args.out, force=args.force) as folder:
            written = write_comparison(result, folder, plot=plot)
        print(f"wrote {', '.join(written)} to {args.out}/")
    return 0


def _builtin_sweep_names() -> list[str]:
    from carom.sweeps.spec import builtin_sweeps

    return list(builtin_sweeps())


def _cmd_sweep(args: argparse.Namespace) -> int:
    from carom.sweeps import SweepInterrupted, load_sweep, sweep

    spec = load_sweep(args.sweep)
    plots = not args.no_plots and _have_matplotlib()
    try:
        report = sweep(
            spec,
            args.out,
            workers=args.workers,
            scheduler=args.scheduler,
            resume=args.resume,
            force=args.force,
            progress=False if args.quiet else None,
            plots=plots,
        )
    except SweepInterrupted as stopped:
        print(
            printable(f"carom: {stopped}; continue with: {_resume_command(args.argv)}"),
            file=sys.stderr,
        )
        return 128 + stopped.signal
    points = spec.count()
    seeds = len(spec.seeds) if spec.seeds else 1
    done = "" if report.ran == report.runs else f" ({report.runs - report.ran} done before)"
    print(
        f"{report.title}: {plural(report.runs, 'run')} ({plural(points, 'point')} x "
        f"{plural(seeds, 'seed')}){done} on {plural(report.workers, 'worker')} in "
        f"{report.wall_seconds:.1f} s; {report.failed} failed"
    )
    print(f"wrote {', '.join(report.written)} to {args.out}/")
    return 0 if report.failed == 0 else 1


def _cmd_showcase(args: argparse.Namespace) -> int:
    from carom.run.showcase import build_showcase

    page = build_showcase(args.out, force=args.force)
    print(f"\nopen {page} in a browser")
    return 0


def _cmd_play(args: argparse.Namespace) -> int:
    from carom.play.server import PlayServer, need_websockets, run

    need_websockets()
    if not 0 <= args.port <= 65535:
        raise CaromError(f"--port must be a port number from 0 to 65535; got {args.port}")
    from carom.play.live import Live

    print(f"carom play: loading {args.scene} (the first time compiles the engine's kernels)")
    server = PlayServer(Live(args.scene), args.host, args.port)

    def ready(url: str) -> None:
        where = "" if args.host in ("127.0.0.1", "localhost", "::1") else " (open to the network)"
        print(f"carom play: serving {args.scene} at {url}{where}; Ctrl-C stops it", flush=True)
        if not args.no_open:
            import webbrowser

            webbrowser.open(url)

    try:
        run(server, ready)
    except OSError as error:
        raise CaromError(
            f"cannot listen on {args.host}:{args.port} ({error.strerror or error}); "
            "pass another --port (0 picks a free one) or --host"
        ) from None
    if server.errors:
        raise CaromError(f"the world stopped: {server.errors[0]}")
    print("carom play: stopped")
    return 0


def _cmd_view(args: argparse.Namespace) -> int:
    from carom.viz.replay import can_show, open_viewer, write_recording

    if not args.folder.is_dir():
        raise CaromError(f"{args.folder} is not a directory; give the --out DIR of a 'carom run'")
    recording = write_recording(args.folder)
    if args.no_open or not can_show():
        why = "" if args.no_open else " (no display here)"
        print(f"wrote {recording}{why}; open it on a desktop with: rerun {recording}")
        return 0
    open_viewer(recording)
    print(f"wrote {recording}; opening it in the rerun viewer")
    return 0


def _cmd_run(args: argparse.Namespace) -> int:
    from carom.jit import kernels_cached
    from carom.run.runner import Outputs, RunInterrupted, run_scene, with_overrides
    from carom.scene import find_scene, load_scene

    _check_seconds("--until", args.until)
    _check_seconds("--checkpoint-every", args.checkpoint_every)
    scene = load_scene(find_scene(args.scene))
    outputs = with_overrides(
        Outputs.of(scene),
        trajectory=False if args.no_trajectory else None,
        events=False if args.no_events else None,
        plots=False if args.no_plots else None,
        animation=args.animation,
    )
    if not kernels_cached():
        print(
            "carom: compiling the engine's kernels (once per install; 10 to 20 s)...",
            file=sys.stderr,
            flush=True,
        )
    try:
        report = run_scene(
            args.scene,
            args.out,
            until=args.until,
            outputs=outputs,
            resume=args.resume,
            force=args.force,
            progress=False if args.quiet else None,
            checkpoint_every=args.checkpoint_every,
        )
    except KeyboardInterrupt:
        from carom.run.runner import CHECKPOINT, work_directory

        kept = (work_directory(Path(args.out)) / CHECKPOINT).is_file()
        print(
            printable(
                f"carom: interrupted at once (a second Ctrl-C); nothing was written to "
                f"{args.out}"
                + (
                    f"; its last checkpoint is kept: continue with: {_resume_command(args.argv)}"
                    if kept
                    else ""
                )
            ),
            file=sys.stderr,
        )
        return 130
    except RunInterrupted as stopped:
        print(
            printable(
                f"carom: {stopped}; nothing was written to {args.out}. Continue with: "
                f"{_resume_command(args.argv)}"
            ),
            file=sys.stderr,
        )
        return 128 + stopped.signal
    resumed = "" if report.resumed_at is None else f" (resumed at {report.resumed_at:g} s)"
    prepared = (
        f"; kernels compiled or loaded in {report.prepare_seconds:.1f} s before it"
        if report.prepare_seconds >= 1.0
        else ""
    )
    print(
        f"{report.title}: {plural(report.bodies, 'body', 'bodies')}, {report.simulated:g} s "
        f"simulated{resumed}, {report.work()}{prepared}"
    )
    print(f"wrote {', '.join(report.written)} to {args.out}/")
    return 0


def _resume_command(argv: Sequence[str]) -> str:
    """The command line that continues an interrupted ``carom run argv``: the same options
    (so that the run's until, outputs and scene match its checkpoint), ``--resume`` instead
    of ``--force``, quoted for a POSIX shell."""
    import shlex

    kept = [a for a in argv if a not in ("--force", "--resume")]
    return shlex.join(["carom", *kept, "--resume"])


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
    from carom.io.outdir import check_output, staged_output
    from carom.run.study import case_document, write_case_study
    from carom.studies.two_spheres import conclusions, format_details, format_table, run_study

    if args.out is not None:
        check_output(args.out, force=args.force)
    records = run_study()
    findings = conclusions(records)
    document = case_document(records)
    if args.out is not None:
        figures = not args.no_figures and _have_matplotlib()
        with staged_output(args.out, force=args.force) as staging:
            write_case_study(staging, records, figures=figures)

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


def main(argv: Sequence[str] | None = None) -> int:
    """Run the carom command; return the exit code."""
    parser = _build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    try:
        args = parser.parse_args(argv)
    except SystemExit:
        _flush_stdout()  # --help and --version print, then exit: to a reader that may be gone
        raise
    args.argv = argv
    try:
        code: int = args.handler(args)
    except CaromError as exc:
        if args.debug:
            traceback.print_exc()
        print(printable(f"carom: error: {exc}", one_line=True), file=sys.stderr)
        _end_if_hdf5_is_broken(2)
        return 2
    except KeyboardInterrupt:
        print("carom: interrupted; nothing was written", file=sys.stderr)
        return 130
    except BrokenPipeError:
        _reader_gone()
        return 0
    _flush_stdout()
    return code


def _end_if_hdf5_is_broken(code: int) -> None:
    """After a trajectory write failed (a full disk), HDF5 cannot close the file and crashes
    when the interpreter exits; the message is out, so end the process here, cleanly."""
    h5md = sys.modules.get("carom.io.h5md")
    if h5md is not None and h5md.write_failed():
        _flush_stdout()
        sys.stderr.flush()
        os._exit(code)


def _flush_stdout() -> None:
    """Flush standard output now, so that a reader that went away (carom cases | head) is
    found here and not when the interpreter flushes at exit (exit code 120, a traceback)."""
    try:
        sys.stdout.flush()
    except BrokenPipeError:
        _reader_gone()


def _reader_gone() -> None:
    """The reader of standard output went away: stop quietly, as other tools do, sending
    whatever is still buffered nowhere."""
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)
