"""carom play's server (carom.play.server): the page's files, the websocket, and what it
refuses. Clients here are Python's (websockets' own client); tests/play/test_browser.py
drives a real browser."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
import urllib.error
import urllib.request
from pathlib import Path

import numpy as np
import pytest
from websockets.exceptions import ConnectionClosed, InvalidStatus
from websockets.sync.client import connect

from carom.play.server import ACK, MOST_COMMANDS, PlayServer
from carom.play.wire import unpack
from tests.processes import from_a_terminal


def ws_url(server: PlayServer) -> str:
    return server.url.replace("http://", "ws://") + "ws"


def messages(ws, seconds: float):  # type: ignore[no-untyped-def]
    """What the server sent for ``seconds``: (headers of binary messages, replies)."""
    headers, replies = [], []
    end = time.monotonic() + seconds
    while time.monotonic() < end:
        try:
            m = ws.recv(timeout=max(end - time.monotonic(), 0.01))
        except TimeoutError:
            break
        if isinstance(m, bytes):
            headers.append(unpack(m)[0])
            if headers[-1]["type"] == "frame":
                ws.send(ACK)  # as the page does: the next frame may come
        else:
            replies.append(json.loads(m))
    return headers, replies


def test_the_page_is_served(served: PlayServer) -> None:
    with urllib.request.urlopen(served.url) as r:
        page = r.read().decode()
        assert r.headers["Content-Type"].startswith("text/html")
        assert "default-src 'self'" in r.headers["Content-Security-Policy"]
    assert '<script src="play.js">' in page
    with urllib.request.urlopen(served.url + "play.js") as r:
        assert b"CRM1" in r.read()
    with pytest.raises(urllib.error.HTTPError) as missing:
        urllib.request.urlopen(served.url + "../etc/passwd")
    assert missing.value.code == 404
    missing.value.close()


def test_shapes_then_frames_in_real_time(served: PlayServer) -> None:
    with connect(ws_url(served), max_size=None) as ws:
        headers, _ = messages(ws, 1.5)
    assert headers[0]["type"] == "shapes"
    assert headers[0]["dim"] == 2
    frames = [h for h in headers if h["type"] == "frame"]
    # a frame a tick (60 a second), at least 30 a second even on a busy machine
    assert len(frames) >= 30
    # real time: the world's clock moves as the wall clock does (less what was dropped)
    span = frames[-1]["time"] - frames[0]["time"]
    assert span > 0.5


def test_bad_commands_are_answered_and_harm_nothing(served: PlayServer) -> None:
    world = served.live.world
    n = world.n_bodies
    with connect(ws_url(served)) as ws:
        for text in [
            '{"op": "grab", "point": [NaN, 1]}',
            '{"op": "shoot", "point": [3, 9], "velocity": [1e12, 0]}',
            '{"op": "scene", "name": "../../etc/passwd"}',
            '{"op": "drag", "target": [1, 1]}',
            '{"op": "set", "name": "gravity", "value": -5}',
            "not json",
        ]:
            ws.send(text)
        ws.send(b"\x00\x01")
        _, replies = messages(ws, 1.0)
    whys = [r["why"] for r in replies if r["op"] == "refused"]
    assert len(whys) == 7, whys
    assert any("NaN" in w for w in whys)
    assert any("no scene" in w for w in whys)
    assert any("nothing is held" in w for w in whys)
    assert any("JSON text" in w for w in whys)
    assert world is served.live.world
    assert world.n_bodies == n
    assert np.all(np.isfinite(world.positions))
    assert world.gravity[1] == -10.0


def flood(ws) -> None:  # type: ignore[no-untyped-def]
    """Send far more than a page may, then read until the server ends the connection."""
    for _ in range(20000):
        ws.send('{"op": "play"}')
    messages(ws, 2.0)
    ws.recv(timeout=2.0)


def test_a_flood_is_cut_off_and_the_server_stays(served: PlayServer) -> None:
    with connect(ws_url(served)) as ws:
        for _ in range(3 * MOST_COMMANDS):
            ws.send('{"op": "pause"}')
        _, replies = messages(ws, 1.0)
        assert {"op": "refused", "why": f"too many commands: at most {MOST_COMMANDS} a second"} in (
            replies
        )
        # a page that never stops is disconnected
        with pytest.raises(ConnectionClosed):
            flood(ws)
    # the next page is served as before
    with connect(ws_url(served)) as ws:
        headers, _ = messages(ws, 1.0)
    assert any(h["type"] == "frame" for h in headers)


def test_a_page_that_goes_away_lets_go(served: PlayServer) -> None:
    live = served.live
    top = live.world.n_bodies - 1
    x = live.world.positions[top]
    with connect(ws_url(served)) as ws:
        ws.send(json.dumps({"op": "grab", "point": [float(x[0]), float(x[1])]}))
        _, replies = messages(ws, 0.5)
        assert {"op": "grabbed", "body": top} == {k: replies[0][k] for k in ("op", "body")}
        joints = live.world.joint_rows[0]
        assert joints.shape[0] == 1
        assert joints[0, 0] >= 0
        with connect(ws_url(served)) as other:  # another page comes and goes: the hold stays
            messages(other, 0.3)
        time.sleep(0.5)
        assert live.world.joint_rows[0][0, 0] >= 0
    time.sleep(0.5)  # (the physics thread takes the release at its next tick)
    assert live.world.joint_rows[0][0, 0] < 0  # removed


def test_pages_from_other_sites_are_refused(served: PlayServer) -> None:
    with pytest.raises(InvalidStatus) as refused:
        connect(ws_url(served), origin="http://evil.example")  # type: ignore[arg-type]
    assert refused.value.response.status_code == 403
    with connect(ws_url(served), origin=served.url.rstrip("/")) as ws:  # type: ignore[arg-type]
        assert messages(ws, 0.3)[0]


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _other_address() -> str | None:
    """An address of this machine other than the loopback's, if it has one (a UDP socket
    "connected" to a documentation address sends nothing)."""
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        try:
            s.connect(("203.0.113.1", 9))
        except OSError:
            return None
        address = str(s.getsockname()[0])
    return None if address.startswith("127.") or address == "0.0.0.0" else address


def _carom(*args: str) -> subprocess.Popen[str]:
    env = {**os.environ, "PYTHONUNBUFFERED": "1"}
    return subprocess.Popen(
        from_a_terminal([sys.executable, "-m", "carom", *args]),
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
    )


@pytest.mark.slow
def test_the_command_serves_and_ctrl_c_stops_it(small_pyramid: Path) -> None:
    port = _free_port()
    proc = _carom("play", str(small_pyramid), "--port", str(port), "--no-open")
    try:
        assert proc.stdout is not None
        line = ""
        deadline = time.monotonic() + 600  # (a fresh machine compiles the kernels first)
        while "serving" not in line and time.monotonic() < deadline:
            line = proc.stdout.readline()
        assert f"http://127.0.0.1:{port}/" in line
        with urllib.request.urlopen(f"http://127.0.0.1:{port}/") as r:
            assert r.status == 200
        # bound to the loopback address only: another address of this machine is not served
        other = _other_address()
        if other is not None:
            with pytest.raises(ConnectionRefusedError), socket.create_connection((other, port), 5):
                pass
        proc.send_signal(signal.SIGINT)
        out, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:  # (never left running: the test failed above)
            proc.kill()
            proc.communicate()
    assert proc.returncode == 0, err
    assert "stopped" in out
    assert "Traceback" not in err


@pytest.mark.slow
@pytest.mark.parametrize(
    ("args", "says"),
    [
        (["no-such-scene"], "no-such-scene"),
        (["pyramid", "--port", "70000"], "--port must be"),
        (["pyramid", "--host", "203.0.113.9"], "cannot listen on 203.0.113.9"),
    ],
)
def test_the_command_refuses_bad_input(args: list[str], says: str) -> None:
    proc = _carom("play", *args, "--no-open")
    out, err = proc.communicate(timeout=600)
    assert proc.returncode == 2, (out, err)
    assert says in err
    assert "Traceback" not in err
    assert len(err.strip().splitlines()) == 1


@pytest.mark.slow
def test_a_port_in_use_is_refused(small_pyramid: Path) -> None:
    with socket.socket() as taken:
        taken.bind(("127.0.0.1", 0))
        taken.listen()
        port = taken.getsockname()[1]
        proc = _carom("play", str(small_pyramid), "--port", str(port), "--no-open")
        out, err = proc.communicate(timeout=600)
    assert proc.returncode == 2, (out, err)
    assert f"cannot listen on 127.0.0.1:{port}" in err
    assert "Traceback" not in err
