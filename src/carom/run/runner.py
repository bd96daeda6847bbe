"""The job behind ``carom run``: run a scene, write its results, survive interruption.

A run works in a directory of its own beside the output, ``.DIR.carom-run/``: the
trajectory grows there frame by frame and a checkpoint (the world, bit for bit, and the
run's progress) is written there every ``checkpoint_every`` seconds and when the run is
interrupted (Ctrl-C). Only a finished run is moved to ``DIR``, by renames, so ``DIR`` never
holds half-written files. ``resume=True`` continues from the checkpoint; because the engine
stops and restarts at frame times without changing a bit, a resumed run writes the same
trajectory, events and summary as one that was never interrupted.
"""

from __future__ import annotations

import contextlib
import hashlib
import json
import math
import shutil
import signal
import sys
import threading
import time
from collections.abc import Iterator
from dataclasses import asdict, dataclass, field, replace
from pathlib import Path
from types import FrameType
from typing import Any, Literal

import numpy as np

from carom._text import plural
from carom.errors import CaromError
from carom.limits import LARGEST, MAX_FRAMES, SMALLEST
from carom.observables import RunHistory
from carom.recording import check_steps
from carom.scene import Scene, find_scene, load_scene
from carom.world import World

__all__ = [
    "Outputs",
    "RunInterrupted",
    "RunReport",
    "run_scene",
    "stop_on_signals",
    "work_directory",
]

CHECKPOINT = "checkpoint.npz"
TRAJECTORY = "trajectory.h5"
EVENTS = "events.csv"
#: progress updates (and chances to stop) per run when the scene asks for no frames
CHUNKS_WITHOUT_FRAMES = 100


@dataclass(frozen=True)
class Outputs:
    """Which files a run writes besides ``summary.json`` (the scene's ``[outputs]`` table)."""

    trajectory: bool = True
    events: bool = True
    plots: bool = True
    animation: Literal["mp4", "gif", "none"] = "mp4"

    @classmethod
    def of(cls, scene: Scene) -> Outputs:
        """The outputs a scene asks for (defaults where it says nothing)."""
        return cls(**{k: v for k, v in scene.outputs.items() if k in cls.__dataclass_fields__})


@dataclass
class RunReport:
    """What a finished run did: for the command's closing lines."""

    title: str
    bodies: int
    simulated: float
    collisions: int
    wall_collisions: int
    wall_seconds: float
    written: list[str] = field(default_factory=list)
    resumed_at: float | None = None
    #: seconds spent before the run compiling the engine's kernels (once per install) or
    #: loading them from the cache; not part of ``wall_seconds``
    prepare_seconds: float = 0.0
    #: the time-stepped (rigid) engine's step [s]; None for the event-driven engine
    step: float | None = None

    def work(self) -> str:
        """What the engine did, and how fast: collisions for the event-driven engine, steps
        (and the impacts it solved exactly) for the time-stepped one."""
        wall = self.wall_seconds
        if self.step is None:
            rate = self.collisions / wall if wall > 0 else float("inf")
            return (
                f"{plural(self.collisions, 'collision')} and {self.wall_collisions} at walls in "
                f"{wall:.2f} s ({rate:.3g} collisions/s)"
            )
        steps = round(self.simulated / self.step)
        each = f", {1e3 * wall / steps:.3g} ms a step" if steps else ""
        impacts = self.collisions + self.wall_collisions
        return (
            f"{plural(steps, 'step')} of {self.step:.4g} s in {wall:.2f} s{each}; "
            f"{plural(impacts, 'impact')} solved exactly"
        )


class RunInterrupted(Exception):  # noqa: N818 (it is not an error: the user asked to stop)
    """The run was stopped (Ctrl-C or SIGTERM); a checkpoint to resume from was written.

    ``signal`` is the number of the signal that asked (``signal.SIGINT`` or ``SIGTERM``).
    """

    def __init__(self, message: str, signal: int) -> None:
        super().__init__(message)
        self.signal = signal


def work_directory(out: Path) -> Path:
    """Where a run writing to ``out`` keeps its trajectory and checkpoint until it is done."""
    return out.parent / f".{out.name}.carom-run"


