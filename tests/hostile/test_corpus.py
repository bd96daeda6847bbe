"""Every entry of the hostile corpus is refused with one clear message: a CaromError from the
API, and from the command line exit code 2, one line, no traceback, nothing left behind."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from carom import CaromError
from carom.cli import main
from carom.run.runner import run_scene, work_directory
from carom.scene import load_scene
from tests.cli.helpers import carom as carom_command
from tests.hostile.corpus import API, SCENES


@pytest.mark.parametrize(
    ("text", "pattern"), [(t, p) for _, t, p in SCENES], ids=[i for i, _, _ in SCENES]
)
def test_a_hostile_scene_is_refused_by_the_api(tmp_path: Path, text: str, pattern: str) -> None:
    path = tmp_path / "scene.toml"
    path.write_text(text)
    with pytest.raises(CaromError, match=pattern):
        _load_build_and_run(path, tmp_path / "out")


def _load_build_and_run(path: Path, out: Path) -> None:
    """What carom run does, through the API: the refusal may come at any stage (the frame
    count is checked by run_scene, which knows the outputs)."""
    load_scene(path).build()
    run_scene(path, out, progress=False)


@pytest.mark.parametrize(
    ("text", "pattern"), [(t, p) for _, t, p in SCENES], ids=[i for i, _, _ in SCENES]
)
def test_a_hostile_scene_ends_carom_run_with_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str], text: str, pattern: str
) -> None:
    path = tmp_path / "scene.toml"
    path.write_text(text)
    out = tmp_path / "out"
    code = main(["run", str(path), "--out", str(out), "--quiet"])
    captured = capsys.readouterr()
    assert code == 2
    assert captured.out == ""
    lines = captured.err.splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("carom: error: ")
    assert re.search(pattern, lines[0]), lines[0]
    assert "\x1b" not in captured.err
    assert "\u202e" not in captured.err
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.toml"]  # nothing left
    assert not work_directory(out).exists()


@pytest.mark.parametrize("name", ["box-1e300", "nested-too-deeply", "negative-seed"])
def test_as_a_process_too(tmp_path: Path, name: str) -> None:
    # what once crashed the interpreter (exit 139) or printed a traceback, run for real
    text, pattern = next((t, p) for i, t, p in SCENES if i == name)
    (tmp_path / "scene.toml").write_text(text)
    done = carom_command("run", "scene.toml", "--out", "out", cwd=tmp_path)
    assert done.returncode == 2, done.stderr
    assert "Traceback" not in done.stderr
    assert re.search(pattern, done.stderr)
    assert sorted(p.name for p in tmp_path.iterdir()) == ["scene.toml"]


@pytest.mark.parametrize(
    ("call", "pattern"), [(c, p) for _, c, p in API], ids=[i for i, _, _ in API]
)
def test_a_hostile_api_call_raises_carom_error(call, pattern: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(CaromError, match=pattern):
        call()


def test_a_scene_path_with_a_newline_is_named_on_one_line(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    # issue 45: the path was printed raw, over two lines
    code = main(["run", str(tmp_path / "a\nb.toml"), "--out", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert code == 2
    assert len(err.splitlines()) == 1, err
    assert "a\\nb.toml: no such scene file" in err
