"""`carom cases` end to end, as a user runs it: exit codes, files, and the JSON's physics."""

from __future__ import annotations

import csv
import json
import math
import subprocess
import sys
from pathlib import Path

import pytest

from carom.studies.two_spheres import MODELS, ROUND_OFF
from tests.cli.helpers import carom


@pytest.fixture(scope="module")
def study(
    tmp_path_factory: pytest.TempPathFactory,
) -> tuple[Path, subprocess.CompletedProcess[str]]:
    out = tmp_path_factory.mktemp("runs") / "cases"
    return out, carom("cases", "--out", str(out), "--json")


def test_help_explains_itself() -> None:
    top = carom("--help")
    assert top.returncode == 0
    assert "cases" in top.stdout
    assert "Hecker" in top.stdout
    sub = carom("cases", "--help")
    assert sub.returncode == 0
    for option in ("--out", "--json", "--force", "--no-figures"):
        assert option in sub.stdout


def test_writes_every_output(study: tuple[Path, subprocess.CompletedProcess[str]]) -> None:
    out, proc = study
    assert proc.returncode == 0, proc.stderr
    names = sorted(p.name for p in out.iterdir())
    assert names == sorted(["cases.csv", "cases.json", *(f"case-{i}.png" for i in range(1, 8))])
    assert not [p for p in out.parent.iterdir() if p.name.startswith(".")]  # no staging left
    assert json.loads(proc.stdout) == json.loads((out / "cases.json").read_text())


def test_json_matches_the_closed_form(study: tuple[Path, subprocess.CompletedProcess[str]]) -> None:
    # PHYSICS.md section 1 in the (n, t) frame: the normal components follow the 1D law
    # v1n' = ((m1 - e m2) v1n + (1 + e) m2 v2n) / (m1 + m2) (and symmetrically), the
    # tangential components are unchanged. carom and Hecker (contact normal) must match it to
    # round-off; the head-on reading must match it only in head-on cases.
    out, _ = study
    doc = json.loads((out / "cases.json").read_text())
    assert len(doc["records"]) == 19
    for rec in doc["records"]:
        m1, m2, e = rec["m1"], rec["m2"], rec["e"]
        d = [a - b for a, b in zip(rec["x1"], rec["x2"], strict=True)]
        n = [c / math.hypot(*d) for c in d]
        t = [-n[1], n[0]]

        def proj(v, axis):
            return v[0] * axis[0] + v[1] * axis[1]

        v1n, v2n = proj(rec["v1"], n), proj(rec["v2"], n)
        v1n_after = ((m1 - e * m2) * v1n + (1 + e) * m2 * v2n) / (m1 + m2)
        v2n_after = ((m2 - e * m1) * v2n + (1 + e) * m1 * v1n) / (m1 + m2)
        expect1 = [v1n_after * n[i] + proj(rec["v1"], t) * t[i] for i in range(2)]
        expect2 = [v2n_after * n[i] + proj(rec["v2"], t) * t[i] for i in range(2)]
        scale = math.hypot(*(a - b for a, b in zip(rec["v1"], rec["v2"], strict=True)))
        for model in MODELS:
            got = rec["models"][model]
            err = max(math.dist(got["v1_after"], expect1), math.dist(got["v2_after"], expect2))
            if model != "hecker_head_on" or not rec["oblique"]:
                assert err <= ROUND_OFF * scale, (rec["case"], rec["e"], model)
            else:
                assert err > 0.1 * scale
    assert any("Verdict" in line for line in doc["conclusions"])


def test_csv_has_a_row_per_case_e_and_model(
    study: tuple[Path, subprocess.CompletedProcess[str]],
) -> None:
    out, _ = study
    with (out / "cases.csv").open() as handle:
        rows = list(csv.DictReader(handle))
    assert len(rows) == 19 * (1 + len(MODELS))  # exact + three models
    assert {r["model"] for r in rows} == {"exact", *MODELS}
    exact_case1 = next(
        r for r in rows if r["case"] == "1" and r["e"] == "1.0" and r["model"] == "exact"
    )
    # equal masses head-on elastic: velocities exchange (v1 = 1, v2 = -1 -> -1, 1)
    assert float(exact_case1["v1_after_x"]) == -1.0
    assert float(exact_case1["v2_after_x"]) == 1.0


