"""A carom play server on a free port, in this process (its world readable by the tests)."""

from __future__ import annotations

import asyncio
import threading
from collections.abc import Iterator
from pathlib import Path

import pytest

from carom.play.live import Live
from carom.play.server import PlayServer
from tests.play.scenes import SMALL_PYRAMID


def start(scene: str, port: int = 0) -> tuple[PlayServer, threading.Thread]:
    """A server for ``scene`` serving on its own thread; ready when this returns."""
    server = PlayServer(Live(scene), port=port)
    ready = threading.Event()
    thread = threading.Thread(
        target=lambda: asyncio.run(server.serve(lambda url: ready.set())), daemon=True
    )
    thread.start()
    assert ready.wait(120), "the server did not start"
    return server, thread


@pytest.fixture
def small_pyramid(tmp_path: Path) -> Path:
    path = tmp_path / "small-pyramid.toml"
    path.write_text(SMALL_PYRAMID)
    return path


@pytest.fixture
def served(small_pyramid: Path) -> Iterator[PlayServer]:
    server, thread = start(str(small_pyramid))
    yield server
    server.stop()
    thread.join(timeout=20)
    assert not thread.is_alive()
    assert server.errors == []
