"""Running a sweep on Dask: every point a task, on a local cluster or an existing scheduler.

The rows land in ``DIR/results.csv`` as the points finish, each forced to disk, so a crash,
a ``kill`` or Ctrl-C loses nothing done; ``resume=True`` runs only what is missing (and the
points that failed). A point that raises is a ``failed`` row with its message; the others go
on. A worker that dies (killed, out of memory) hands its task back to the scheduler, which
runs it on another worker (Dask's ``distributed.scheduler.allowed-failures``, 3 by default,
before the point is recorded as failed). At the end the table is put in the order of the
points, so it does not depend on which worker finished first.
"""

from __future__ import annotations

import contextlib
import csv
import json
import logging
import os
import shutil
import signal
import sys
import threading
import time
import uuid
from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from types import FrameType
from typing import Any

from carom.errors import CaromError
from carom.io.outdir import write_whole
from carom.sweeps.observe import run_point
from carom.sweeps.spec import Point, SweepSpec, load_sweep
from carom.sweeps.table import RESULTS, ResultsTable, completed, write_parquet

__all__ = ["SweepInterrupted", "SweepReport", "sweep"]

#: the sweep's own record in its folder: what it is (for --resume) and how it went
MANIFEST = "sweep.json"
#: per run: the worker that ran it, its wall-clock seconds, the time spent on kernels and how
#: many it compiled or loaded (0 once a worker is warm)
TIMINGS = "tasks.csv"
#: seconds between rewrites of results.parquet while the sweep runs
PARQUET_EVERY = 10.0


class SweepInterrupted(Exception):  # noqa: N818 (the user asked to stop: not an error)
    """Ctrl-C or SIGTERM: the rows done are in ``results.csv``; ``resume=True`` continues.

    ``signal`` is the number of the signal that asked (``signal.SIGINT`` or ``SIGTERM``).
    """

    def __init__(self, message: str, signal: int) -> None:
        super().__init__(message)
        self.signal = signal


@contextlib.contextmanager
def _stop_on_sigterm() -> Iterator[list[int]]:
    """SIGTERM (what timeout, docker stop and batch schedulers send) stops a sweep as Ctrl-C
    does, so that its cluster is closed and its table kept; yields the signals received.
    Only the main thread can own signal handlers; elsewhere SIGTERM keeps its meaning, and
    so it does where the process was started ignoring it (as :func:`carom.run.runner.
    stop_on_signals` keeps an ignored signal ignored)."""
    received: list[int] = []
    if (
        threading.current_thread() is not threading.main_thread()
        or signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
    ):
        yield received
        return

    def handler(signum: int, frame: FrameType | None) -> None:
        received.append(signum)
        raise KeyboardInterrupt

    previous = signal.signal(signal.SIGTERM, handler)
    try:
        yield received
    finally:
        signal.signal(signal.SIGTERM, previous)


@dataclass
class SweepReport:
    """What a finished sweep did."""

    title: str
    folder: Path
    runs: int  # points times seeds in the sweep
    ran: int  # run by this call (the others were done before: resume)
    failed: int
    workers: int
    wall_seconds: float
    written: list[str] = field(default_factory=list)