def run_scene(
    scene_or_file: str | Path,
    out: str | Path,
    *,
    until: float | None = None,
    outputs: Outputs | None = None,
    resume: bool = False,
    force: bool = False,
    progress: bool | None = None,
    checkpoint_every: float = 60.0,
) -> RunReport:
    """Run a scene and write its results to ``out``.

    Parameters
    ----------
    scene_or_file : str or Path
        A built-in scene name or a scene file.
    out : str or Path
        The output directory; it must not exist or be empty, unless ``force``.
    until : float, optional
        Simulated time to reach [s]; the scene's ``[run] until`` by default.
    outputs : Outputs, optional
        What to write; the scene's ``[outputs]`` by default.
    resume : bool
        Continue the interrupted run found in :func:`work_directory` ``(out)``.
    force : bool
        Replace a non-empty ``out``; without ``resume``, discard an interrupted run.
    progress : bool, optional
        Show a progress bar on standard error; by default only when it is a terminal.
    checkpoint_every : float
        Wall-clock seconds between checkpoints [s].

    Returns
    -------
    RunReport

    Raises
    ------
    CaromError
        Bad scene, options or output directory; a missing optional package.
    RunInterrupted
        Ctrl-C: the checkpoint is written, ``out`` untouched; resume with ``resume=True``.
    """
    from carom.io.outdir import check_output, publish

    path = find_scene(scene_or_file)
    scene = load_scene(path)
    until = float(scene.run["until"] if until is None else until)
    if not (SMALLEST <= until <= LARGEST):
        raise CaromError(
            f"until must be a number of seconds from {SMALLEST:g} to {LARGEST:g}; got {until!r}"
        )
    outputs = outputs or Outputs.of(scene)
    target = check_output(Path(out), force=force)
    work = work_directory(target)
    if work.is_symlink() or (work.exists() and not work.is_dir()):
        raise CaromError(
            f"{work} is {'a symbolic link' if work.is_symlink() else 'not a directory'}; carom "
            f"keeps a run's working files there and will not write through it: move it away"
        )
    job = {
        "scene_sha256": hashlib.sha256(path.read_bytes()).hexdigest(),
        "until": until,
        "frame_interval": scene.run["frame_interval"],
        "outputs": asdict(outputs),
    }
    if resume and not (work / CHECKPOINT).is_file():
        raise CaromError(
            f"nothing to resume for {target}: {work / CHECKPOINT} does not exist; run "
            f"without --resume"
        )
    if not resume and work.exists():
        # (a run stopped before its first checkpoint left nothing to resume: replaced)
        if not force and (work / CHECKPOINT).exists():
            raise CaromError(
                f"{work} holds an interrupted run writing to {target}; pass --resume to "
                f"continue it, or --force to start again"
            )
        shutil.rmtree(work)
    _check_extras(outputs)
    _check_size(scene, until, outputs, target)
    began = time.perf_counter()
    if resume:
        run = _Run.resume(work, job)
        run.world.prepare()
    else:
        world = scene.build()  # refuses a bad scene before anything is written
        check_steps(
            world.fixed_step,
            world.engine_name,
            until=until,
            frame_interval=scene.run["frame_interval"],
        )
        world.prepare()  # compiled (or loaded) apart from the run's own time
        _make_directory(work)
        try:
            run = _Run.start(work, world, job)
        except BaseException:
            shutil.rmtree(work, ignore_errors=True)
            raise
    run.prepare_seconds = time.perf_counter() - began
    title = scene.scene.get("title") or path.stem
    try:
        with stop_on_signals() as stop:
            run.simulate(
                until, scene.run["frame_interval"], outputs, progress, stop, checkpoint_every
            )
            # the run is complete: checkpoint it, so that a crash while the results are
            # written (kill -9 during the animation) loses nothing; --resume finishes it
            run.checkpoint()
    except RunInterrupted:
        run.close()
        raise
    except BaseException as exc:
        # a failure or a second Ctrl-C: keep the work only if a checkpoint can resume it
        run.close(failed=True)
        if not (work / CHECKPOINT).is_file():
            shutil.rmtree(work, ignore_errors=True)
        if isinstance(exc, OSError):
            raise _write_failed(work, exc) from None
        raise
    run.close()
    try:
        written = run.finish(str(path), title, outputs)
        publish(work, target)
    except OSError as exc:
        raise _write_failed(work, exc) from None
    world = run.world
    return RunReport(
        title=title,
        bodies=world.n_bodies,
        simulated=world.time,
        collisions=world.stats.collisions,
        wall_collisions=world.stats.wall_collisions,
        wall_seconds=run.wall,
        written=written,
        resumed_at=run.resumed_at,
        prepare_seconds=run.prepare_seconds,
        step=world.fixed_step,
    )