def test_figures_decode(study: tuple[Path, subprocess.CompletedProcess[str]]) -> None:
    import matplotlib.image

    out, _ = study
    for i in range(1, 8):
        image = matplotlib.image.imread(out / f"case-{i}.png")
        rows = 1 if i == 7 else 3  # one row per restitution
        assert image.shape[1] > 1000  # four panels side by side
        assert image.shape[0] > 250 * rows
        assert image.std() > 0.01  # not blank


def test_refuses_to_clobber_and_force_replaces(tmp_path: Path) -> None:
    out = tmp_path / "mine"
    out.mkdir()
    (out / "notes.txt").write_text("my notes")
    proc = carom("cases", "--out", str(out), "--no-figures")
    assert proc.returncode == 2
    assert "already exists" in proc.stderr
    assert "--force" in proc.stderr
    assert "Traceback" not in proc.stderr
    assert proc.stdout == ""  # refused before doing anything
    assert (out / "notes.txt").read_text() == "my notes"
    proc = carom("cases", "--out", str(out), "--no-figures", "--force")
    assert proc.returncode == 0, proc.stderr
    assert sorted(p.name for p in out.iterdir()) == ["cases.csv", "cases.json"]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["mine"]


@pytest.mark.parametrize(
    ("args", "message"),
    [
        (["cases", "--bogus"], "unrecognized arguments"),
        ([], "required: COMMAND"),
        (["explode"], "invalid choice"),
    ],
)
def test_bad_usage_exits_2(args: list[str], message: str) -> None:
    proc = carom(*args)
    assert proc.returncode == 2
    assert message in proc.stderr
    assert "Traceback" not in proc.stderr


def test_out_is_a_file(tmp_path: Path) -> None:
    target = tmp_path / "file.txt"
    target.write_text("keep me")
    proc = carom("cases", "--out", str(target))
    assert proc.returncode == 2
    assert "is not a directory" in proc.stderr
    assert target.read_text() == "keep me"


def test_interrupted_write_leaves_nothing(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # A failure (here Ctrl-C) while the files are being written leaves no output directory
    # and no staging directory behind.
    from carom import cli
    from carom.viz import cases as viz_cases

    def interrupted(*_args: object, **_kwargs: object) -> None:
        raise KeyboardInterrupt

    monkeypatch.setattr(viz_cases, "plot_case", interrupted)
    code = cli.main(["cases", "--out", str(tmp_path / "run")])
    assert code == 130
    assert list(tmp_path.iterdir()) == []


def test_terminal_output_shows_inputs_and_every_models_velocities() -> None:
    proc = carom("cases")
    assert proc.returncode == 0, proc.stderr
    text = proc.stdout
    # case 1 block: inputs, then e = 1: equal masses exchange velocities in every model
    assert "Case 1: head-on, equal masses, opposite directions" in text
    assert "v1 = ( 1.000,  0.000) m/s, v2 = (-1.000,  0.000) m/s" in text
    for label in ("exact", "carom", "Hecker, contact normal", "Hecker, head-on reading"):
        assert f"{label:<24}(-1.000,  0.000)  ( 1.000,  0.000)" in text
    assert "Summary" in text
    assert "Conclusions (derived from the numbers above):" in text
    brief = carom("cases", "--brief")
    assert brief.returncode == 0
    assert "Case 1:" not in brief.stdout
    assert "Conclusions" in brief.stdout


def test_a_reader_that_goes_away_is_not_an_error() -> None:
    # `carom cases | head -1`: the pipe closes early; carom stops quietly
    with subprocess.Popen(
        [sys.executable, "-m", "carom", "cases"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        stdin=subprocess.DEVNULL,
    ) as proc:
        assert proc.stdout is not None
        assert proc.stderr is not None
        proc.stdout.readline()
        proc.stdout.close()
        stderr = proc.stderr.read().decode()
        assert proc.wait(timeout=120) == 0
    assert "Traceback" not in stderr