def sweep(
    sweep_file: str | Path | SweepSpec,
    out: str | Path,
    *,
    workers: int | None = None,
    scheduler: str | None = None,
    resume: bool = False,
    force: bool = False,
    progress: bool | None = None,
    plots: bool = True,
) -> SweepReport:
    """Run a parameter sweep on Dask and write its table (and plots) to ``out``.

    Parameters
    ----------
    sweep_file : str, Path or SweepSpec
        A sweep file, the name of a built-in sweep (``eos-3d``), or a checked spec.
    out : str or Path
        The output folder: ``results.csv`` (and ``results.parquet``), ``tasks.csv``,
        ``sweep.json``, ``sweep.toml`` and the plots. It must not exist or be empty, unless
        ``force`` (replace it) or ``resume``.
    workers : int, optional
        Worker processes of the local cluster (one thread each); the number of cores by
        default, and never more than the runs to do. Not with ``scheduler``.
    scheduler : str, optional
        The address of a running Dask scheduler (``tcp://host:8786``) whose workers run the
        points; they need carom installed and the scene's files at the same paths.
    resume : bool
        Continue the sweep in ``out``: run only the points without a successful row.
    force : bool
        Replace a non-empty ``out`` that holds something else.
    progress : bool, optional
        A progress bar on standard error (points done, running, failed, time left); by
        default only when it is a terminal.
    plots : bool
        Draw each observable against the parameter (needs matplotlib).

    Returns
    -------
    SweepReport

    Raises
    ------
    CaromError
        A bad sweep file, ``out`` or option; Dask not installed; a scheduler that cannot be
        reached.
    SweepInterrupted
        Ctrl-C: what finished is in ``results.csv``; continue with ``resume=True``.
    """
    spec = sweep_file if isinstance(sweep_file, SweepSpec) else load_sweep(sweep_file)
    points = spec.check()
    if workers is not None and scheduler is not None:
        raise CaromError(
            "--workers sizes the local cluster; with --scheduler the cluster's own workers run "
            "the points: give one of them"
        )
    if workers is not None and not 1 <= workers <= 4096:
        raise CaromError(f"--workers must be a whole number from 1 to 4096, got {workers}")
    folder = Path(out)
    _check_folder(folder, spec, resume=resume, force=force)  # (nothing written yet)
    if plots:
        from carom.viz import require_matplotlib

        require_matplotlib()
    _need_dask()
    began = time.perf_counter()
    done = completed(folder, spec) if resume else set()
    todo = [p for p in points if p.key not in done]
    failed, nworkers = 0, 0
    table: ResultsTable | None = None
    with _stop_on_sigterm() as received:
        try:
            with contextlib.ExitStack() as stack:
                # the cluster first: a scheduler that cannot be reached leaves nothing behind
                warm = (todo[0].scene, str(spec.scene_path)) if todo else None
                # (no more local workers than runs: each is a process of its own)
                size = min(workers or os.cpu_count() or 1, len(todo))
                client = stack.enter_context(_cluster(size, scheduler, warm)) if todo else None
                if not resume:
                    _make_folder(folder, spec)
                table = ResultsTable(folder, spec, keep=resume)
                _write_manifest(folder, spec, points, state="running")
                if client is not None:
                    nworkers = len(client.scheduler_info()["workers"])
                    failed = _run(client, spec, todo, table, folder, progress)
        except KeyboardInterrupt:
            number = received[0] if received else int(signal.SIGINT)
            if table is None:
                raise SweepInterrupted(
                    "interrupted before any point ran; nothing was written", number
                ) from None
            table.close()
            _write_manifest(folder, spec, points, state="interrupted")
            raise SweepInterrupted(
                f"interrupted: {len(table.done())} of {len(points)} runs are in {folder / RESULTS}",
                number,
            ) from None
        except BaseException:
            if table is not None:
                table.close()
                _write_manifest(folder, spec, points, state="interrupted")
            raise
    table.finish()
    written = [RESULTS, TIMINGS, MANIFEST]
    if spec.text:
        written.append("sweep.toml")
    if write_parquet(folder, spec):
        written.append("results.parquet")
    if plots:
        from carom.sweeps.plots import write_plots

        written += write_plots(folder, spec)
    _write_manifest(folder, spec, points, state="done")
    return SweepReport(
        title=spec.title,
        folder=folder,
        runs=len(points),
        ran=len(todo),
        failed=failed,
        workers=nworkers,
        wall_seconds=time.perf_counter() - began,
        written=written,
    )


def _need_dask() -> None:
    try:
        import distributed  # noqa: F401
    except ImportError:
        raise CaromError(
            "carom sweep runs its points on Dask, which is not installed: "
            "pip install 'carom[sweep]'"
        ) from None


def _check_folder(out: Path, spec: SweepSpec, *, resume: bool, force: bool) -> None:
    """Refuse ``out`` unless it is new, may be replaced (``force``) or holds this sweep
    (``resume``); writes nothing."""
    from carom.io.outdir import check_output

    if not resume:
        check_output(out, force=force)
        return
    manifest = out / MANIFEST
    if not manifest.is_file():
        raise CaromError(
            f"nothing to resume in {out}: it holds no {MANIFEST}; run without --resume"
        )
    try:
        saved = json.loads(manifest.read_text())
    except (OSError, ValueError) as exc:
        raise CaromError(
            f"{manifest} cannot be read ({exc}); pass --force to start again"
        ) from None
    if saved.get("digest") != spec.digest():
        raise CaromError(
            f"{out} holds another sweep (its scene, parameters, seeds, run or observables "
            f"differ from {spec.source}); resume it with the file it was started with, or "
            f"pass --force to start again"
        )


def _make_folder(out: Path, spec: SweepSpec) -> None:
    """A fresh ``out`` (replacing what :func:`_check_folder` allowed), with the sweep file
    and the header of the timing log."""
    if out.exists():
        try:
            shutil.rmtree(out)
        except OSError as exc:
            raise CaromError(f"cannot replace {out}: {exc.strerror}") from None
    try:
        out.mkdir(parents=True)
    except OSError as exc:
        raise CaromError(f"cannot create the output folder {out}: {exc.strerror}") from None
    if spec.text:
        (out / "sweep.toml").write_text(spec.text, encoding="utf-8")
    with (out / TIMINGS).open("w", newline="") as handle:
        csv.writer(handle, lineterminator="\n").writerow(
            ["point", "seed", "status", "worker", "wall_s", "prepare_s", "kernels_loaded"]
        )


