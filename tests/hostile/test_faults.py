"""Faults a run must survive (issue 12): signals, a crash while the results are written, a
full disk, outputs that cannot work, overflowing sizes; each leaves nothing half-written and
loses nothing finished."""

from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import carom
from carom.cli import main
from carom.engines.edmd import driver
from carom.run.runner import CHECKPOINT, Outputs, RunInterrupted, run_scene, work_directory
from tests.cli.helpers import carom as carom_command

NO_FILM = Outputs(animation="none")
NO_PLOTS = ("--animation", "none", "--no-plots")


def test_a_huge_box_runs_on_a_bounded_grid() -> None:
    # once: a box of 1e300 m made 1e300 / 0.2 cells, cast to int64 (garbage), and segfaulted;
    # now at most max(4096, 16 N) cells. A box of 1e12 m (the largest for a 1 m sphere, whose
    # radius must be 1e-12 of it) would hold 1e35 cells of its size. The ball crossing it at
    # 1e11 m/s hits the far wall after (1e12 - 2 a) / 1e11 s (to round-off). Its neighbour
    # shell is made as wide as the box is empty: with the default (half a diameter, 1 m) the
    # lone ball would rebuild its list every metre, 1e12 times.
    world = carom.World(3, [1e12, 1e12, 1e12], shell_thickness=1e10)
    world.add_spheres([1.0, 5e11, 5e11], [1e11, 0.0, 0.0], radius=1.0)
    world.run(until=12.0, log=True)
    assert world.engine is not None
    assert int(np.prod(world.engine.model.ncell)) <= driver.MIN_CELLS
    (hit,) = world.collisions
    assert hit["time"] == pytest.approx((1e12 - 2.0) / 1e11, rel=4 * np.finfo(float).eps)


def test_a_sparse_scene_needs_no_dense_grid() -> None:
    # two 1 cm spheres 100 m apart in a 1 km box: a dense grid of shell-sized cells had 1.6e13
    # cells (114 TiB); the bounded grid has at most 4096. Head-on at 2 m/s they touch when
    # the gap of 100 - 0.02 m has closed: t = 99.98 / 2 s (closed form). Each moves 50 m
    # in steps of its 0.01 m shell, its position rounded at each of 5000 steps by up to half
    # an ulp of 500 m (5.7e-14 m): at worst 2.8e-10 m, so 2.8e-10 s at 1 m/s each
    world = carom.World(3, [1000.0, 1000.0, 1000.0])
    world.add_spheres(
        [[400.0, 500, 500], [500.0, 500, 500]], [[1.0, 0, 0], [-1.0, 0, 0]], radius=0.01
    )
    world.run(until=60.0, log=True)
    assert world.engine is not None
    assert int(np.prod(world.engine.model.ncell)) <= driver.MIN_CELLS
    assert world.collisions[0]["time"] == pytest.approx(99.98 / 2, rel=0, abs=2.8e-10)


@pytest.mark.parametrize("speed", [1e20, 1e50, 1e100])
def test_the_fastest_sphere_allowed_never_tunnels(speed: float) -> None:
    # once: at 1e200 m/s, v^2 overflowed and the sphere flew through the wall. Now speeds are
    # capped at 1e100 m/s and at that speed it still bounces: from x = 0.5 in a 1 m box with
    # radius 0.1, it travels 10.2 m in 10.2 / v s: 0.4 m to the first wall (x = 0.9), then
    # 0.8 m per crossing; the 13th wall collision is at 10 m, on the same wall, and it ends
    # 0.2 m back from it, at x = 0.7 (round-off: a few eps of the 10 m travelled)
    world = carom.World(3, [1.0, 1.0, 1.0])
    world.add_spheres([0.5, 0.5, 0.5], [speed, 0.0, 0.0], radius=0.1)
    world.run(until=10.2 / speed)
    assert world.stats.wall_collisions == 13
    assert world.positions[0, 0] == pytest.approx(0.7, abs=1e-12)
    assert world.stats.kinetic_energy == pytest.approx(0.5 * speed**2, rel=1e-15)


