"""`carom run` end to end: the files it writes, their physics, and how it refuses bad input."""

from __future__ import annotations

import csv
import json
import math
import os
import subprocess
import sys
from pathlib import Path

import pytest


def carom(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "carom", *map(str, args)],
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=300,
        env={**os.environ, "MPLBACKEND": "Agg"},
    )


def test_run_a_bouncing_ball_and_check_its_events(tmp_path: Path) -> None:
    out = tmp_path / "ball"
    done = carom("run", "bouncing-ball", "--out", out, "--until", "2.0")
    assert done.returncode == 0, done.stderr
    assert "wrote events.csv, summary.json" in done.stdout
    with (out / "events.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    # dropped from h0 = 1.55 - 0.05 = 1.5 m (centre above contact) under g = 9.81 m/s^2 onto a
    # floor of e = 0.8: first impact at sqrt(2 h0 / g) with u = -sqrt(2 g h0), leaving at
    # -e u; each later flight lasts 2 e^k sqrt(2 h0 / g) (closed forms, to round-off)
    g, h0, e = 9.81, 1.5, 0.8
    t1, u1 = math.sqrt(2 * h0 / g), math.sqrt(2 * g * h0)
    assert rows[0]["partner"] == "wall y-"
    assert float(rows[0]["time_s"]) == pytest.approx(t1, rel=1e-12, abs=0.0)
    assert float(rows[0]["un_before_m_s"]) == pytest.approx(-u1, rel=1e-12, abs=0.0)
    assert float(rows[0]["un_after_m_s"]) == pytest.approx(e * u1, rel=1e-12, abs=0.0)
    assert float(rows[1]["time_s"]) - float(rows[0]["time_s"]) == pytest.approx(
        2 * e * t1, rel=1e-12, abs=0.0
    )
    summary = json.loads((out / "summary.json").read_text())
    assert summary["wall_collisions"] == len(rows)
    assert summary["simulated_time_s"] == 2.0
    # energy: start (all potential) = end (kinetic + potential) + dissipated, to round-off
    assert abs(summary["energy"]["balance_error_relative"]) < 1e-12
    assert summary["energy"]["dissipated_J"] > 0


def test_run_newtons_cradle_keeps_energy_and_momentum(tmp_path: Path) -> None:
    out = tmp_path / "gas"
    done = carom("run", "newtons-cradle", "--out", out, "--until", "0.6")
    assert done.returncode == 0, done.stderr
    summary = json.loads((out / "summary.json").read_text())
    assert summary["collisions"] == 4  # the strike and three hand-overs
    assert summary["energy"]["dissipated_J"] == 0.0
    assert summary["energy"]["kinetic_end_J"] == pytest.approx(0.5, rel=1e-12, abs=0.0)
    assert summary["momentum"]["end_kg_m_s"] == pytest.approx([1.0, 0.0], rel=1e-12, abs=1e-12)


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
    _refused(done, out, "--until must be a positive number of seconds")
