"""Interrupting a run and resuming it: same files as a run never interrupted; Ctrl-C leaves a
valid checkpoint and nothing half-written."""

from __future__ import annotations

import json
import os
import shlex
import signal
import subprocess
import sys
import time
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import carom
from carom.run import runner
from carom.run.runner import CHECKPOINT, Outputs, RunInterrupted, run_scene, work_directory
from tests.processes import from_a_terminal

h5py = pytest.importorskip("h5py", reason="the io extra (h5py) is not installed")
pytest.importorskip("matplotlib", reason="the viz extra (matplotlib) is not installed")

NO_FILM = Outputs(animation="none")


def _stop_after(monkeypatch: pytest.MonkeyPatch, polls: int) -> None:
    """Make the run's stop flag read as set from its ``polls``-th look on (as Ctrl-C does)."""
    seen = {"n": 0}

    def stop_requested(self: object) -> bool:
        seen["n"] += 1
        return seen["n"] >= polls

    monkeypatch.setattr(runner.Stop, "__bool__", stop_requested)


def _without_performance(path: Path) -> dict[str, object]:
    data = json.loads(path.read_text())
    data.pop("performance")  # wall-clock figures: the only part that may differ
    data.pop("scene")
    return data


def _assert_same_results(a: Path, b: Path) -> None:
    names = sorted(p.name for p in a.iterdir())
    assert names == sorted(p.name for p in b.iterdir())
    assert (a / "events.csv").read_bytes() == (b / "events.csv").read_bytes()
    assert _without_performance(a / "summary.json") == _without_performance(b / "summary.json")
    for png in a.glob("*.png"):
        assert png.read_bytes() == (b / png.name).read_bytes(), png.name
    with h5py.File(a / "trajectory.h5", "r") as fa, h5py.File(b / "trajectory.h5", "r") as fb:
        datasets: list[str] = []
        fa.visit(lambda name: datasets.append(name) if isinstance(fa[name], h5py.Dataset) else None)
        assert len(datasets) >= 10
        for name in datasets:
            np.testing.assert_array_equal(fa[name][()], fb[name][()], err_msg=name)


@pytest.mark.parametrize("scene", ["billiards-break", "hard-sphere-gas"])
def test_a_resumed_run_writes_what_an_uninterrupted_one_does(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, scene: str
) -> None:
    straight = tmp_path / "straight"
    run_scene(scene, straight, until=1.0, outputs=NO_FILM, progress=False)
    # the same run, stopped after 7 frames and again after 5 more, then finished
    out = tmp_path / "out"
    work = work_directory(out)
    for polls in (7, 5):
        _stop_after(monkeypatch, polls)
        with pytest.raises(RunInterrupted, match=r"stopped at t = .* checkpoint written"):
            run_scene(scene, out, until=1.0, outputs=NO_FILM, progress=False, resume=polls == 5)
        assert not out.exists()  # nothing half-written where the results go
        world = carom.World.load(work / CHECKPOINT)  # a valid checkpoint
        assert 0 < world.time < 1.0
    monkeypatch.undo()
    report = run_scene(scene, out, until=1.0, outputs=NO_FILM, progress=False, resume=True)
    assert report.resumed_at is not None
    assert report.resumed_at > 0
    assert not work.exists()
    _assert_same_results(straight, out)


