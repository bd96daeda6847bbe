"""The showcase of `make demo`: every link on index.html leads to a file it wrote."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from carom.run.showcase import SHOWCASE_SCENES, build_showcase
from carom.studies.two_spheres import run_study

pytest.importorskip("h5py", reason="the io extra (h5py) is not installed")
pytest.importorskip("imageio_ffmpeg", reason="the viz extra is not installed")


@pytest.mark.slow  # (the whole showcase but its sweep)
def test_the_page_shows_the_study_and_links_every_file(tmp_path: Path) -> None:
    out = tmp_path / "out"
    lines: list[str] = []
    page = build_showcase(
        out,
        scenes=("case-4", "newtons-cradle", "rod-drop", "ring-toss"),
        sweeps=("rebound",),
        say=lines.append,
    )
    assert page == out / "index.html"
    text = page.read_text()
    # one row per impact of the study (19), each model's error shown
    assert text.count("<tr><td>") == len(run_study())
    assert "Conclusions, derived from these numbers" in text
    links = set(re.findall(r'(?:href|src)="([^"#]+)"', text))
    assert "scenes/case-4/animation.mp4" in links
    assert "scenes/newtons-cradle/trajectory.h5" in links
    assert "cases/case-7.png" in links
    assert "scenes/rod-drop/animation.mp4" in links  # a rigid body, drawn turned
    assert "energy given by the solver" in text  # the rigid engine's ledger
    assert "scenes/ring-toss/animation.mp4" in links  # 3D rigid bodies, drawn as shaded faces
    # the sweep: its plot and table, and the closed form beside each point
    assert "sweeps/rebound/plot-rebound_height.png" in links
    assert "sweeps/rebound/results.csv" in links
    # (e^2 h0 to round-off: every one of the ten rows agrees to 0.00%)
    assert text.count("<tr class='sweep'>") == 10
    assert text.count("<td>+0.00%</td>") + text.count("<td>-0.00%</td>") == 10
    missing = [link for link in links if not (out / link).is_file()]
    assert not missing
    # and nothing written that the page does not show or link
    files = {p.relative_to(out).as_posix() for p in out.rglob("*") if p.is_file()}
    assert files - links == {"index.html"}
    # the study, then each scene (and a line on compiling when the kernels were not cached)
    done = [line for line in lines if " -> " in line]
    assert len(done) == 6
    assert done[0].startswith("the seven two-sphere cases")


def test_the_showcase_runs_what_the_issue_asks() -> None:
    # the seven cases, Newton's cradle, a billiards break and a 3D gas (issue 1); a pyramid, a
    # tumbler and the rod drop (issue 13)
    assert SHOWCASE_SCENES[:7] == tuple(f"case-{n}" for n in range(1, 8))
    assert {"newtons-cradle", "billiards-break", "hard-sphere-gas"} <= set(SHOWCASE_SCENES)
    assert {"pyramid", "tumbler", "rod-drop"} <= set(SHOWCASE_SCENES)
    # 3D rigid bodies beside them: a pyramid, the ring toss, the billiards break (issue 42)
    assert {"pyramid-3d", "ring-toss", "billiards-3d"} <= set(SHOWCASE_SCENES)


def test_the_showcase_says_when_it_compiles_first(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # regression: the first make demo printed "case 1: 1 collisions in 33.11 s", a minute of
    # compiling reported as the run; now it says so before, and times the runs apart
    from carom.run import showcase

    monkeypatch.setattr(showcase, "kernels_cached", lambda: False)
    lines: list[str] = []
    build_showcase(tmp_path / "out", scenes=("case-1",), sweeps=(), say=lines.append)
    compiling = [k for k, line in enumerate(lines) if "compiling the engines' kernels" in line]
    case = [k for k, line in enumerate(lines) if "1 collision and 0 at walls in" in line]
    assert compiling
    assert case
    assert compiling[0] < case[0]
