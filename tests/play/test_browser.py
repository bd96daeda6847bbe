"""carom play in a real browser: Debian's chromium (``make test`` installs it) driven by
playwright, against a server in this process whose world the tests read."""

from __future__ import annotations

import io
import os
import shutil
import time
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import Any

import numpy as np
import pytest

from carom.play.server import PlayServer
from tests.play.conftest import start

CHROMIUM = os.environ.get("CAROM_CHROMIUM") or shutil.which("chromium")
#: what chromium needs here: no sandbox as root, no network beyond this machine
FLAGS = [
    "--no-sandbox",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
    "--no-first-run",
    "--disable-dev-shm-usage",
]

pytestmark = pytest.mark.slow


@pytest.fixture(scope="module")
def browser() -> Iterator[Any]:
    if CHROMIUM is None:
        why = "no chromium on this machine: make test installs Debian's (apt-get install chromium)"
        if os.environ.get("CI"):
            pytest.fail(why)
        pytest.skip(why)
    playwright = pytest.importorskip("playwright.sync_api")
    with playwright.sync_playwright() as p:
        chromium = p.chromium.launch(executable_path=CHROMIUM, args=FLAGS)
        yield chromium
        chromium.close()


class Page:
    """A page of the testbed and what its console said."""

    def __init__(self, browser: Any, url: str) -> None:
        self.page = browser.new_page(viewport={"width": 1100, "height": 700})
        self.errors: list[str] = []
        self.page.on("console", lambda m: self.errors.append(m.text) if m.type == "error" else None)
        self.page.on("pageerror", lambda e: self.errors.append(str(e)))
        self.page.goto(url)
        self.wait_for("carom.state.framesSeen > 3")

    def wait_for(self, condition: str, seconds: float = 60.0) -> None:
        # (polled from here: the page's policy forbids the eval that wait_for_function uses)
        end = time.monotonic() + seconds
        while not self.page.evaluate(condition):
            assert time.monotonic() < end, f"not within {seconds} s: {condition}"
            self.page.wait_for_timeout(50)

    def js(self, expression: str) -> Any:
        return self.page.evaluate(expression)

    def screen(self, point: Any) -> tuple[float, float]:
        x, y = self.js(f"carom.toScreen([{float(point[0])}, {float(point[1])}])")
        return float(x), float(y)


@pytest.fixture
def served_page(browser: Any, small_pyramid: Path) -> Iterator[tuple[PlayServer, Page]]:
    server, thread = start(str(small_pyramid))
    page = Page(browser, server.url)
    yield server, page
    page.page.close()
    server.stop()
    thread.join(timeout=20)
    assert server.errors == []


def until(condition: Callable[[], bool], seconds: float = 20.0) -> bool:
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        if condition():
            return True
        time.sleep(0.05)
    return condition()


def drawn(png: bytes) -> tuple[float, int]:
    """The share of the view's pixels that are not the background, and how many colours."""
    from matplotlib.image import imread

    image = imread(io.BytesIO(png))[..., :3]
    view = image[:, : image.shape[1] - 320]  # (the panel is on the right)
    background = np.array([20, 22, 26]) / 255
    painted = np.any(np.abs(view - background) > 0.02, axis=-1)
    colours = np.unique((view * 255).astype(np.uint8).reshape(-1, 3), axis=0)
    return float(painted.mean()), len(colours)


def test_the_page_loads_and_draws(served_page: tuple[PlayServer, Page]) -> None:
    _, page = served_page
    page.wait_for("carom.state.framesSeen > 30")
    share, colours = drawn(page.page.screenshot())
    # the small pyramid, its ground and the box's frame cover a few percent of the view
    assert share > 0.01
    assert colours > 8
    assert page.errors == []
    assert page.js("carom.state.shapeHeader.scene").endswith("small-pyramid.toml")


def test_a_drag_moves_the_box_in_the_servers_world(served_page: tuple[PlayServer, Page]) -> None:
    server, page = served_page
    world = server.live.world
    top = world.n_bodies - 1
    x0 = world.positions[top].copy()
    sx, sy = page.screen(x0)
    page.page.mouse.move(sx, sy)
    page.page.mouse.down()
    page.wait_for(f"carom.state.held === {top}", 10)
    scale = page.js("carom.toScreen([1, 0])[0] - carom.toScreen([0, 0])[0]")  # pixels a metre
    for k in range(1, 11):  # 3 m up, in ten moves
        page.page.mouse.move(sx, sy - k * 0.3 * scale)
        page.page.wait_for_timeout(30)
    # the target joint pulls it up to the pointer (a 5 Hz spring): 2 m within 2 s
    assert until(lambda: world.positions[top, 1] > x0[1] + 2.0, 10)
    page.page.mouse.up()
    assert until(lambda: world.joint_rows[0][-1, 0] < 0, 5)  # released: the joint is gone
    assert page.errors == []