def test_resume_refuses_what_it_cannot_continue(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    out = tmp_path / "out"
    with pytest.raises(carom.CaromError, match=r"nothing to resume for .*run without --resume"):
        run_scene("newtons-cradle", out, resume=True, progress=False)
    _stop_after(monkeypatch, 3)
    with pytest.raises(RunInterrupted):
        run_scene("newtons-cradle", out, outputs=NO_FILM, progress=False)
    monkeypatch.undo()
    # an interrupted run is not silently replaced by a new one...
    with pytest.raises(carom.CaromError, match=r"holds an interrupted run .* --resume .* --force"):
        run_scene("newtons-cradle", out, outputs=NO_FILM, progress=False)
    # ...nor resumed with other settings
    with pytest.raises(carom.CaromError, match=r"started with another until"):
        run_scene("newtons-cradle", out, until=0.5, outputs=NO_FILM, progress=False, resume=True)
    # --force starts again
    run_scene("newtons-cradle", out, outputs=NO_FILM, progress=False, force=True)
    assert (out / "summary.json").exists()


@pytest.fixture
def sigint_as_in_a_terminal() -> Iterator[None]:
    """SIGINT at Python's own handler for the test, as a terminal starts a program, however
    the test suite was started (a background shell starts it ignoring SIGINT)."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    try:
        yield
    finally:
        signal.signal(signal.SIGINT, before)


@pytest.mark.usefixtures("sigint_as_in_a_terminal")
@pytest.mark.parametrize("first", [signal.SIGINT, signal.SIGTERM])
def test_the_first_signal_asks_to_stop_and_the_second_interrupts(first: int) -> None:
    # Ctrl-C and SIGTERM (timeout, docker stop, batch schedulers) alike
    before = signal.getsignal(signal.SIGTERM)
    with runner.stop_on_signals() as stop:
        assert not stop
        signal.raise_signal(first)
        assert stop  # the run will stop within a block of events, after a checkpoint
        assert stop.signal == first  # the exit code will say which (128 + signal)
        with pytest.raises(KeyboardInterrupt):
            signal.raise_signal(signal.SIGINT if first == signal.SIGTERM else signal.SIGTERM)
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler
    assert signal.getsignal(signal.SIGTERM) == before


def test_a_run_started_ignoring_sigint_keeps_ignoring_it() -> None:
    # A background shell (`make test &`, nohup, a scheduler) starts its children with SIGINT
    # ignored, so that Ctrl-C in the terminal reaches only the foreground job; a run keeps
    # that choice (POSIX), and SIGTERM still asks it to stop.
    before = signal.signal(signal.SIGINT, signal.SIG_IGN)
    try:
        with runner.stop_on_signals() as stop:
            signal.raise_signal(signal.SIGINT)
            assert not stop
            assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
            signal.raise_signal(signal.SIGTERM)
            assert stop
            assert stop.signal == signal.SIGTERM
        assert signal.getsignal(signal.SIGINT) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGINT, before)


@pytest.mark.slow  # (a real run of 2e6 collisions in a fresh process)
@pytest.mark.needs_jit
@pytest.mark.parametrize("sent", [signal.SIGINT, signal.SIGTERM])
def test_a_signal_on_the_command_line_then_resume_as_told(tmp_path: Path, sent: int) -> None:
    # A real SIGINT (Ctrl-C) or SIGTERM (timeout, docker stop) to a real run (2e6
    # collisions, only the summary written, so that the signal lands mid-run without
    # gigabytes of output): exit 128 + the signal, a message giving the whole command that
    # resumes it (every option kept), no output directory, a checkpoint; then that command,
    # run as printed, finishes it.
    out = tmp_path / "gas"
    work = work_directory(out)
    command = [sys.executable, "-m", "carom", "run", "hard-sphere-gas", "--out", str(out)]
    command += ["--until", "400", "--animation", "none", "--no-plots", "--no-trajectory"]
    command += ["--no-events"]
    env = {**os.environ, "MPLBACKEND": "Agg"}
    process = subprocess.Popen(
        from_a_terminal(command),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )
    deadline = time.monotonic() + 240
    while not work.exists() and time.monotonic() < deadline:
        time.sleep(0.02)
    time.sleep(0.5)
    process.send_signal(sent)
    stdout, stderr = process.communicate(timeout=240)
    assert process.returncode == 128 + sent, stderr
    assert stdout == ""  # no results reported
    assert "Traceback" not in stderr
    told = stderr.split("Continue with: ", 1)[1].strip()
    assert shlex.split(told) == ["carom", *command[3:], "--resume"]
    assert not out.exists()
    world = carom.World.load(work / CHECKPOINT)
    assert 0 < world.time < 400
    done = subprocess.run(
        [sys.executable, "-m", *shlex.split(told)],
        capture_output=True,
        text=True,
        env=env,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr
    assert f"(resumed at {world.time:g} s)" in done.stdout
    assert not work.exists()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["simulated_time_s"] == 400
    # the collisions before the stop are counted with those after it (about 5000 per
    # simulated second in this gas)
    assert summary["collisions"] > 1_000_000
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"]
