"""``carom compare`` as a user runs it: the table, the files, and every refusal."""

from __future__ import annotations

import importlib.util
import json

import pytest

from carom.cli import main
from carom.compare.engines import ENGINES
from carom.studies.two_spheres import ROUND_OFF
from tests.cli.helpers import carom


def test_compare_writes_table_json_text_and_plot(tmp_path):
    out = tmp_path / "cmp"
    result = carom("compare", "case-2", "--engines", "carom", "--out", out)
    assert result.returncode == 0, result.stderr
    assert "closed form: two smooth spheres" in result.stdout
    assert result.stdout.splitlines()[4].startswith("carom")
    assert sorted(p.name for p in out.iterdir()) == ["compare.json", "compare.png", "compare.txt"]
    data = json.loads((out / "compare.json").read_text())
    run = data["engines"]["carom"]
    assert run["metrics"]["velocity_error"] <= ROUND_OFF
    assert run["settings"]["frame_interval_s"] == 0.01
    assert data["scene"] == "case-2"
    assert data["bodies"] == 2
    assert data["until_s"] == 1.0
    assert (out / "compare.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_every_installed_peer_runs_by_default(tmp_path):
    # (each peer says how it is installed: pip install 'carom[compare]', or make pooltool)
    missing = [why for e in ENGINES.values() if (why := e.missing()) is not None]
    if missing:
        pytest.skip("; ".join(missing))
    out = tmp_path / "cradle"
    result = carom("compare", "newtons-cradle", "--out", out)
    assert result.returncode == 0, result.stderr

    def strict(constant):
        raise AssertionError(f"{constant} is not JSON (pymunk's sleep threshold is inf)")

    data = json.loads((out / "compare.json").read_text(), parse_constant=strict)
    assert list(data["engines"]) == ["carom", "pymunk", "pybullet", "mujoco"]
    assert data["skipped"] == {}
    for name, run in data["engines"].items():
        assert run["settings"], name  # every setting is on record
        assert run["notes"], name
        assert f"\n{name} " in "\n" + result.stdout


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["case-1", "--engines", "carom,nosuch"], "unknown engine 'nosuch'"),
        (["case-1", "--engines", " , "], "--engines needs at least one engine"),
        (["hard-sphere-gas"], "periodic box"),
        (["galton-board"], "static bodies"),
        (["gas-3d", "--engines", "pymunk"], "pymunk simulates 2D only"),
        (["case-1", "--until", "-1"], "--until must be a number of seconds from 1e-100"),
        (["no-such-scene"], "no-such-scene"),
    ],
)
def test_bad_input_exits_2_with_one_line_and_writes_nothing(tmp_path, args, message):
    out = tmp_path / "out"
    result = carom("compare", *args, "--out", out)
    assert result.returncode == 2
    assert message in result.stderr
    assert "Traceback" not in result.stderr
    assert not out.exists()


def test_an_existing_folder_is_kept_without_force(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    (out / "mine.txt").write_text("keep me")
    result = carom("compare", "case-1", "--engines", "carom", "--out", out)
    assert result.returncode == 2
    assert "--force" in result.stderr
    assert (out / "mine.txt").read_text() == "keep me"
    result = carom("compare", "case-1", "--engines", "carom", "--out", out, "--force")
    assert result.returncode == 0, result.stderr
    assert not (out / "mine.txt").exists()
    assert (out / "compare.json").exists()


def test_a_peer_that_is_not_installed_is_skipped_or_refused(monkeypatch, capsys):
    real = importlib.util.find_spec
    monkeypatch.setattr(
        importlib.util, "find_spec", lambda name, *a: None if name == "pymunk" else real(name, *a)
    )
    assert main(["compare", "case-1", "--engines", "carom"]) == 0
    capsys.readouterr()
    assert main(["compare", "case-5"]) == 0
    out = capsys.readouterr().out
    assert "pymunk    skipped: pymunk is not installed; pip install 'carom[compare]'" in out
    assert main(["compare", "case-5", "--engines", "pymunk"]) == 2
    assert "pymunk is not installed" in capsys.readouterr().err


def test_progress_bars_count_each_engine_s_steps(capsys):
    from carom.compare import compare

    compare("case-1", ["carom"], progress=True)  # 1 s at carom's 0.01 s frames
    err = capsys.readouterr().err
    assert "carom" in err
    assert "100/100" in err


def test_a_gas_plots_its_energy_error_where_no_velocity_closed_form_exists(tmp_path):
    out = tmp_path / "gas"
    result = carom("compare", "gas-2d", "--engines", "carom", "--until", "0.05", "--out", out)
    assert result.returncode == 0, result.stderr
    assert "closed form: energy conservation" in result.stdout
    data = json.loads((out / "compare.json").read_text())
    metrics = data["engines"]["carom"]["metrics"]
    assert metrics["velocity_error"] is None
    # 1000 elastic disks: the energy is a sum of 1000 terms, each exact to round-off
    assert abs(metrics["energy_error"]) < 1e-13
    assert (out / "compare.png").stat().st_size > 10_000
