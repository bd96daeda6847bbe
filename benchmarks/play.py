"""carom play under load: does the server keep real time and feed the page?

Starts ``carom play SCENE`` in its own process (as a user does), waits for the world to be
running, then reads its frames for ``--seconds`` as a page would, either from Python (a
websocket client in this process: what the server sends when the page takes everything at
once) or from Debian's chromium (``--browser``: the real page, drawing with WebGL on this
machine's CPU when it has no GPU, the server and the browser sharing the machine's cores).

Reports, over the window: frames a second received; simulated seconds a real second (1.000:
real time kept); the engine's step time (the server's running mean); real time the server
dropped in the window; the size of a frame; and with ``--browser`` the page's own drawing
rate (animation frames a second).

    .venv/bin/python benchmarks/play.py large-pyramid --seconds 20
    .venv/bin/python benchmarks/play.py large-pyramid --seconds 20 --browser
"""

from __future__ import annotations

import argparse
import asyncio
import json
import os
import platform
import shutil
import signal
import socket
import subprocess
import sys
import time
from typing import Any

from carom.play.server import ACK
from carom.play.wire import unpack


def free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def start(scene: str, port: int) -> subprocess.Popen[str]:
    proc = subprocess.Popen(
        [sys.executable, "-m", "carom", "play", scene, "--port", str(port), "--no-open"],
        stdout=subprocess.PIPE,
        text=True,
        env={**os.environ, "PYTHONUNBUFFERED": "1"},
    )
    assert proc.stdout is not None
    for line in proc.stdout:
        if "serving" in line:
            return proc
    raise SystemExit("carom play did not start")


async def read_frames(url: str, warm: float, seconds: float) -> dict[str, Any]:
    from websockets.asyncio.client import connect

    async with connect(url, max_size=None) as ws:
        end_warm = time.monotonic() + warm
        while time.monotonic() < end_warm:
            if isinstance(await ws.recv(), bytes):
                await ws.send(ACK)
        first = last = None
        count, size = 0, 0
        start = time.monotonic()
        while time.monotonic() - start < seconds:
            m = await ws.recv()
            if isinstance(m, bytes) and b'"frame"' in m[8:64]:
                await ws.send(ACK)  # as the page does once it has drawn a frame
                header, _ = unpack(m)
                first = first or header
                last = header
                count += 1
                size = len(m)
        wall = time.monotonic() - start
    assert first is not None
    assert last is not None
    return {
        "frames_per_s": count / wall,
        "sim_per_real": (last["time"] - first["time"]) / wall,
        "step_ms": last["step_ms"],
        "dropped_s": last["behind"] - first["behind"],
        "frame_bytes": size,
        "bodies": last["bodies"],
    }


def browser_frames(url: str, warm: float, seconds: float) -> dict[str, Any]:
    from playwright.sync_api import sync_playwright

    chromium = shutil.which("chromium")
    if chromium is None:
        raise SystemExit("no chromium: apt-get install chromium")
    flags = ["--no-sandbox", "--disable-background-networking", "--disable-component-update",
             "--disable-sync", "--no-first-run"]  # fmt: skip
    with sync_playwright() as p:
        browser = p.chromium.launch(executable_path=chromium, args=flags)
        page = browser.new_page(viewport={"width": 1280, "height": 720})
        page.goto(url)
        page.wait_for_timeout(1000 * warm)
        read = (
            "[carom.state.framesSeen, carom.state.header.time, carom.state.header.behind,"
            " carom.state.header.step_ms, carom.state.header.bodies]"
        )
        before = page.evaluate(read)
        draws = page.evaluate(
            """(ms) => new Promise(done => { let n = 0; const t0 = performance.now();
            function f() { n++; if (performance.now() - t0 < ms) requestAnimationFrame(f);
            else done(n / ((performance.now() - t0) / 1000)); } requestAnimationFrame(f); })""",
            1000 * seconds,
        )
        after = page.evaluate(read)
        browser.close()
    return {
        "frames_per_s": (after[0] - before[0]) / seconds,
        "sim_per_real": (after[1] - before[1]) / seconds,
        "step_ms": after[3],
        "dropped_s": after[2] - before[2],
        "page_draws_per_s": draws,
        "bodies": after[4],
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("scene", nargs="?", default="large-pyramid")
    parser.add_argument("--seconds", type=float, default=20.0)
    parser.add_argument("--warm", type=float, default=5.0, help="seconds before the window")
    parser.add_argument("--browser", action="store_true", help="the page in chromium reads")
    args = parser.parse_args()
    port = free_port()
    proc = start(args.scene, port)
    try:
        if args.browser:
            result = browser_frames(f"http://127.0.0.1:{port}/", args.warm, args.seconds)
        else:
            url = f"ws://127.0.0.1:{port}/ws"
            result = asyncio.run(read_frames(url, args.warm, args.seconds))
    finally:
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=60)
    result.update(
        scene=args.scene,
        reader="chromium" if args.browser else "python",
        seconds=args.seconds,
        machine=f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores",
        date=time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime()),
    )
    print(json.dumps(result, indent=1))


if __name__ == "__main__":
    main()
