"""`carom run` end to end: the files it writes, their physics, and how it refuses bad input."""

from __future__ import annotations

import csv
import json
import math
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from carom.run.runner import Outputs
from tests.cli.helpers import carom
from tests.scene.test_load import BAD_SCENES, GOOD


def test_run_a_bouncing_ball_and_check_its_events(tmp_path: Path) -> None:
    out = tmp_path / "ball"
    done = carom("run", "bouncing-ball", "--out", out, "--until", "2.0")
    assert done.returncode == 0, done.stderr
    assert "wrote trajectory.h5, events.csv, summary.json" in done.stdout
    with (out / "events.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    # dropped from h0 = 1.55 - 0.05 = 1.5 m (centre above contact) under g = 9.81 m/s^2 onto a
    # floor of e = 0.8: first impact at sqrt(2 h0 / g) with u = -sqrt(2 g h0), leaving at
    # -e u; each later flight lasts 2 e^k sqrt(2 h0 / g) (closed forms, to round-off)
    g, h0, e = 9.81, 1.5, 0.8
    t1, u1 = math.sqrt(2 * h0 / g), math.sqrt(2 * g * h0)
    # numeric columns: partner_kind "wall", partner 2 = the lower wall of y (2 k + 0, k = 1);
    # the ball has the default mass, 1 kg, so its impulse is (1 + e) u1 in N s
    assert (rows[0]["partner_kind"], int(rows[0]["body"]), int(rows[0]["partner"])) == (
        "wall",
        0,
        2,
    )
    # events.csv holds repr() of each float (an exact round trip); the engine reaches these
    # numbers by a quadratic root and a few dozen float64 operations, each within half an ulp,
    # so they are right to ~1e-15; 1e-12 leaves a wide margin and still fails any wrong
    # formula (e, g or h0 off by a per cent shows at 1e-2)
    assert float(rows[0]["time_s"]) == pytest.approx(t1, rel=1e-12, abs=0.0)
    assert float(rows[0]["un_before_m_s"]) == pytest.approx(-u1, rel=1e-12, abs=0.0)
    assert float(rows[0]["un_after_m_s"]) == pytest.approx(e * u1, rel=1e-12, abs=0.0)
    assert float(rows[1]["time_s"]) - float(rows[0]["time_s"]) == pytest.approx(
        2 * e * t1, rel=1e-12, abs=0.0
    )
    assert float(rows[0]["impulse_y_Ns"]) == pytest.approx((1 + e) * u1, rel=1e-12, abs=0.0)
    # the contact point is on the floor, y = 0, to round-off of the 1.55 m drop (a few eps)
    assert float(rows[0]["point_y_m"]) == pytest.approx(0.0, abs=8 * 2.2e-16 * 1.55)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["wall_collisions"] == len(rows)
    assert summary["simulated_time_s"] == 2.0
    # energy: start (all potential) = end (kinetic + potential) + dissipated, to round-off
    assert abs(summary["energy"]["balance_error_relative"]) < 1e-12
    assert summary["energy"]["dissipated_J"] > 0


def test_two_runs_of_a_scene_agree_on_everything_but_the_wall_clock(tmp_path: Path) -> None:
    # same input and seed, bit-identical results: summary.json differs only in its
    # "performance" block (wall time and rates), kept apart for this; a pile (galton-board,
    # the parting floor at work) and a gas (random start from a seed)
    for scene in ("galton-board", "gas-2d"):
        runs = [tmp_path / f"{scene}-{k}" for k in range(2)]
        for out in runs:
            done = carom(
                "run", scene, "--out", out, "--until", "0.5", "--no-plots", "--animation", "none"
            )
            assert done.returncode == 0, done.stderr
        first, second = (json.loads((out / "summary.json").read_text()) for out in runs)
        assert first.pop("performance") != second.pop("performance")  # wall time moved
        assert first == second
        assert first["simulated_time_s"] == 0.5
        assert (runs[0] / "events.csv").read_bytes() == (runs[1] / "events.csv").read_bytes()


def test_run_newtons_cradle_keeps_energy_and_momentum(tmp_path: Path) -> None:
    out = tmp_path / "gas"
    done = carom("run", "newtons-cradle", "--out", out, "--until", "0.6")
    assert done.returncode == 0, done.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["collisions"] == 4  # the strike and three hand-overs
    assert summary["energy"]["dissipated_J"] == 0.0
    # head-on impacts part at their approach speed: the parting floor never acts
    assert summary["parting_floor_collisions"] == 0
    assert summary["energy"]["given_by_parting_floor_J"] == 0.0
    assert summary["energy"]["kinetic_end_J"] == pytest.approx(0.5, rel=1e-12, abs=0.0)
    assert summary["momentum"]["end_kg_m_s"] == pytest.approx([1.0, 0.0], rel=1e-12, abs=1e-12)


def test_run_a_rigid_body_reports_its_spin_and_energy_balance(tmp_path: Path) -> None:
    # rod-drop: a 1 m x 5 cm rod (density 1: m = 0.05 kg) lands at 30 degrees on a static
    # floor (e = 0.5) and turns. summary.json gives its rotational energy I w^2 / 2 with
    # I = m (w^2 + h^2) / 12, and angular momentum about the origin m (x v_y - y v_x) + I w,
    # from the last frame; the energy balance closes to round-off (the impacts are exact:
    # the solver gives nothing).
    h5py = pytest.importorskip("h5py", reason="the io extra (h5py) is not installed")
    out = tmp_path / "rod"
    done = carom("run", "rod-drop", "--out", out, "--until", "0.6", "--animation", "none")
    assert done.returncode == 0, done.stderr
    summary = json.loads((out / "summary.json").read_text())
    with h5py.File(out / "trajectory.h5", "r") as f:
        x = f["particles/all/position/value"][-1, 1]
        v = f["particles/all/velocity/value"][-1, 1]
        w = f["particles/all/angular_velocity/value"][-1, 1, 2]
        m = f["particles/all/mass"][1]
    assert m == pytest.approx(0.05, rel=1e-15)
    inertia = m * (1.0 + 0.05**2) / 12.0
    energy = summary["energy"]
    assert energy["rotational_start_J"] == 0.0  # dropped without spin
    assert energy["rotational_end_J"] == pytest.approx(0.5 * inertia * w**2, rel=1e-12)
    assert energy["given_by_solver_J"] == 0.0
    assert energy["work_by_kinematic_bodies_J"] == 0.0  # nothing kinematic here
    assert "given_by_parting_floor_J" not in energy
    assert abs(energy["balance_error_relative"]) < 1e-12
    lz = m * (x[0] * v[1] - x[1] * v[0]) + inertia * w
    assert summary["angular_momentum"]["start_kg_m2_s"] == [0.0, 0.0, 0.0]
    assert summary["angular_momentum"]["end_kg_m2_s"] == pytest.approx([0.0, 0.0, lz], rel=1e-12)
    # it did land: m g h = 0.05 * 9.81 * 1 = 0.49 J at the start, most of it lost since
    assert energy["dissipated_J"] > 0.1
    assert "energy.png" in done.stdout
    # a time-stepped run reports its steps (0.6 s at 60 Hz), not a collision rate
    assert re.search(
        r"36 steps of 0.01667 s in [0-9.]+ s, [0-9.]+ ms a step; \d+ impacts? ", done.stdout
    )


def _refused(done: subprocess.CompletedProcess[str], out: Path, message: str) -> None:
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    assert done.stderr.startswith("carom: error: ")
    assert message in done.stderr
    assert not out.exists()


def test_a_missing_scene_is_refused_without_output(tmp_path: Path) -> None:
    out = tmp_path / "out"
    done = carom("run", tmp_path / "nope.toml", "--out", out)
    _refused(done, out, "no such scene file, and no built-in scene of that name")


def test_a_bad_scene_is_refused_without_output(tmp_path: Path) -> None:
    scene = tmp_path / "bad.toml"
    scene.write_text(
        '[world]\ndimension = 2\nbox = [1.0, 1.0]\ncolour = "red"\n[run]\nuntil = 1.0\n'
    )
    out = tmp_path / "out"
    done = carom("run", scene, "--out", out)
    _refused(done, out, "bad.toml:4: [world] colour: is not a known key")


def test_an_existing_output_is_never_clobbered(tmp_path: Path) -> None:
    out = tmp_path / "out"
    out.mkdir()
    (out / "mine.txt").write_text("keep me")
    done = carom("run", "bouncing-ball", "--out", out, "--until", "0.1")
    assert done.returncode == 2
    assert "Traceback" not in done.stderr
    assert (out / "mine.txt").read_text() == "keep me"
    assert sorted(p.name for p in out.iterdir()) == ["mine.txt"]
    done = carom("run", "bouncing-ball", "--out", out, "--until", "0.1", "--force")
    assert done.returncode == 0, done.stderr
    assert (out / "summary.json").exists()


def test_a_bad_until_is_refused(tmp_path: Path) -> None:
    out = tmp_path / "out"
    done = carom("run", "bouncing-ball", "--out", out, "--until", "-1")
    _refused(done, out, "--until must be a number of seconds from 1e-100 to 1e+100")


def test_the_trajectory_is_h5md_with_every_frame(tmp_path: Path) -> None:
    h5py = pytest.importorskip("h5py", reason="the io extra (h5py) is not installed")
    out = tmp_path / "cradle"
    done = carom("run", "newtons-cradle", "--out", out, "--until", "0.6")
    assert done.returncode == 0, done.stderr
    with h5py.File(out / "trajectory.h5", "r") as f:
        assert tuple(f["h5md"].attrs["version"]) == (1, 1)
        assert f["h5md/creator"].attrs["name"] == "carom"
        box = f["particles/all/box"]
        assert box.attrs["dimension"] == 2
        assert list(box.attrs["boundary"]) == ["none", "none"]
        np.testing.assert_array_equal(box["edges"][()], [1.4, 0.4])
        np.testing.assert_array_equal(f["particles/all/radius"][()], [0.05] * 5)
        position = f["particles/all/position"]
        assert position["value"].attrs["unit"] == "m"
        # the start and one frame every 0.01 s to 0.6 s: 61 frames of 5 bodies in 2D
        assert position["value"].shape == (61, 5, 2)
        np.testing.assert_allclose(position["time"][()], np.arange(61) * 0.01, rtol=0, atol=1e-12)
        np.testing.assert_array_equal(position["step"][()], np.arange(61))
        # the strike at 0.3 s hands the 1 m/s to the last ball: at 0.6 s it is 0.3 m further
        # on, the first ball stopped where it touched the second (x = 0.5)
        last = position["value"][-1]
        np.testing.assert_allclose(last[:, 0], [0.5, 0.6, 0.7, 0.8, 1.2], rtol=0, atol=1e-12)
        velocity = f["particles/all/velocity/value"][-1]
        np.testing.assert_allclose(velocity[:, 0], [0, 0, 0, 0, 1.0], rtol=0, atol=1e-12)
        # kinetic energy, m v^2 / 2 = 0.5 J in every frame (elastic)
        ke = f["observables/kinetic_energy/value"][()]
        np.testing.assert_allclose(ke, 0.5, rtol=1e-12, atol=0)


def test_without_h5py_the_run_is_refused_before_it_starts(tmp_path: Path) -> None:
    # the io extra missing: one message saying how to install it, exit 2, nothing written
    out = tmp_path / "out"
    code = (
        "import sys; sys.modules['h5py'] = None\n"
        "from carom.cli import main\n"
        f"sys.exit(main(['run', 'bouncing-ball', '--out', {str(out)!r}]))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=300)
    _refused(done, out, "needs h5py: pip install 'carom[io]'")


def test_plots_are_written_where_they_mean_something(tmp_path: Path) -> None:
    image = pytest.importorskip("matplotlib.image", reason="the viz extra is not installed")
    gas = tmp_path / "gas"
    done = carom("run", "hard-sphere-gas", "--out", gas, "--until", "0.5", "--no-trajectory")
    assert done.returncode == 0, done.stderr
    for name in ("energy.png", "collision_rate.png", "speeds.png"):
        picture = image.imread(gas / name)
        assert picture.ndim == 3
        assert picture.shape[0] > 200
        assert picture.shape[1] > 400
    ball = tmp_path / "ball"
    done = carom("run", "bouncing-ball", "--out", ball, "--until", "1.0")
    assert done.returncode == 0, done.stderr
    # one ball under gravity is no gas: no speed distribution
    assert sorted(p.name for p in ball.glob("*.png")) == ["collision_rate.png", "energy.png"]
    quiet = tmp_path / "quiet"
    done = carom("run", "bouncing-ball", "--out", quiet, "--until", "1.0", "--no-plots")
    assert done.returncode == 0, done.stderr
    assert not list(quiet.glob("*.png"))


def _coloured(frame: np.ndarray) -> np.ndarray:
    """Mask of strongly coloured pixels (the bodies; box, text and background are grey)."""
    f = frame.astype(float)
    return (f.max(axis=-1) - f.min(axis=-1)) > 60


def test_the_animation_decodes_with_one_frame_per_trajectory_frame(tmp_path: Path) -> None:
    imageio_ffmpeg = pytest.importorskip("imageio_ffmpeg", reason="the viz extra is missing")
    out = tmp_path / "cradle"
    done = carom("run", "newtons-cradle", "--out", out, "--until", "0.6")
    assert done.returncode == 0, done.stderr
    assert "animation.mp4" in done.stdout
    # decoded by the ffmpeg that imageio-ffmpeg ships, to raw RGB: 960 x 720 per frame
    raw = subprocess.run(
        [
            imageio_ffmpeg.get_ffmpeg_exe(),
            "-v",
            "error",
            "-i",
            str(out / "animation.mp4"),
            "-f",
            "rawvideo",
            "-pix_fmt",
            "rgb24",
            "-",
        ],
        capture_output=True,
        check=True,
        timeout=120,
    ).stdout
    width, height = 960, 720
    assert len(raw) % (width * height * 3) == 0
    frames = list(np.frombuffer(raw, np.uint8).reshape(-1, height, width, 3))
    assert len(frames) == 61  # the start and one every 0.01 s to 0.6 s, as in trajectory.h5
    # the balls are drawn in colour, the same area in every frame (five disks; the colour
    # bar's column is left out), and their centre of area moves right with the momentum
    # (1 kg m/s to the right all along: the centre of mass moves 0.2 m / 0.6 s = 0.33 m/s)
    columns = np.arange(width) < int(0.86 * width)
    areas, centres = [], []
    for frame in frames[::10]:
        mask = _coloured(frame) & columns[None, :]
        areas.append(mask.sum())
        centres.append(np.nonzero(mask)[1].mean())
    assert min(areas) > 1000
    assert max(areas) < 1.1 * min(areas)
    assert np.all(np.diff(centres) > 0)


def test_a_gif_on_request(tmp_path: Path) -> None:
    iio = pytest.importorskip("imageio.v3", reason="the viz extra is missing")
    out = tmp_path / "ball"
    done = carom("run", "case-4", "--out", out, "--animation", "gif", "--no-plots")
    assert done.returncode == 0, done.stderr
    film = iio.imread(out / "animation.gif", index=None)
    assert film.shape[0] == 101  # 0 to 1 s every 0.01 s
    assert not (out / "animation.mp4").exists()


def test_the_progress_bar_shows_on_a_terminal_only(tmp_path: Path) -> None:
    import fcntl
    import pty
    import struct
    import termios

    done = carom("run", "hard-sphere-gas", "--out", tmp_path / "a", "--until", "0.5")
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""  # not a terminal: quiet
    leader, follower = pty.openpty()
    # a terminal 120 columns wide, as a person's would be
    fcntl.ioctl(follower, termios.TIOCSWINSZ, struct.pack("HHHH", 40, 120, 0, 0))
    process = subprocess.Popen(
        [
            sys.executable,
            "-m",
            "carom",
            "run",
            "hard-sphere-gas",
            "--out",
            str(tmp_path / "b"),
            "--until",
            "0.5",
            "--animation",
            "none",
        ],
        stdin=subprocess.DEVNULL,
        stdout=subprocess.DEVNULL,
        stderr=follower,
        env={**os.environ, "MPLBACKEND": "Agg"},
    )
    os.close(follower)
    seen = b""
    while True:
        try:
            chunk = os.read(leader, 4096)
        except OSError:
            break
        if not chunk:
            break
        seen += chunk
    os.close(leader)
    assert process.wait(timeout=300) == 0
    text = seen.decode(errors="replace")
    # simulated time, the rate of events and the time left
    assert "simulating 100%" in text
    assert "t = 0.5 of 0.5 s" in text
    assert "events/s" in text
    assert "<" in text


@pytest.mark.parametrize(("change", "message"), BAD_SCENES)
def test_each_bad_scene_ends_the_command_with_one_message(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], change: tuple[str, str], message: str
) -> None:
    # in-process (main() is what the carom script calls): exit code 2, one line on standard
    # error naming file, key and fix, no traceback, nothing written
    from carom.cli import main

    old, new = change
    scene = tmp_path / "scene.toml"
    scene.write_text(GOOD.replace(old, new, 1))
    out = tmp_path / "out"
    assert main(["run", str(scene), "--out", str(out)]) == 2
    captured = capsys.readouterr()
    assert captured.out == ""
    assert captured.err.startswith("carom: error: ")
    assert captured.err.count("\n") == 1
    assert "Traceback" not in captured.err
    assert re.search(message, captured.err)
    assert not out.exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.toml"]  # no work directory


def test_first_run_says_it_compiles_and_times_the_run_apart(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch, capsys: pytest.CaptureFixture[str]
) -> None:
    # regression: the first `make demo` said "case 1: 1 collisions in 33.11 s", the kernels'
    # compile time reported as the run's. Now a run whose kernels are not cached says first
    # that they are being compiled, and the run's time excludes preparing them.
    import carom.jit
    from carom.cli import main
    from carom.run.runner import run_scene

    monkeypatch.setattr(carom.jit, "kernels_cached", lambda: False)
    assert main(["run", "case-1", "--out", str(tmp_path / "a"), "--no-trajectory",
                 "--no-plots", "--animation", "none", "--quiet"]) == 0  # fmt: skip
    out, err = capsys.readouterr()
    assert "compiling the engine's kernels (once per install" in err
    assert "case 1" in out.lower()
    assert "2 bodies, 1 s simulated, 1 collision and 0 at walls" in out
    report = run_scene(
        "case-1",
        tmp_path / "b",
        outputs=Outputs(trajectory=False, plots=False, animation="none"),
        progress=False,
    )
    assert report.prepare_seconds > 0.0
    assert report.collisions == 1
