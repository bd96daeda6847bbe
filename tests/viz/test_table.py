"""A billiards run drawn from above: each ball's path on the table (carom.viz.table)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from carom.run.runner import Outputs, run_scene
from carom.scene import find_scene, load_scene
from carom.viz.table import billiards_table

PNG = b"\x89PNG\r\n\x1a\n"


def test_only_balls_on_a_level_cloth_make_a_table() -> None:
    # the shot scenes' box is the table; a pyramid of boxes or a gas is not one
    assert billiards_table(load_scene(find_scene("follow-shot")).build()) == (0.0, 0.0, 4.0, 2.0)
    assert billiards_table(load_scene(find_scene("three-cushion")).build()) is not None
    for name in ("pyramid-3d", "spin-ball-3d", "billiards-break", "hard-sphere-gas"):
        assert billiards_table(load_scene(find_scene(name)).build()) is None


@pytest.mark.parametrize(("name", "drawn"), [("follow-shot", True), ("rod-drop-3d", False)])
def test_a_run_draws_its_balls_paths_on_the_table(tmp_path: Path, name: str, drawn: bool) -> None:
    out = tmp_path / "run"
    report = run_scene(name, out, until=0.3, outputs=Outputs(animation="none"), progress=False)
    assert ("table.png" in report.written) is drawn
    assert (out / "table.png").exists() is drawn
    if drawn:
        assert (out / "table.png").read_bytes()[:8] == PNG
        assert (out / "table.png").stat().st_size > 10_000  # the cloth, two paths, two balls
    assert np.all(np.isfinite(load_scene(find_scene(name)).build().positions))
