"""``carom play``'s server: the page and its websocket on one port, the world on its own
thread.

One port serves the page's files (``GET /``, ``/play.js``, ``/play.css``) and the websocket
(``/ws``), through the ``websockets`` package (the ``play`` extra). The world lives on the
physics thread (:class:`PlayServer` runs it): it takes the commands the pages sent, advances
the world in real time (:meth:`carom.play.live.Live.advance`), and packs a frame every tick;
the event loop sends each page the newest frame when the page has taken the last one, so a
slow page skips frames and never holds the world back.

Safe by default: bound to the loopback address unless told otherwise; a websocket whose page
came from another site is refused (its ``Origin`` must be this server's); every command is
checked (:func:`carom.play.wire.read_command`) and one that fails is answered with why and
changes nothing; a page sending more than :data:`MOST_COMMANDS` commands a second has the
rest refused, and one that keeps flooding is disconnected; a page that goes away lets go of
what it held and leaves the server to the next one.
"""

from __future__ import annotations

import asyncio
import contextlib
import http
import json
import queue
import signal
import sys
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from importlib import resources
from typing import Any

from carom.errors import CaromError
from carom.play.live import Live
from carom.play.wire import Refused, read_command

__all__ = ["MOST_COMMANDS", "PlayServer", "need_websockets"]

#: commands a page may send a second (a drag sends one a frame); beyond, they are refused
MOST_COMMANDS = 240
#: refused commands (less :data:`MOST_COMMANDS` a second) after which a page is
#: disconnected: it keeps sending many times faster than it may
MOST_REFUSED = 2000
#: frames sent to a page and not yet acknowledged, at most: a page that draws slowly gets
#: fewer, newer frames (nothing queues up in the socket's buffers behind its back)
IN_FLIGHT = 4
#: the page's acknowledgement of a frame, as it sends it
ACK = '{"op":"ack"}'
#: what the physics thread is told when a page goes away, in place of a command's text (no
#: text a page can send)
GONE = None
#: pages connected at once
MOST_PAGES = 16
#: the page's files and their types
FILES = {
    "/": ("index.html", "text/html; charset=utf-8"),
    "/index.html": ("index.html", "text/html; charset=utf-8"),
    "/play.js": ("play.js", "text/javascript; charset=utf-8"),
    "/play.css": ("play.css", "text/css; charset=utf-8"),
    "/favicon.svg": ("favicon.svg", "image/svg+xml"),
}


def need_websockets() -> Any:
    """The ``websockets`` package (its asyncio server and HTTP responses loaded), or a
    CaromError saying how to install it."""
    try:
        import websockets
        import websockets.asyncio.server
        import websockets.datastructures
        import websockets.http11
    except ImportError:
        raise CaromError(
            "carom play needs the websockets package: install the play extra, "
            "pip install 'carom[play]'"
        ) from None
    return websockets


def page_file(name: str) -> bytes:
    """A file of the page, from the package."""
    return (resources.files("carom.play") / "page" / name).read_bytes()


@dataclass(eq=False)
class _Page:
    """A connected page: its socket, what it is owed, and its budget of commands."""

    socket: Any
    wake: asyncio.Event = field(default_factory=asyncio.Event)
    replies: list[str] = field(default_factory=list)
    shapes_sent: int = -1
    tokens: float = float(MOST_COMMANDS)
    refill: float = field(default_factory=time.monotonic)
    flooding: float = 0.0  # refused commands, less MOST_COMMANDS a second since
    in_flight: int = 0  # frames sent that the page has not acknowledged yet
    frame_sent: int = -1  # the number of the last frame sent
    frames: int = 0


