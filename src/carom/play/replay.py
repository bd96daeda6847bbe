"""A replay page that opens from the file system: ``replay.html`` beside a run's films.

:func:`write_replay` reads the H5MD trajectory ``carom run`` wrote and writes one HTML file
holding the testbed's own page (its drawing, camera and panel; :mod:`carom.play`) and the
run's frames in the same binary messages a live server sends (:mod:`carom.play.wire`),
base64 in the page. No server, no network: the browser opens the file and the page plays
it, with a timeline to scrub, the 3D view to orbit, and a body to pick for its speed and
energy. A long run is thinned to at most :data:`MOST_BYTES` of frames (every k-th frame,
the last kept; the page says how many were kept).
"""

from __future__ import annotations

import base64
import json
import math
from pathlib import Path
from typing import Any

import numpy as np

from carom.errors import CaromError
from carom.play.drawn import shape_arrays
from carom.play.server import page_file
from carom.play.wire import pack

__all__ = ["MOST_BYTES", "REPLAY", "write_replay"]

REPLAY = "replay.html"
#: the most frame data a replay page holds (before base64) [bytes]
MOST_BYTES = 24 * 2**20


def write_replay(folder: Path, out: Path | None = None, title: str | None = None) -> Path:
    """Write ``folder/replay.html`` (or ``out``) from ``folder/trajectory.h5``; return it.

    Raises
    ------
    CaromError
        No trajectory there, or one that cannot be read.
    """
    from carom.io.h5md import need_h5py
    from carom.viz.animate import TrajectoryScene

    h5py = need_h5py()
    source = Path(folder) / "trajectory.h5"
    if not source.is_file():
        raise CaromError(f"{source} does not exist: a replay is made from a carom run's trajectory")
    target = Path(folder) / REPLAY if out is None else Path(out)
    with h5py.File(source, "r") as f:
        scene = TrajectoryScene.read(f)
        shapes, frames, kept, total = _messages(f, scene, title or source.parent.name)
    data = {"shapes": _text(shapes), "frames": [_text(m) for m in frames]}
    page = _page(data, f"{title or source.parent.name}: carom replay", kept, total)
    partial = target.with_name(target.name + ".partial")
    partial.write_text(page, encoding="utf-8")
    partial.replace(target)  # (never a half-written page where the last one was)
    return target


def _messages(f: Any, scene: Any, title: str) -> tuple[bytes, list[bytes], int, int]:
    pieces = _pieces(f, len(scene.radius))
    still = ~np.isfinite(np.asarray(f["particles/all/mass"][:], float))
    mass = np.asarray(f["particles/all/mass"][:], float)
    lo, hi = np.zeros(scene.dim), np.asarray(scene.box, float)
    speeds_seen = 0.0
    header = {
        "type": "shapes",
        "version": 1,
        "dim": scene.dim,
        "scene": title,
        "title": title,
        "description": "a replay of carom run: scrub the timeline, pick a body",
        "catalog": [title],
        "engine": "replay",
        "box": [lo.tolist(), hi.tolist()],
        "boundary": "periodic" if scene.periodic else "walls",
        "down": [0.0] * scene.dim,
        "size": float(2.0 * np.median(scene.radius)) if len(scene.radius) else 1.0,
        "top_speed": 0.0,
        "settings": {},
        "dt": None,
    }
    shapes = pack(header, shape_arrays(scene.dim, pieces, scene.radius, mass, still))
    times = np.asarray(f["particles/all/position/time"][:], float)
    positions = f["particles/all/position/value"]
    velocities = f["particles/all/velocity/value"]
    turns = f["particles/all/orientation/value"]
    observed = f["observables"]
    energy = {
        name: np.asarray(observed[f"{name}/value"][:], float)
        for name in ("kinetic_energy", "potential_energy", "dissipated_energy")
    }
    given = _series(observed, "given_energy", len(times))
    work = _series(observed, "work_done", len(times))
    total = len(times)
    n = len(scene.radius)
    per_frame = n * (4 * scene.dim + 4 * (4 if scene.dim == 3 else 1) + 4 + 1) + 512
    every = max(1, math.ceil(total * per_frame / MOST_BYTES))
    chosen = list(range(0, total, every))
    if chosen[-1] != total - 1:
        chosen.append(total - 1)
    start = float(energy["kinetic_energy"][0] + energy["potential_energy"][0]) if total else 0.0
    frames = []
    for k in chosen:
        v = np.asarray(velocities[k], float)
        speed = np.sqrt(np.sum(v * v, axis=1))
        speeds_seen = max(speeds_seen, float(speed.max(initial=0.0)))
        head = {
            "type": "frame",
            "version": 1,
            "time": float(times[k]),
            "steps": int(k),
            "paused": False,
            "slow": 1.0,
            "step_ms": None,
            "stages": {},
            "behind": 0.0,
            "bodies": n,
            "contacts": 0,
            "awake": n,
            "islands": 0,
            "energy": {
                "kinetic": float(energy["kinetic_energy"][k]),
                "potential": float(energy["potential_energy"][k]),
                "lost": float(energy["dissipated_energy"][k]),
                "given": float(given[k]),
                "work": float(work[k]),
                "start": start,
            },
            "held": -1,
        }
        frames.append(
            pack(
                head,
                {
                    "x": np.asarray(positions[k], np.float32),
                    "turn": np.asarray(turns[k], np.float32),
                    "speed": speed.astype(np.float32),
                    "state": np.full(n, 3, np.uint8),
                },
            )
        )
    return shapes, frames, len(chosen), total


def _series(observed: Any, name: str, count: int) -> Any:
    return np.asarray(observed[f"{name}/value"][:], float) if name in observed else np.zeros(count)


def _pieces(f: Any, n: int) -> list[Any]:
    from carom.bodies import PIECE_ARRAYS, pieces_from_arrays

    stored = f["particles/all"].get("pieces")
    if stored is None:
        return [() for _ in range(n)]
    return pieces_from_arrays({k: stored[k][:] for k in PIECE_ARRAYS if k in stored}, n)


def _text(message: bytes) -> str:
    return base64.b64encode(message).decode("ascii")


def _page(data: dict[str, Any], title: str, kept: int, total: int) -> str:
    """The testbed's page with its style, script and the replay's data inline."""
    html = page_file("index.html").decode()
    css = page_file("play.css").decode()
    js = page_file("play.js").decode()
    note = "" if kept == total else f" ({kept} of its {total} frames, evenly)"
    payload = json.dumps({**data, "note": note}, separators=(",", ":")).replace("</", "<\\/")
    html = html.replace(
        '<link rel="stylesheet" href="play.css">', "<style>\n" + css + "</style>"
    ).replace('<link rel="icon" href="favicon.svg" type="image/svg+xml">', "")
    html = html.replace("<title>carom play</title>", f"<title>{_escape(title)}</title>")
    script = (
        f"<script>window.CAROM_REPLAY = {payload};</script>\n"
        + "<script>\n"
        + js.replace("</script", "<\\/script")
        + "</script>"
    )
    return html.replace('<script src="play.js"></script>', script)


def _escape(text: str) -> str:
    return text.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