def _check_size(scene: Scene, until: float, outputs: Outputs, target: Path) -> None:
    """Refuse a run whose trajectory would hold more than :data:`MAX_FRAMES` frames or more
    bytes than the disk beside ``target`` has free, before anything runs."""
    from carom.io.h5md import frame_bytes
    from carom.io.outdir import existing_folder
    from carom.scene.build import count_bodies

    interval = scene.run["frame_interval"]
    if interval is None or not (outputs.trajectory or outputs.animation != "none"):
        return
    frames = math.floor(until / interval) + 2  # t = 0, every interval, and until
    if frames > MAX_FRAMES:
        raise CaromError(
            f"until = {until:g} s with frame_interval = {interval:g} s makes {frames:,} frames, "
            f"more than the {MAX_FRAMES:,} a trajectory may hold (docs/scenes.md, Limits); "
            f"raise frame_interval or lower --until"
        )
    per_frame = frame_bytes(count_bodies(scene), scene.world["dimension"])
    need = frames * per_frame
    folder = existing_folder(target.parent)
    free = shutil.disk_usage(folder).free
    if need > free:
        raise CaromError(
            f"the trajectory would need about {need / 2**30:.3g} GiB ({frames:,} frames of "
            f"{per_frame / 2**20:.3g} MiB), and {folder} has {free / 2**30:.3g} GiB free; raise "
            f"frame_interval, lower --until, or pass --no-trajectory --animation none"
        )


def _write_failed(work: Path, exc: OSError) -> CaromError:
    """The message for a write that failed (a full disk): what, why, and what was kept."""
    kept = (
        f"the last checkpoint is kept in {work}: free some space and continue with --resume"
        if (work / CHECKPOINT).is_file()
        else "nothing was kept"
    )
    where = f" to {exc.filename}" if exc.filename else ""
    return CaromError(f"the run could not be written{where}: {exc.strerror or exc}; {kept}")


def _make_directory(path: Path) -> None:
    try:
        path.mkdir(parents=True)
    except OSError as exc:
        raise CaromError(f"cannot create the working directory {path}: {exc.strerror}") from None


def _check_extras(outputs: Outputs) -> None:
    """A missing optional package is named before the run, not after it."""
    from carom.io.h5md import need_h5py
    from carom.viz import require_matplotlib

    if outputs.trajectory or outputs.animation != "none":
        need_h5py()  # the animation is drawn from the trajectory
    if outputs.plots or outputs.animation != "none":
        require_matplotlib()
    if outputs.animation != "none":
        from carom.viz.animate import need_encoder

        need_encoder(outputs.animation)


class Stop:
    """Set by the first Ctrl-C or SIGTERM; the run stops within a fraction of a second, after
    a checkpoint. ``signal`` is the number of the signal that asked."""

    def __init__(self) -> None:
        self.requested = False
        self.signal = int(signal.SIGINT)

    def __bool__(self) -> bool:
        return self.requested


#: the signals that ask a run to stop: Ctrl-C, and what timeout, docker stop and batch
#: schedulers send
STOP_SIGNALS = (signal.SIGINT, signal.SIGTERM)


@contextlib.contextmanager
def stop_on_signals() -> Iterator[Stop]:
    """Turn the first SIGINT or SIGTERM into a request to stop cleanly (a second one
    interrupts at once, with KeyboardInterrupt).

    A signal the process was started ignoring stays ignored: a shell starts background jobs
    (``make test &``, ``nohup``, a scheduler's jobs) with SIGINT ignored so that the
    terminal's Ctrl-C reaches only the job in the foreground, and a program keeps that
    choice (POSIX's rule for such children; Python itself installs no Ctrl-C handler then).
    Only the main thread can own signal handlers; elsewhere the signals keep their meaning.
    """
    stop = Stop()
    if threading.current_thread() is not threading.main_thread():
        yield stop
        return

    def handler(signum: int, frame: FrameType | None) -> None:
        if stop.requested:
            raise KeyboardInterrupt
        stop.requested = True
        stop.signal = signum

    previous = {
        s: signal.signal(s, handler)
        for s in STOP_SIGNALS
        if signal.getsignal(s) is not signal.SIG_IGN
    }
    try:
        yield stop
    finally:
        for s, old in previous.items():
            signal.signal(s, old)