def test_a_click_in_open_space_shoots_a_ball(served_page: tuple[PlayServer, Page]) -> None:
    server, page = served_page
    world = server.live.world
    n = world.n_bodies
    spot = np.array([3.0, 9.0])  # above the ground, left of the pyramid
    page.page.mouse.click(*page.screen(spot))
    assert until(lambda: world.n_bodies == n + 1, 10)
    # dropped from the click (a click is a drag of no length: no speed), it falls straight
    x = world.positions[n]
    scale = page.js("carom.toScreen([1, 0])[0] - carom.toScreen([0, 0])[0]")
    assert abs(x[0] - spot[0]) < 2.0 / scale  # within two pixels
    assert x[1] <= spot[1]
    assert page.errors == []


def test_pause_stops_time(served_page: tuple[PlayServer, Page]) -> None:
    server, page = served_page
    world = server.live.world
    page.page.click("#pause")
    assert until(lambda: server.live.paused, 5)
    t = world.time
    time.sleep(0.5)
    assert world.time == t
    page.wait_for('document.getElementById("pause").textContent === "play"', 5)
    page.page.click("#step")
    assert until(lambda: world.time == pytest.approx(t + server.live.dt), 5)
    page.page.click("#pause")  # (now "play")
    assert until(lambda: world.time > t + 0.2, 5)


def test_the_picker_switches_scenes(served_page: tuple[PlayServer, Page]) -> None:
    server, page = served_page
    # (a scene's first start on a fresh machine compiles its engine's kernels: minutes)
    page.page.select_option("#scene", "gas-2d")
    assert until(lambda: server.live.scene_name == "gas-2d", 600)
    page.wait_for('carom.state.shapeHeader.scene === "gas-2d"', 60)
    # the gas: its speed histogram against Maxwell-Boltzmann is shown
    page.wait_for('!document.getElementById("histogram").classList.contains("hidden")', 10)
    page.page.select_option("#scene", "pyramid-3d")
    assert until(lambda: server.live.scene_name == "pyramid-3d", 600)
    page.wait_for("carom.state.dim === 3 && carom.state.framesSeen > 5", 120)
    page.page.wait_for_timeout(500)
    share, colours = drawn(page.page.screenshot())
    assert share > 0.02
    assert colours > 8
    assert page.errors == []


def test_the_page_comes_back_when_the_server_does(browser: Any, small_pyramid: Path) -> None:
    server, thread = start(str(small_pyramid))
    page = Page(browser, server.url)
    port = server.port
    server.stop()
    thread.join(timeout=20)
    page.wait_for('document.getElementById("status").textContent.includes("connecting")', 10)
    seen = page.js("carom.state.framesSeen")
    again, thread = start(str(small_pyramid), port=port)
    try:
        page.wait_for(f"carom.state.framesSeen > {seen + 10}", 30)
        assert page.errors == [] or all("ERR_CONNECTION_REFUSED" in e for e in page.errors)
    finally:
        page.page.close()
        again.stop()
        thread.join(timeout=20)


def test_sliders_and_switches_reach_the_server(served_page: tuple[PlayServer, Page]) -> None:
    server, page = served_page
    live = server.live
    # paused, so that the pyramid cannot fall asleep (and its contacts leave the solver)
    # between the switch below and the frame the page is asked about, however slow the machine
    page.page.click("#pause")
    assert until(lambda: live.paused, 5)
    # a switch: the server sends the contact points from then on
    page.page.check('[data-draw="contacts"]')
    assert until(lambda: "contacts" in live.drawings, 10)
    # a slider applies when let go (its change event): gravity 2.5 m/s^2 downward; the engine
    # is built again then, every body awake (World.set_gravity)
    page.page.eval_on_selector(
        "#gravity",
        "(e) => { e.value = '2.5'; e.dispatchEvent(new Event('input')); "
        "e.dispatchEvent(new Event('change')); }",
    )
    assert until(lambda: live.world.gravity[1] == -2.5, 10)
    assert page.page.inner_text("#gravity-out") == "2.5"
    # one step: the pyramid rests on the ground, so it has contacts, and the page has them
    t = live.world.time
    page.page.click("#step")
    assert until(lambda: live.world.time > t, 10)
    page.wait_for(
        "carom.state.frame.contacts !== undefined && carom.state.frame.contacts.length > 0", 10
    )
    page.page.uncheck('[data-draw="contacts"]')
    assert until(lambda: "contacts" not in live.drawings, 10)
    assert page.errors == []