def _write_manifest(folder: Path, spec: SweepSpec, points: list[Point], *, state: str) -> None:
    from carom import __version__

    data = {
        "title": spec.title,
        "description": spec.description,
        "source": spec.source,
        "scene": str(spec.scene_path),
        "digest": spec.digest(),
        "state": state,
        "runs": len(points),
        "points": spec.count(),
        "seeds": spec.seeds,
        "parameters": list(spec.parameters),
        "observables": spec.observables,
        "until_s": spec.until,
        "warmup_s": spec.warmup,
        "carom": __version__,
    }
    write_whole(folder / MANIFEST, json.dumps(data, indent=2) + "\n")


def _warm(scene: dict[str, Any], source: str) -> None:
    """Compile (or load from the cache) the kernels a point's scene uses, in this process.
    Run on every worker before the points, so that no task compiles (a failure here is the
    first point's to report)."""
    with contextlib.suppress(Exception):
        from carom.scene import Scene

        Scene.from_dict(scene, source).build().prepare()


@contextlib.contextmanager
def _cluster(
    workers: int, scheduler: str | None, warm: tuple[dict[str, Any], str] | None
) -> Iterator[Any]:
    """A Dask client: to the scheduler at ``scheduler``, or to a new local cluster of
    ``workers`` processes, its kernels made ready."""
    from distributed import Client, LocalCluster

    cluster = None
    if scheduler is not None:
        try:
            client = Client(scheduler, timeout="5s")
        except (OSError, TimeoutError) as exc:
            raise CaromError(
                f"cannot reach the Dask scheduler at {scheduler} ({exc}); check the address "
                f"(tcp://host:8786) and that the scheduler and its workers are running"
            ) from None
    else:
        if warm is not None:
            # compile once here, into the on-disk cache the local workers then load from
            _warm(*warm)
        cluster = LocalCluster(
            n_workers=workers,
            threads_per_worker=1,
            processes=True,
            # no dashboard wanted, but Dask starts its HTTP server anyway, on 8787 unless told:
            # any free port, so that a dashboard or another cluster already on 8787 (a second
            # sweep at once, a parallel test run) costs nothing, not a warning
            dashboard_address=":0",
            # the sweep reports every failure itself (a row and its message); what Dask would
            # add is noise, such as the traceback of a worker whose heartbeat, delayed by a
            # kernel, finds the scheduler already closed after Ctrl-C (seen in CI)
            silence_logs=logging.CRITICAL,
            preload=["carom.sweeps.worker"],  # Ctrl-C is the sweep's to handle, not theirs
        )
        client = Client(cluster)
    try:
        if warm is not None:
            client.run(_warm, *warm)
        yield client
    finally:
        client.close()
        if cluster is not None:
            cluster.close()


def _run(
    client: Any,
    spec: SweepSpec,
    todo: list[Point],
    table: ResultsTable,
    folder: Path,
    progress: bool | None,
) -> int:
    """Submit every point, write each row as it comes; return how many failed."""
    from distributed import as_completed
    from tqdm import tqdm

    token = uuid.uuid4().hex[:8]
    by_key = {}
    futures = []
    for point in todo:
        key = f"carom-point-{point.index}-{point.seed}-{token}"
        by_key[key] = point
        futures.append(client.submit(run_point, spec.task(point), key=key, pure=False))
    failed = 0
    threads = max(1, sum(client.nthreads().values()))
    parquet_at = time.perf_counter()
    bar = tqdm(
        total=len(todo),
        disable=(None if progress is None else not progress),
        file=sys.stderr,
        unit="run",
        desc="sweeping",
        dynamic_ncols=True,
    )
    timings = (folder / TIMINGS).open("a", newline="")
    log = csv.writer(timings, lineterminator="\n")
    try:
        with bar:
            bar.set_postfix_str(f"running {min(threads, len(todo))}, failed 0", refresh=False)
            for future in as_completed(futures):
                point = by_key[future.key]
                try:
                    result = future.result()
                except Exception as exc:  # the task could not finish: its workers died
                    result = {
                        "status": "failed",
                        "message": " ".join(f"{type(exc).__name__}: {exc}".split()),
                        "values": {},
                        "theory": {},
                        "worker": "",
                        "wall_s": float("nan"),
                        "prepare_s": float("nan"),
                        "kernels_loaded": "",
                    }
                table.add(point, result)
                log.writerow(
                    [
                        point.index,
                        "" if point.seed is None else point.seed,
                        result["status"],
                        result["worker"],
                        f"{result['wall_s']:.6g}",
                        f"{result['prepare_s']:.6g}",
                        result["kernels_loaded"],
                    ]
                )
                timings.flush()
                failed += result["status"] != "ok"
                left = len(todo) - bar.n - 1
                bar.set_postfix_str(f"running {min(threads, left)}, failed {failed}", refresh=False)
                bar.update(1)
                if time.perf_counter() - parquet_at > PARQUET_EVERY:
                    write_parquet(folder, spec)  # (from the rows on disk so far)
                    parquet_at = time.perf_counter()
    finally:
        timings.close()
        for future in futures:
            future.cancel()
    return failed
