"""What travels between ``carom play``'s server and its page.

Server to page: binary messages, one format for the scene's shapes and for every frame
(:func:`pack`): the bytes ``CRM1``, the length of a JSON header (little-endian uint32), the
header, then each array's raw little-endian bytes, each starting at a multiple of 8 so that
the page reads it as a typed array without copying. The header names every array with its
dtype, shape and offset; numbers that are not arrays (the clock, the stats) travel in it.

Page to server: small JSON texts, one command each, which :func:`read_command` checks before
anything touches the world: a known ``op``, the fields that op takes and no others, finite
numbers of the world's dimension, speeds and distances within bounds. A message that fails is
refused with a :class:`Refused` that says what was wrong; the world is not touched.
"""

from __future__ import annotations

import json
import math
import struct
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "COMMANDS",
    "MAGIC",
    "MAX_MESSAGE",
    "Command",
    "Refused",
    "pack",
    "read_command",
    "unpack",
]

MAGIC = b"CRM1"
#: the longest command a page may send [bytes]
MAX_MESSAGE = 4096
#: dtypes a packed array may have (the page's typed arrays)
_TYPES = {"float32", "float64", "int32", "uint8", "uint32"}
#: the settings the page's sliders change, and their ranges (unit, low, high)
SETTINGS: dict[str, tuple[str, float, float]] = {
    "gravity": ("m/s^2", 0.0, 100.0),
    "restitution": ("-", 0.0, 1.0),
    "friction": ("-", 0.0, 2.0),
    "substeps": ("-", 1.0, 64.0),
}
#: debug drawings the page may ask for
DRAWINGS = ("contacts", "normals", "impulses", "joints", "sleeping", "boxes")
#: slow-motion factors the page may choose (simulated seconds per real second)
SLOW = (1.0, 0.5, 0.25, 0.1)


class Refused(ValueError):  # noqa: N818 (a refusal, not an error of the server)
    """A command refused: ``str(refusal)`` says what was wrong and how to send it."""


@dataclass(frozen=True)
class Command:
    """A checked command: its ``op`` and fields (vectors as float64 arrays)."""

    op: str
    fields: Mapping[str, Any]


def _vector(op: str, key: str, value: Any, dim: int, bound: float) -> NDArray[np.float64]:
    if (
        not isinstance(value, list)
        or len(value) != dim
        or not all(isinstance(v, int | float) and not isinstance(v, bool) for v in value)
    ):
        raise Refused(f"{op}: {key} must be a list of {dim} numbers; got {_show(value)}")
    out = np.array(value, dtype=float)
    if not np.all(np.isfinite(out)):
        raise Refused(f"{op}: {key} must be finite; got {_show(value)}")
    if float(np.max(np.abs(out))) > bound:
        raise Refused(f"{op}: {key} must be within {bound:g} of the origin; got {_show(value)}")
    return out


def _number(op: str, key: str, value: Any, low: float, high: float) -> float:
    if not isinstance(value, int | float) or isinstance(value, bool):
        raise Refused(f"{op}: {key} must be a number; got {_show(value)}")
    x = float(value)
    if not math.isfinite(x) or not low <= x <= high:
        raise Refused(f"{op}: {key} must be between {low:g} and {high:g}; got {_show(value)}")
    return x


def _show(value: Any) -> str:
    text = json.dumps(value) if _jsonable(value) else repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


def _jsonable(value: Any) -> bool:
    try:
        json.dumps(value, allow_nan=False)
    except (TypeError, ValueError):
        return False
    return True


#: each command's fields: name -> kind ("point": a position, "velocity", "name", a setting...)
COMMANDS: dict[str, tuple[str, ...]] = {
    "pause": (),
    "play": (),
    "step": (),
    "reset": (),
    "slow": ("factor",),
    "scene": ("name",),
    "grab": ("point", "direction"),  # 2D: point; 3D: a ray from point along direction
    "drag": ("target",),
    "release": (),
    "shoot": ("point", "velocity"),
    "set": ("name", "value"),
    "draw": ("name", "on"),
}


def read_command(text: str | bytes, dim: int, reach: float, top_speed: float) -> Command:
    """Check one message from the page and return it as a :class:`Command`.

    Parameters
    ----------
    text : str or bytes
        The message (JSON text; bytes are refused: the page sends text).
    dim : int
        The world's dimension (2 or 3): the length of every vector.
    reach : float
        How far from the origin a point may be [m] (the server passes a multiple of the
        scene's size).
    top_speed : float
        The fastest ball a page may shoot [m/s].

    Raises
    ------
    Refused
        What is wrong with it, and how to send it.
    """
    if not isinstance(text, str):
        raise Refused("commands are JSON text, not binary messages")
    if len(text) > MAX_MESSAGE:
        raise Refused(f"a command is at most {MAX_MESSAGE} bytes; got {len(text)}")
    try:
        message = json.loads(text, parse_constant=_no_constant)
    except ValueError as error:
        raise Refused(f"not JSON: {error}") from None
    if not isinstance(message, dict) or not isinstance(message.get("op"), str):
        raise Refused('a command is a JSON object with an "op"; e.g. {"op": "pause"}')
    op = message["op"]
    if op not in COMMANDS:
        raise Refused(f"unknown op {_show(op)}; the ops are {', '.join(COMMANDS)}")
    allowed = set(COMMANDS[op]) | {"op"}
    if op == "grab" and dim == 2:
        allowed.discard("direction")
    extra = sorted(set(message) - allowed)
    if extra:
        raise Refused(f"{op} takes {sorted(allowed - {'op'}) or 'no fields'}; not {extra}")
    missing = sorted(allowed - set(message))
    if missing:
        raise Refused(f"{op} needs {missing}")
    fields: dict[str, Any] = {}
    for key in allowed - {"op"}:
        fields[key] = _field(op, key, message[key], dim, reach, top_speed)
    if op == "grab" and dim == 3:
        length = float(np.linalg.norm(fields["direction"]))
        if length == 0.0:
            raise Refused("grab: direction must not be zero")
        fields["direction"] = fields["direction"] / length
    return Command(op, fields)