def test_a_stop_request_is_seen_within_a_block_of_events() -> None:
    # the engine returns to Python every STOP_CHECK_EVENTS events, so Ctrl-C and a run's stop
    # request are seen within a fraction of a second however long the step asked for
    from tests.worlds import gas

    world = gas(2, 30, 0.3, seed=1)
    asked = []

    def stop() -> bool:
        asked.append(world.counters().events)
        return len(asked) >= 3

    world.run(until=1e6, stop=stop)
    assert world.time < 1e6  # stopped early, consistent, where the last event left it
    assert len(asked) == 3
    assert asked[0] == driver.STOP_CHECK_EVENTS  # the first look after one block
    assert asked[2] - asked[1] == driver.STOP_CHECK_EVENTS
    before = world.time
    world.run(until=before + 1.0)  # and it continues from there
    assert world.time == before + 1.0


def test_a_run_stopped_between_frames_resumes_bit_for_bit(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # blocks of 64 events, so that the stop lands between two frames, mid-interval
    pytest.importorskip("h5py")
    from tests.cli.test_resume import _assert_same_results, _stop_after

    monkeypatch.setattr(driver, "STOP_CHECK_EVENTS", 64)
    straight = tmp_path / "straight"
    run_scene("billiards-break", straight, until=1.0, outputs=NO_FILM, progress=False)
    out = tmp_path / "out"
    _stop_after(monkeypatch, 4)
    with pytest.raises(RunInterrupted):
        run_scene("billiards-break", out, until=1.0, outputs=NO_FILM, progress=False)
    stopped = carom.World.load(work_directory(out) / CHECKPOINT).time
    monkeypatch.undo()
    run_scene("billiards-break", out, until=1.0, outputs=NO_FILM, progress=False, resume=True)
    _assert_same_results(straight, out)
    assert stopped * 20 % 1 != 0  # not at one of the frames, 0.05 s apart


def _second_ctrl_c_at_run(monkeypatch: pytest.MonkeyPatch, call: int) -> None:
    """Make the ``call``-th World.run of the run raise KeyboardInterrupt, as a second Ctrl-C
    does (the first one's request is not seen before it)."""
    calls = {"n": 0}
    run = carom.World.run

    def second_ctrl_c(self: carom.World, *args: object, **kwargs: object) -> object:
        calls["n"] += 1
        if calls["n"] == call:
            raise KeyboardInterrupt
        return run(self, *args, **kwargs)  # type: ignore[arg-type]

    monkeypatch.setattr(carom.World, "run", second_ctrl_c)


def test_a_second_ctrl_c_before_any_checkpoint_leaves_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # once: two quick Ctrl-Cs said "nothing was written" and left a 17 MB working folder
    _second_ctrl_c_at_run(monkeypatch, 3)
    out = tmp_path / "out"
    with pytest.raises(KeyboardInterrupt):
        run_scene("newtons-cradle", out, outputs=NO_FILM, progress=False)
    assert sorted(tmp_path.iterdir()) == []


def test_a_second_ctrl_c_after_a_checkpoint_keeps_it(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    _second_ctrl_c_at_run(monkeypatch, 5)
    out = tmp_path / "out"
    argv = ["run", "newtons-cradle", "--out", str(out), "--quiet", "--checkpoint-every", "1e-9"]
    argv += ["--animation", "none"]
    assert main(argv) == 130
    err = capsys.readouterr().err
    assert "its last checkpoint is kept: continue with: carom run newtons-cradle" in err
    assert "--checkpoint-every 1e-9 --animation none --resume" in err
    assert (work_directory(out) / CHECKPOINT).is_file()
    assert not out.exists()


def test_a_crash_while_the_results_are_written_loses_nothing(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # once: kill -9 while the figures were drawn lost a finished run (no checkpoint yet).
    # Now the finished run is checkpointed first; --resume writes the results.
    pytest.importorskip("matplotlib")
    from carom.viz import run as plots

    straight = tmp_path / "straight"
    run_scene("billiards-break", straight, until=1.0, outputs=NO_FILM, progress=False)

    def killed(*args: object, **kwargs: object) -> list[str]:
        raise SystemExit(137)  # what a kill -9 leaves behind: the files as they are

    monkeypatch.setattr(plots, "write_run_plots", killed)
    out = tmp_path / "out"
    with pytest.raises(SystemExit):
        run_scene("billiards-break", out, until=1.0, outputs=NO_FILM, progress=False)
    assert carom.World.load(work_directory(out) / CHECKPOINT).time == 1.0
    monkeypatch.undo()
    report = run_scene(
        "billiards-break", out, until=1.0, outputs=NO_FILM, progress=False, resume=True
    )
    assert report.resumed_at == 1.0
    from tests.cli.test_resume import _assert_same_results

    _assert_same_results(straight, out)


def _limit_file_size() -> None:
    """In the child: files may not grow past 200 kB, and the write then fails with EFBIG
    (as it does with ENOSPC on a full disk) instead of killing the process."""
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (200_000, 200_000))


@pytest.mark.skipif(not hasattr(resource, "RLIMIT_FSIZE"), reason="needs RLIMIT_FSIZE")
def test_a_full_disk_is_one_message_not_a_crash(tmp_path: Path) -> None:
    # once: 533 lines of h5py tracebacks, then a segfault
    pytest.importorskip("h5py")
    done = subprocess.run(
        [sys.executable, "-m", "carom", "run", "gas-3d", "--out", "out", "--quiet", *NO_PLOTS],
        capture_output=True,
        text=True,
        cwd=tmp_path,
        stdin=subprocess.DEVNULL,
        timeout=600,
        env={**os.environ, "MPLBACKEND": "Agg"},
        preexec_fn=_limit_file_size,
    )
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    assert len(done.stderr.splitlines()) == 1, done.stderr
    assert "carom: error: the run could not be written" in done.stderr
    assert "written writing" not in done.stderr  # (once: "could not be written writing ...")
    assert "File too large" in done.stderr
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(
    ("out", "pattern"),
    [
        (".", r"does not name a directory of its own"),
        ("", r"does not name a directory of its own"),
        ("..", r"does not name a directory of its own"),
        ("x" * 250, r"is 250 bytes long; the file system allows"),
    ],
)
def test_outputs_that_cannot_work_are_refused_first(
    tmp_path: Path,
    capsys: pytest.CaptureFixture[str],
    monkeypatch: pytest.MonkeyPatch,
    out: str,
    pattern: str,
) -> None:
    # once: --out . ran to the end, then failed with EBUSY and hid the results in ..carom-run
    inner = tmp_path / "here"
    inner.mkdir()
    monkeypatch.chdir(inner)
    assert main(["run", "newtons-cradle", "--out", out, "--force", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("carom: error: --out")
    assert len(err.splitlines()) == 1
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["here"]


def test_a_working_folder_that_is_a_symlink_is_not_followed(tmp_path: Path) -> None:
    elsewhere = tmp_path / "elsewhere"
    elsewhere.mkdir()
    (tmp_path / ".out.carom-run").symlink_to(elsewhere)
    done = carom_command("run", "newtons-cradle", "--out", "out", cwd=tmp_path)
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    assert ".out.carom-run is a symbolic link" in done.stderr
    assert list(elsewhere.iterdir()) == []


@pytest.mark.parametrize("damage", ["not-hdf5", "empty-hdf5"])
def test_carom_view_on_a_damaged_trajectory_is_one_message(tmp_path: Path, damage: str) -> None:
    # once: an h5py OSError traceback
    h5py = pytest.importorskip("h5py")
    pytest.importorskip("rerun")
    folder = tmp_path / "run"
    folder.mkdir()
    if damage == "not-hdf5":
        (folder / "trajectory.h5").write_text("garbage")
    else:
        h5py.File(folder / "trajectory.h5", "w").close()
    done = carom_command("view", folder, CI="true")
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    assert "trajectory.h5 is not a readable trajectory" in done.stderr or (
        "trajectory.h5 lacks part of a carom trajectory" in done.stderr
    )
    assert sorted(p.name for p in folder.iterdir()) == ["trajectory.h5"]  # nothing added


def test_resume_from_a_truncated_checkpoint_is_one_message(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # once: a BadZipFile traceback
    from tests.cli.test_resume import _stop_after

    out = tmp_path / "out"
    _stop_after(monkeypatch, 3)
    with pytest.raises(RunInterrupted):
        run_scene("newtons-cradle", out, outputs=NO_FILM, progress=False)
    monkeypatch.undo()
    checkpoint = work_directory(out) / CHECKPOINT
    checkpoint.write_bytes(checkpoint.read_bytes()[:100])
    assert main(["run", "newtons-cradle", "--out", str(out), "--resume", "--quiet"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("carom: error: ")
    assert "checkpoint" in err
    assert len(err.splitlines()) == 1
