"""The replay page of a carom run (carom.play.replay): one HTML file, no server, no network."""

from __future__ import annotations

import base64
import json
import re
import subprocess
import sys
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from carom.play.replay import REPLAY, write_replay
from carom.play.wire import unpack
from tests.play.scenes import SMALL_PYRAMID
from tests.play.test_browser import CHROMIUM, FLAGS, drawn

h5py = pytest.importorskip("h5py")


@pytest.fixture(scope="module")
def run(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A carom run of the small pyramid with a ball shot into it: trajectory and replay."""
    folder = tmp_path_factory.mktemp("run")
    scene = folder / "scene.toml"
    scene.write_text(
        SMALL_PYRAMID.replace("until = 10.0", "until = 1.5\nframe_interval = 0.05")
        + '\n[[bodies]]\nshape = "circle"\nradius = 0.4\npositions = [[4.0, 1.0]]\n'
        + "velocities = [[12.0, 2.0]]\ndensity = 5.0\n"
    )
    out = folder / "out"
    done = subprocess.run(
        [sys.executable, "-m", "carom", "run", str(scene), "--out", str(out), "--animation",
         "none", "--quiet"],
        capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr
    assert REPLAY in done.stdout  # listed among the files written
    return out


def payload(page: str) -> dict[str, Any]:
    text = re.search(r"window\.CAROM_REPLAY = (\{.*?\});</script>", page, re.S)
    assert text is not None
    data: dict[str, Any] = json.loads(text.group(1))
    return data


def test_the_page_holds_the_runs_frames(run: Path) -> None:
    page = (run / REPLAY).read_text()
    # nothing to fetch: no file, server or network named
    assert not re.search(r'(src|href)="(?!#)', page)
    data = payload(page)
    shapes, arrays = unpack(base64.b64decode(data["shapes"]))
    assert shapes["dim"] == 2
    assert len(arrays["radius"]) == 17  # the ground, 15 boxes and the ball
    with h5py.File(run / "trajectory.h5") as f:
        x = f["particles/all/position/value"][:]
        t = f["particles/all/position/time"][:]
        kinetic = f["observables/kinetic_energy/value"][:]
    assert len(data["frames"]) == len(t) == 31
    for k in (0, 17, 30):
        header, frame = unpack(base64.b64decode(data["frames"][k]))
        assert header["time"] == t[k]
        assert header["energy"]["kinetic"] == kinetic[k]
        np.testing.assert_array_equal(frame["x"], x[k].astype(np.float32))


def test_a_long_run_is_thinned(run: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    import carom.play.replay as replay

    monkeypatch.setattr(replay, "MOST_BYTES", 10_000)
    out = write_replay(run, run / "thin.html")
    data = payload(out.read_text())
    kept = len(data["frames"])
    assert 2 <= kept < 31
    assert f"{kept} of its 31 frames" in data["note"]
    last, _ = unpack(base64.b64decode(data["frames"][-1]))
    assert last["time"] == pytest.approx(1.5)  # the last frame is kept


@pytest.mark.slow
def test_the_replay_plays_in_a_browser_from_the_file(run: Path) -> None:
    if CHROMIUM is None:
        pytest.skip("no chromium (make test installs it)")
    playwright = pytest.importorskip("playwright.sync_api")
    with playwright.sync_playwright() as p:
        browser = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        page = browser.new_page(viewport={"width": 1100, "height": 700})
        errors: list[str] = []
        asked: list[str] = []
        page.on("console", lambda m: errors.append(m.text) if m.type == "error" else None)
        page.on("pageerror", lambda e: errors.append(str(e)))
        page.on("request", lambda r: asked.append(r.url))
        page.goto((run / REPLAY).as_uri())
        page.wait_for_timeout(800)
        share, colours = drawn(page.screenshot())
        assert share > 0.01
        assert colours > 8
        # scrubbing: the timeline's frame 20 is the run's frame 20
        page.fill("#scrub", "20")  # (sets the range input and fires its input event)
        page.wait_for_timeout(200)
        assert page.evaluate("carom.state.header.time") == pytest.approx(1.0)
        assert "frame 21 of 31" in page.inner_text("#frameno")
        # picking the ball: its speed and energy
        with h5py.File(run / "trajectory.h5") as f:
            ball = int(np.argmin(np.abs(f["particles/all/radius"][:] - 0.4)))
            x = f["particles/all/position/value"][20, ball]
            v = f["particles/all/velocity/value"][20, ball]
        page.mouse.click(*page.evaluate(f"carom.toScreen([{x[0]}, {x[1]}])"))
        status = page.inner_text("#status")
        assert status.startswith(f"body {ball}: speed "), status
        shown = float(status.split("speed ")[1].split(" ")[0])
        assert shown == pytest.approx(np.hypot(*v), rel=1e-3)  # (4 digits shown)
        assert errors == []
        assert [u for u in asked if not u.startswith("file:")] == []
        browser.close()