def _no_constant(name: str) -> Any:
    raise ValueError(f"{name} is not a number here")


def _field(op: str, key: str, value: Any, dim: int, reach: float, top_speed: float) -> Any:
    if key in ("point", "target"):
        return _vector(op, key, value, dim, reach)
    if key == "direction":
        return _vector(op, key, value, dim, 1e6)
    if key == "velocity":
        v = _vector(op, key, value, dim, math.inf)
        speed = float(np.linalg.norm(v))
        if speed > top_speed:
            raise Refused(f"{op}: the speed is at most {top_speed:g} m/s; got {speed:.4g}")
        return v
    if key == "factor":
        factor = _number(op, key, value, 0.0, 1.0)
        if factor not in SLOW:
            raise Refused(f"slow: factor must be one of {list(SLOW)}; got {_show(value)}")
        return factor
    if key == "name" and op == "scene":
        if not isinstance(value, str) or not 0 < len(value) <= 200:
            raise Refused(f"scene: name must be a scene's name; got {_show(value)}")
        return value
    if key == "name" and op == "set":
        if value not in SETTINGS:
            raise Refused(f"set: name must be one of {list(SETTINGS)}; got {_show(value)}")
        return value
    if key == "name":  # draw
        if value not in DRAWINGS:
            raise Refused(f"draw: name must be one of {list(DRAWINGS)}; got {_show(value)}")
        return value
    if key == "on":
        if not isinstance(value, bool):
            raise Refused(f"draw: on must be true or false; got {_show(value)}")
        return value
    # set's value: checked against its setting's range once the name is known
    if not isinstance(value, int | float) or isinstance(value, bool):
        raise Refused(f"set: value must be a number; got {_show(value)}")
    return float(value)


def check_setting(name: str, value: float) -> float:
    """``value`` for the setting ``name`` (:data:`SETTINGS`), or a :class:`Refused`."""
    _, low, high = SETTINGS[name]
    number = _number("set", name, value, low, high)
    if name == "substeps" and number != int(number):
        raise Refused(f"set: substeps must be a whole number; got {value!r}")
    return number


def pack(header: Mapping[str, Any], arrays: Mapping[str, NDArray[Any]]) -> bytes:
    """One binary message: ``header`` (JSON-able) and ``arrays`` (module docstring).

    Parameters
    ----------
    header : mapping
        Plain values (no NaN); the key ``"arrays"`` is this function's.
    arrays : mapping of str to ndarray
        Each of a dtype in ``float32, float64, int32, uint8, uint32``.
    """
    table: list[list[Any]] = []
    blobs: list[bytes] = []
    offset = 0
    for name, array in arrays.items():
        a = np.ascontiguousarray(array)
        if a.dtype.name not in _TYPES:
            raise TypeError(f"pack: {name} has dtype {a.dtype}; one of {sorted(_TYPES)}")
        data = a.astype(a.dtype.newbyteorder("<"), copy=False).tobytes()
        table.append([name, a.dtype.name, list(a.shape), offset])
        blobs.append(data + b"\0" * (-len(data) % 8))
        offset += len(blobs[-1])
    text = json.dumps({**header, "arrays": table}, allow_nan=False, separators=(",", ":"))
    head = text.encode()
    head += b" " * (-(len(head) + 8) % 8)
    return b"".join([MAGIC, struct.pack("<I", len(head)), head, *blobs])


def unpack(message: bytes) -> tuple[dict[str, Any], dict[str, NDArray[Any]]]:
    """The header and arrays of a message :func:`pack` made (the page's reader, in Python:
    for tests and tools)."""
    if message[:4] != MAGIC:
        raise ValueError("not a carom play message")
    (size,) = struct.unpack("<I", message[4:8])
    header = json.loads(message[8 : 8 + size])
    start = 8 + size
    arrays: dict[str, NDArray[Any]] = {}
    for name, dtype, shape, offset in header.pop("arrays"):
        kind = np.dtype(dtype).newbyteorder("<")
        count = int(np.prod(shape, dtype=np.int64))
        arrays[name] = np.frombuffer(message, kind, count, start + offset).reshape(shape)
    return header, arrays


def vectors(values: Sequence[float]) -> list[float]:
    """Plain floats for a JSON header."""
    return [float(v) for v in values]