class _Run:
    """A run's world, trajectory writer and history, and how to checkpoint them."""

    def __init__(self, work: Path, world: World, job: dict[str, Any]) -> None:
        self.work = work
        self.world = world
        self.job = job
        self.history = RunHistory()
        self.writer: Any = None
        self.events: Any = None  # the events.csv writer
        self.prepare_seconds = 0.0
        self.frames = 0  # frames in the trajectory
        self.t0 = world.time  # frames fall at t0 + k frame_interval
        self.wall = 0.0  # seconds spent in the engine
        self.resumed_at: float | None = None

    @classmethod
    def start(cls, work: Path, world: World, job: dict[str, Any]) -> _Run:
        run = cls(work, world, job)
        run._open_trajectory(resume=False)
        run._open_events(keep=None)
        run._record()
        return run

    @classmethod
    def resume(cls, work: Path, job: dict[str, Any]) -> _Run:
        world, extra = World.load_with_extra(work / CHECKPOINT)
        saved = json.loads(str(extra["job"]))
        changed = [k for k in job if saved.get(k) != job[k]]
        if changed:
            raise CaromError(
                f"the interrupted run in {work} was started with another "
                f"{' and '.join(changed).replace('_', ' ')} ({saved.get(changed[0])!r}, now "
                f"{job[changed[0]]!r}); resume it as it was started, or pass --force to start "
                f"again"
            )
        run = cls(work, world, job)
        progress = json.loads(str(extra["progress"]))
        run.frames, run.t0, run.wall = progress["frames"], progress["t0"], progress["wall"]
        run.resumed_at = world.time
        prefix = "history."
        try:
            run.history = RunHistory.from_arrays(
                {k[len(prefix) :]: v for k, v in extra.items() if k.startswith(prefix)}
            )
        except KeyError as missing:
            raise CaromError(
                f"the interrupted run in {work} was checkpointed by an older carom (its history "
                f"lacks {missing}); pass --force to start again"
            ) from None
        run._open_trajectory(resume=True)
        run._open_events(keep=progress["events_bytes"])
        return run

    def _open_events(self, *, keep: int | None) -> None:
        """The events.csv writer (new, or the file of an interrupted run cut back to what its
        checkpoint knows)."""
        if not self.job["outputs"]["events"]:
            return
        from carom.io.results import EventsWriter

        path = self.work / EVENTS
        if keep is not None and (not path.is_file() or path.stat().st_size < keep):
            raise CaromError(
                f"the events file {path} holds less than its checkpoint knows; pass --force to "
                f"start again"
            )
        self.events = EventsWriter(path, self.world.dim, keep)

    def _open_trajectory(self, *, resume: bool) -> None:
        outputs = self.job["outputs"]
        if not outputs["trajectory"] and outputs["animation"] == "none":
            return
        from carom.io.h5md import H5MDWriter

        path = self.work / TRAJECTORY
        if resume:
            self.writer = H5MDWriter.reopen(path, self.world, self.frames)
        else:
            self.writer = H5MDWriter(path, self.world)

    def _record(self, *, frame_too: bool = True) -> None:
        """Record the world now in the history and, for a frame, in the trajectory."""
        frame = self.world.frame()
        self.history.add(self.world, frame)
        if self.writer is not None and frame_too:
            h = self.history
            observed = {
                "kinetic_energy": h.kinetic[-1],
                "potential_energy": h.potential[-1],
                "dissipated_energy": h.dissipated[-1],
                "given_energy": h.given[-1],
                "work_done": h.work[-1],
                "rotational_energy": h.rotational[-1],
                "angular_momentum": h.angular_momentum[-1],
            }
            self.writer.write(frame, observed)
            self.frames = self.writer.frames

    def checkpoint(self) -> None:
        """Flush the trajectory, then write the checkpoint (atomically) that matches it."""
        if self.writer is not None:
            self.writer.flush()
        events_bytes = self.events.flush() if self.events is not None else 0
        progress = {
            "frames": self.frames,
            "t0": self.t0,
            "wall": self.wall,
            "events_bytes": events_bytes,
        }
        history = {f"history.{k}": v for k, v in self.history.arrays().items()}
        self.world.save(
            self.work / CHECKPOINT,
            extra={
                "job": np.array(json.dumps(self.job)),
                "progress": np.array(json.dumps(progress)),
                **history,
            },
        )

    def simulate(
        self,
        until: float,
        frame_interval: float | None,
        outputs: Outputs,
        progress: bool | None,
        stop: Stop,
        checkpoint_every: float,
    ) -> None:
        """Run to ``until``, frame by frame, with a progress bar; checkpoint on the way."""
        from tqdm import tqdm

        world = self.world
        stream = self.events.write if self.events is not None else None
        span = until - self.t0
        step = frame_interval if frame_interval is not None else span / CHUNKS_WITHOUT_FRAMES
        k = _frames_done(world.time, self.t0, step)
        bar = tqdm(
            total=span,
            initial=world.time - self.t0,
            disable=(None if progress is None else not progress),
            file=sys.stderr,
            unit="s",
            bar_format="{desc} {percentage:3.0f}%|{bar}| t = {n:.4g} of {total:.4g} s "
            "[{elapsed} < {remaining}{postfix}]",
            desc="simulating",
            dynamic_ncols=True,
        )
        saved = time.perf_counter()
        events0 = world.counters().events
        began = time.perf_counter()
        with bar:
            done = world.time >= until
            while not done:
                if stop:
                    self.checkpoint()
                    raise RunInterrupted(
                        f"stopped at t = {world.time:.6g} s of {until:g} s; checkpoint written",
                        stop.signal,
                    )
                target = min(until, self.t0 + (k + 1) * step)
                mark = time.perf_counter()
                world.run(until=target, on_collisions=stream, stop=stop.__bool__)
                self.wall += time.perf_counter() - mark
                if not world.reached:
                    continue  # stopped between frames: checkpoint above
                # (a time-stepped engine stops on the step nearest the target: the target
                # counts as reached, whatever the round-off of the clock)
                k += 1
                done = target >= until
                self._record(frame_too=frame_interval is not None or done)
                elapsed = time.perf_counter() - began
                bar.set_postfix_str(
                    f", {(world.counters().events - events0) / max(elapsed, 1e-9):.3g} events/s",
                    refresh=False,
                )
                bar.update(world.time - self.t0 - bar.n)
                if time.perf_counter() - saved > checkpoint_every and not done:
                    self.checkpoint()
                    saved = time.perf_counter()

    def close(self, *, failed: bool = False) -> None:
        """Close the trajectory and the events file; after a failure (``failed``), as far as
        they can be: a write that fails again (the disk is still full) was reported already."""
        for handle in (self.writer, self.events):
            if handle is None:
                continue
            try:
                handle.close()
            except OSError:
                if not failed:
                    raise

    def finish(self, scene: str, title: str, outputs: Outputs) -> list[str]:
        """Write everything else in the working directory; return the file names."""
        from carom.io.h5md import check_trajectory
        from carom.io.results import summary, write_summary

        world, h = self.world, self.history
        written = []
        trajectory = self.work / TRAJECTORY
        if self.writer is not None:
            check_trajectory(trajectory, world, self.frames)
            if outputs.trajectory:
                written.append(TRAJECTORY)
        start = {
            "kinetic_energy": h.kinetic[0],
            "potential_energy": h.potential[0],
            "momentum": np.asarray(h.momentum[0]).tolist(),
            "rotational_energy": h.rotational[0],
            "angular_momentum": np.asarray(h.angular_momentum[0]).tolist(),
        }
        data = summary(world, scene=scene, start=start, wall_seconds=self.wall)
        if outputs.events:
            written.append(EVENTS)
        write_summary(data, self.work / "summary.json")
        written.append("summary.json")
        if outputs.plots:
            from carom.viz.run import write_run_plots

            written += write_run_plots(self.work, world, h)
            from carom.viz.table import write_table_plot

            written += write_table_plot(self.work, world, trajectory)
        if outputs.animation != "none":
            from carom.viz.animate import write_animation

            name = f"animation.{outputs.animation}"
            write_animation(trajectory, self.work / name, title=title)
            written.append(name)
        if trajectory.exists():  # the page that replays it from the file system
            from carom.play.replay import REPLAY, write_replay

            write_replay(self.work, title=title)
            written.append(REPLAY)
        if not outputs.trajectory and trajectory.exists():
            trajectory.unlink()
        (self.work / CHECKPOINT).unlink(missing_ok=True)
        return written


def _frames_done(now: float, t0: float, step: float) -> int:
    """How many frame intervals of ``step`` from ``t0`` lie at or before ``now``: the next
    frame is at ``t0 + (k + 1) step``, computed as the uninterrupted run computes it."""
    if now <= t0:
        return 0
    slack = 1e-9 * step  # a time-stepped engine's clock is the sum of its steps
    k = math.floor((now - t0) / step)
    while t0 + (k + 1) * step <= now + slack:  # the division rounded down past a frame time
        k += 1
    while k > 0 and t0 + k * step > now + slack:  # or up past one
        k -= 1
    return k


def with_overrides(outputs: Outputs, **changes: Any) -> Outputs:
    """``outputs`` with the given fields changed (those given as None left alone)."""
    return replace(outputs, **{k: v for k, v in changes.items() if v is not None})