class PlayServer:
    """Serve ``live`` to pages at ``http://host:port/`` (module docstring).

    Parameters
    ----------
    live : Live
        The scene running.
    host : str
        The address to bind (``127.0.0.1``: this machine only).
    port : int
        0 picks a free port (:attr:`port` says which once :meth:`serve` has started).
    tick : float
        The physics thread's tick [s]: it advances the world and packs a frame this often.
    """

    def __init__(self, live: Live, host: str = "127.0.0.1", port: int = 8765, tick: float = 1 / 60):
        self.live, self.host, self.port, self.tick = live, host, port, tick
        self._pages: set[_Page] = set()
        self._commands: queue.Queue[tuple[_Page, str | None]] = queue.Queue()
        self._stop = threading.Event()
        self._loop: asyncio.AbstractEventLoop | None = None
        self._frame = b""
        self._frame_no = 0
        self._holder: _Page | None = None  # the page holding a body
        self._shapes = b""
        self._version = -1
        self._lock = threading.Lock()
        self.ticks = 0  # the physics thread's ticks
        self.frames_sent = 0
        self.errors: list[str] = []  # what went wrong on the physics thread (also printed)

    # -- the physics thread ---------------------------------------------------------------

    def _physics(self) -> None:
        live, loop = self.live, self._loop
        assert loop is not None
        next_tick = time.perf_counter()
        while not self._stop.is_set():
            self._obey_all()
            live.advance()
            # a frame is packed when a page can take one (none in flight beyond the limit)
            wanted = not self._frame or any(p.in_flight < IN_FLIGHT for p in list(self._pages))
            with self._lock:
                if live.version != self._version:
                    self._shapes, self._version = live.shapes(), live.version
                if wanted:
                    self._frame, self._frame_no = live.frame(), self._frame_no + 1
            self.ticks += 1
            loop.call_soon_threadsafe(self._wake_all)
            next_tick += self.tick
            pause = next_tick - time.perf_counter()
            if pause > 0.0:
                self._stop.wait(pause)
            else:
                next_tick = time.perf_counter()  # behind: do not try to catch up ticks

    def _obey_all(self) -> None:
        while True:
            try:
                page, text = self._commands.get_nowait()
            except queue.Empty:
                return
            if text is GONE:  # a page went away: what it held is let go
                if self._holder is page:
                    self.live.release()
                    self._holder = None
                continue
            reply = self._obey(page, text)
            if reply is not None:
                self._reply(page, reply)

    def _obey(self, page: _Page, text: str) -> dict[str, Any] | None:
        live = self.live
        try:
            command = read_command(text, live.dim, live.reach, live.top_speed)
            reply = live.obey(command)
        except (Refused, CaromError) as why:  # refused by the checks or the world: as it was
            return {"op": "refused", "why": str(why)}
        except Exception as error:  # (a fault of carom's: said, and the server stays)
            print(f"carom play: {text[:200]!r} failed: {error!r}", file=sys.stderr)
            return {"op": "refused", "why": f"carom failed on it ({type(error).__name__})"}
        if command.op == "grab" and reply is not None and reply.get("body", -1) >= 0:
            self._holder = page
        elif command.op in ("release", "scene", "reset"):
            self._holder = None
        return reply

    def _reply(self, page: _Page, reply: dict[str, Any]) -> None:
        loop = self._loop
        assert loop is not None
        text = json.dumps(reply)
        loop.call_soon_threadsafe(self._owe, page, text)

    def _owe(self, page: _Page, text: str) -> None:
        page.replies.append(text)
        page.wake.set()

    def _wake_all(self) -> None:
        for page in self._pages:
            page.wake.set()

    # -- the event loop -------------------------------------------------------------------

    async def _http(self, connection: Any, request: Any) -> Any:
        """Serve the page's files; let ``/ws`` through to the websocket."""
        path = request.path.split("?", 1)[0]
        if path == "/ws":
            origin = request.headers.get("Origin")
            if origin is not None and origin not in self._origins():
                return connection.respond(
                    http.HTTPStatus.FORBIDDEN, f"pages from {origin} may not connect\n"
                )
            return None
        websockets = need_websockets()
        if path not in FILES:
            return connection.respond(http.HTTPStatus.NOT_FOUND, f"no {path} here; try /\n")
        name, kind = FILES[path]
        body = page_file(name)
        headers = websockets.datastructures.Headers(
            [
                ("Content-Type", kind),
                ("Content-Length", str(len(body))),
                ("Cache-Control", "no-store"),
                ("X-Content-Type-Options", "nosniff"),
                ("Content-Security-Policy", "default-src 'self'; connect-src 'self' ws: wss:"),
            ]
        )
        return websockets.http11.Response(200, "OK", headers, body)

    async def _page(self, socket: Any) -> None:
        if len(self._pages) >= MOST_PAGES:
            await socket.close(1013, f"at most {MOST_PAGES} pages at once")
            return
        page = _Page(socket)
        self._pages.add(page)
        sender = asyncio.create_task(self._send(page))
        try:
            async for message in socket:
                self._take(page, message)
                if page.flooding > MOST_REFUSED:
                    await socket.close(1008, "too many commands: at most 240 a second")
                    break
        except Exception:
            pass
        finally:
            sender.cancel()
            self._pages.discard(page)
            # what the page held, let go (the next page finds the world free)
            self._commands.put((page, GONE))

    def _take(self, page: _Page, message: Any) -> None:
        now = time.monotonic()
        gained = (now - page.refill) * MOST_COMMANDS
        page.tokens = min(float(MOST_COMMANDS), page.tokens + gained)
        page.flooding = max(0.0, page.flooding - gained)
        page.refill = now
        if page.tokens < 1.0:
            if page.flooding == 0.0:  # the first refused of a burst is said
                self._owe(page, json.dumps({
                    "op": "refused",
                    "why": f"too many commands: at most {MOST_COMMANDS} a second",
                }))  # fmt: skip
            page.flooding += 1.0
            return
        page.tokens -= 1.0
        if message == ACK:  # the page has drawn a frame: the newest may go
            page.in_flight = max(page.in_flight - 1, 0)
            page.wake.set()
            return
        if not isinstance(message, str):
            self._owe(page, json.dumps({"op": "refused", "why": "commands are JSON text"}))
            return
        self._commands.put((page, message))

    async def _send(self, page: _Page) -> None:
        socket = page.socket
        while True:
            await page.wake.wait()
            page.wake.clear()
            while page.replies:
                await socket.send(page.replies.pop(0))
            with self._lock:
                shapes, version = self._shapes, self._version
                frame, number = self._frame, self._frame_no
            if version != page.shapes_sent and shapes:
                await socket.send(shapes)
                page.shapes_sent = version
            if frame and number > page.frame_sent and page.in_flight < IN_FLIGHT:
                page.in_flight += 1
                page.frame_sent = number
                await socket.send(frame)
                page.frames += 1
                self.frames_sent += 1

    async def serve(self, ready: Callable[[str], None] | None = None) -> None:
        """Serve until :meth:`stop` (or the task is cancelled); call ``ready(url)`` once
        listening."""
        websockets = need_websockets()
        self._loop = asyncio.get_running_loop()
        self._stop.clear()
        physics = threading.Thread(target=self._guarded_physics, name="carom-physics", daemon=True)
        async with websockets.asyncio.server.serve(
            self._page,
            self.host,
            self.port,
            process_request=self._http,
            max_size=8192,
            max_queue=64,
            compression=None,
        ) as server:
            sockets = list(server.sockets)
            self.port = int(sockets[0].getsockname()[1])
            physics.start()
            if ready is not None:
                ready(self.url)
            try:
                await asyncio.get_running_loop().run_in_executor(None, self._stop.wait)
            finally:
                self._stop.set()
                physics.join(timeout=10.0)

    def _origins(self) -> set[str]:
        """The origins a page of this server has (the address it was opened at)."""
        hosts = {self.host, "127.0.0.1", "localhost", "[::1]"}
        hosts = {f"[{h}]" if ":" in h and not h.startswith("[") else h for h in hosts}
        return {f"http://{h}:{self.port}" for h in hosts}

    def _guarded_physics(self) -> None:
        try:
            self._physics()
        except Exception as error:
            self.errors.append(f"{type(error).__name__}: {error}")
            self._stop.set()

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}/"

    def stop(self) -> None:
        """Stop serving (from any thread)."""
        self._stop.set()


def run(server: PlayServer, ready: Callable[[str], None] | None = None) -> None:
    """Serve until Ctrl-C or SIGTERM; return then, the physics thread stopped."""

    async def main() -> None:
        loop = asyncio.get_running_loop()
        with contextlib.suppress(NotImplementedError):
            loop.add_signal_handler(signal.SIGTERM, server.stop)
        await server.serve(ready)

    with contextlib.suppress(KeyboardInterrupt):
        asyncio.run(main())
    server.stop()
