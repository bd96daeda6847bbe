"""The scene schema: every table and key, its check, whether it is required and its default;
and how a scene's errors are worded (file, line, table, key, what is wrong, the fix)."""

from __future__ import annotations

import dataclasses
import difflib
import math
import re
from collections.abc import Callable, Iterable
from typing import Any

from carom._text import printable
from carom.engines import registry
from carom.errors import CaromError
from carom.laws.kinds import BODY_KINDS
from carom.limits import LARGEST, MAX_BODIES, SMALLEST
from carom.materials import COMBINE_RULES
from carom.shape_base import SHAPES as SHAPE_TABLE

__all__ = [
    "ARRAYS",
    "GENERATORS",
    "RENAMED",
    "SCHEMA",
    "Locator",
    "SceneError",
    "all_tables",
    "settings_tables",
]


class SceneError(CaromError):
    """A scene that cannot be used, with the file, key and line it concerns."""


# -- the schema: key -> (check, required, default) per table ----------------------------------

Check = Callable[[Any], str | None]  # returns what is wrong, or None


def _number(value: Any) -> str | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return f"must be a number, got {_show(value)}"
    if not math.isfinite(value):
        return f"must be finite, got {value!r}"
    if abs(value) > LARGEST:
        return f"must be at most {LARGEST:g} in magnitude (docs/scenes.md, Limits), got {value!r}"
    return None


def _positive(value: Any) -> str | None:
    problem = _number(value) or (None if value > 0 else f"must be > 0, got {value!r}")
    if problem is None and value < SMALLEST:
        return f"must be at least {SMALLEST:g} (docs/scenes.md, Limits), got {value!r}"
    return problem


def _integer(value: Any) -> str | None:
    if isinstance(value, bool) or not isinstance(value, int):
        return f"must be an integer, got {_show(value)}"
    return None


def _seed(value: Any) -> str | None:
    if _integer(value) or not 0 <= value < 2**64:
        return f"must be a whole number from 0 to 2^64 - 1, got {_show(value)}"
    return None


def _dimension(value: Any) -> str | None:
    return _integer(value) or (None if value in (2, 3) else f"must be 2 or 3, got {value!r}")


def _choice(*options: str) -> Check:
    def check(value: Any) -> str | None:
        if value in options:
            return None
        return f"must be one of {', '.join(repr(o) for o in options)}, got {_show(value)}"

    return check


def _engine(value: Any) -> str | None:
    """An engine of the table (:mod:`carom.engines.registry`), by name or older spelling."""
    if isinstance(value, str) and registry.known(value):
        return None
    names = [*registry.engine_choices()] + [a for e in registry.engines() for a in e.aliases]
    return f"must be one of {', '.join(repr(o) for o in names)}, got {_show(value)}"


def _by_settings(value: Any) -> str | None:
    """An engine setting: checked once, where its settings are made (the settings dataclass's
    ``__post_init__``, :meth:`carom.scene.load.Scene.from_dict`), not here."""
    return None


def settings_tables() -> dict[str, dict[str, tuple[Check, bool, Any]]]:
    """A table for each engine that has settings, named as the engine (``[rigid]``,
    ``[edmd]``), with a row for every field of its settings dataclass and the field's default:
    the dataclass is the one place a setting's default, range and check live."""
    tables: dict[str, dict[str, tuple[Check, bool, Any]]] = {}
    for entry in registry.engines():
        if entry.settings is not None:
            fields = dataclasses.fields(entry.settings)
            tables[entry.name] = {f.name: (_by_settings, False, f.default) for f in fields}
    return tables


def all_tables() -> dict[str, dict[str, tuple[Check, bool, Any]]]:
    """Every table a scene may hold: :data:`SCHEMA`'s and the engines' settings tables."""
    return SCHEMA | settings_tables()


def _text(value: Any) -> str | None:
    return None if isinstance(value, str) and value else f"must be a name, got {_show(value)}"


def _vector(value: Any) -> str | None:
    if not isinstance(value, list) or not value:
        return f"must be a list of numbers, got {_show(value)}"
    for item in value:
        problem = _number(item)
        if problem:
            return f"must be a list of numbers: an entry {problem}"
    return None


def _number_or_vector(value: Any) -> str | None:
    return _vector(value) if isinstance(value, list) else _number(value)


def _rows(value: Any) -> str | None:
    if not isinstance(value, list) or not value:
        return f"must be a list of [x, y(, z)] rows, got {_show(value)}"
    for row in value:
        problem = _vector(row)
        if problem:
            return f"must be a list of [x, y(, z)] rows of numbers: a row {problem}"
    return None


def _walls(value: Any) -> str | None:
    items = value if isinstance(value, list) else [value]
    if not items or len(items) not in (1, 4, 6):
        return f"must be one restitution or material name, or one per wall face, got {_show(value)}"
    for item in items:
        if isinstance(item, str):
            continue
        problem = _number(item)  # (its range: carom.Material's check)
        if problem:
            return f"must be restitutions or material names: an entry {problem}"
    return None


def _positive_or_list(value: Any) -> str | None:
    if isinstance(value, list):
        problem = _vector(value)
        if problem:
            return problem
        for v in value:
            problem = _positive(v)
            if problem:
                return problem
        return None
    return _positive(value)


def _show(value: Any) -> str:
    kind = type(value).__name__
    text = repr(value)
    return f"{text[:40]}{'...' if len(text) > 40 else ''} ({kind})"


def _boolean(value: Any) -> str | None:
    return None if isinstance(value, bool) else f"must be true or false, got {_show(value)}"


def _count(value: Any) -> str | None:
    problem = _integer(value) or (None if value >= 1 else f"must be >= 1, got {value!r}")
    if problem is None and value > MAX_BODIES:
        return f"must be at most {MAX_BODIES:,} (docs/scenes.md, Limits), got {value:,}"
    return problem


def _counts(value: Any) -> str | None:
    if not isinstance(value, list) or not value or any(_count(v) for v in value):
        return f"must be a list of whole numbers >= 1, got {_show(value)}"
    if math.prod(value) > MAX_BODIES:
        return (
            f"places {math.prod(value):,} bodies, more than the {MAX_BODIES:,} carom takes "
            f"(docs/scenes.md, Limits)"
        )
    return None


def _not_negative(value: Any) -> str | None:
    return _number(value) or (None if value >= 0 else f"must be >= 0, got {value!r}")


def _number_or_list(value: Any) -> str | None:
    return _vector(value) if isinstance(value, list) else _number(value)


def _size(value: Any) -> str | None:
    items = value if isinstance(value, list) else [value]
    if not items or len(items) > 3:
        return f"must be a length, [width, height] or [x, y, z] lengths, got {_show(value)}"
    for item in items:
        problem = _positive(item)
        if problem:
            return f"must be positive lengths: an entry {problem}"
    return None


def suggest(word: str, choices: Iterable[str], *, wrap: str = "{}") -> str:
    """What to write instead of an unknown ``word``: the nearest of ``choices`` (a misspelt
    key: "did you mean restitution?") or, with none near, the list of them (each written
    through ``wrap``, e.g. ``"[{}]"`` for tables)."""
    names = list(choices)
    near = difflib.get_close_matches(word, names, n=1, cutoff=0.6)
    if near:
        return f"did you mean {wrap.format(near[0])}?"
    return f"use one of {', '.join(wrap.format(name) for name in names)}"


def _pieces(value: Any) -> str | None:
    if not isinstance(value, list) or not value or not all(isinstance(v, dict) for v in value):
        return (
            'must be a list of inline tables, e.g. [{shape = "box", size = [1, 0.2], '
            f"offset = [0, 0.5]}}], got {_show(value)}"
        )
    for k, piece in enumerate(value):
        for key, item in piece.items():
            if key not in PIECE_KEYS:
                return f"piece {k + 1}: {key!r} is not a known key; {suggest(key, PIECE_KEYS)}"
            problem = PIECE_KEYS[key](item)
            if problem:
                return f"piece {k + 1}: {key} {problem}"
        if "shape" not in piece:
            return f"piece {k + 1}: shape is required (one of {', '.join(PIECE_SHAPES)})"
    return None


def _body(value: Any) -> str | None:
    if not isinstance(value, dict):
        example = '{shape = "box", size = [0.25, 0.25]}'
        return f"must be an inline table, e.g. {example}, got {_show(value)}"
    problem = _pieces([value])
    return problem.replace("piece 1: ", "") if problem else None


def _spins(value: Any) -> str | None:
    """One spin [rad/s] or one per body (2D), or one [wx, wy, wz] or one per body (3D)."""
    if isinstance(value, list) and value and isinstance(value[0], list):
        return _rows(value)
    return _number_or_list(value)


def _turns(value: Any) -> str | None:
    """One quaternion [w, x, y, z] for every body, or one per body."""
    rows = value if isinstance(value, list) and value and isinstance(value[0], list) else [value]
    for row in rows:
        if not isinstance(row, list) or len(row) != 4 or _vector(row):
            return f"must be a quaternion [w, x, y, z] or a list of them, got {_show(value)}"
    return None


def _pairs(value: Any) -> str | None:
    """One pair of body indices [a, b] (-1: the world), or a list of them."""
    rows = value if isinstance(value, list) and value and isinstance(value[0], list) else [value]
    for row in rows:
        if (
            not isinstance(row, list)
            or len(row) != 2
            or any(isinstance(i, bool) or not isinstance(i, int) for i in row)
        ):
            return (
                "must be a pair of body indices [a, b] (-1: the world) or a list of them, "
                f"got {_show(value)}"
            )
    return None


def _vector_or_rows(value: Any) -> str | None:
    """One vector, or one per joint."""
    if isinstance(value, list) and value and isinstance(value[0], list):
        return _rows(value)
    return _vector(value)


def _two(value: Any) -> str | None:
    """Two numbers [x, y]: a range, a motor (speed, most), a spring (hertz, ratio)."""
    problem = _vector(value)
    if problem is None and len(value) != 2:
        return f"must be two numbers, got {len(value)}"
    return problem


def _region(value: Any) -> str | None:
    if not isinstance(value, list) or len(value) != 2 or any(_vector(c) for c in value):
        return f"must be [[low corner], [high corner]], got {_show(value)}"
    return None


#: shapes of [[bodies]] (docs/scenes.md), from carom's one table of shape names
SHAPES = tuple(SHAPE_TABLE)
#: shapes a compound's pieces may have, and their keys
PIECE_SHAPES = tuple(name for name, shape in SHAPE_TABLE.items() if shape.piece)
PIECE_KEYS: dict[str, Check] = {
    "shape": _choice(*PIECE_SHAPES),
    "size": _size,
    "radius": _not_negative,
    "vertices": _rows,
    "offset": _vector,
    "angle": _number,
    "orientation": _turns,
    "sensor": _boolean,
}

SCHEMA: dict[str, dict[str, tuple[Check, bool, Any]]] = {
    "scene": {
        "title": (_text, False, None),
        "description": (_text, False, None),
    },
    "world": {
        "dimension": (_dimension, True, None),
        "box": (_vector, True, None),
        "boundary": (_choice("walls", "periodic", "open"), False, "walls"),
        "gravity": (_vector, False, None),
        "walls": (_walls, False, 1.0),
        "t_c": (_by_settings, False, None),  # the older place of [edmd] t_c
        "combine": (_choice(*COMBINE_RULES), False, "mean"),
        "engine": (_engine, False, "auto"),
    },
    "materials": {
        "name": (_text, True, None),
        "restitution": (_number, True, None),  # its range: carom.Material's check
        "beta": (_number, False, None),
        "friction": (_number, False, None),
        "beta0": (_number, False, None),
        "rolling": (_not_negative, False, 0.0),
    },
    "bodies": {
        "shape": (_choice(*SHAPES), False, "sphere"),
        "positions": (_rows, True, None),
        "velocities": (_rows, False, None),
        "radius": (_positive_or_list, False, None),
        "mass": (_positive_or_list, False, None),
        "material": (_text, False, None),
        "static": (_boolean, False, False),
        "kind": (_choice(*BODY_KINDS), False, None),
        "size": (_size, False, None),
        "vertices": (_rows, False, None),
        "pieces": (_pieces, False, None),
        "loop": (_boolean, False, False),
        "density": (_positive, False, None),
        "angles": (_number_or_list, False, 0.0),
        "orientations": (_turns, False, None),
        "file": (_text, False, None),
        "angular_velocities": (_spins, False, 0.0),
        "sensor": (_boolean, False, False),
        "category": (_integer, False, None),
        "mask": (_integer, False, None),
        "group": (_integer, False, None),
    },
    "row": {
        "count": (_count, True, None),
        "start": (_vector, True, None),
        "direction": (_vector, False, None),
        "spacing": (_positive, False, None),
        "radius": (_positive, True, None),
        "mass": (_positive, False, 1.0),
        "velocity": (_vector, False, None),
        "material": (_text, False, None),
    },
    "rack": {
        "rows": (_count, True, None),
        "apex": (_vector, True, None),
        "direction": (_vector, False, None),
        "gap": (_not_negative, False, 0.0),
        "radius": (_positive, True, None),
        "mass": (_positive, False, 1.0),
        "velocity": (_vector, False, None),
        "material": (_text, False, None),
    },
    "lattice": {
        "shape": (_counts, True, None),
        "origin": (_vector, True, None),
        "spacing": (_positive, True, None),
        "radius": (_positive, False, None),
        "body": (_body, False, None),
        "mass": (_positive, False, 1.0),
        "velocity": (_vector, False, None),
        "temperature": (_not_negative, False, 0.0),
        "seed": (_seed, False, 0),
        "material": (_text, False, None),
    },
    "pegs": {
        "rows": (_count, True, None),
        "top": (_vector, True, None),
        "spacing": (_vector, True, None),
        "layout": (_choice("triangle", "staggered"), False, "triangle"),
        "columns": (_count, False, None),
        "radius": (_positive, True, None),
        "material": (_text, False, None),
    },
    "pyramid": {
        "rows": (_count, True, None),
        "base": (_vector, True, None),
        "size": (_size, False, [1.0, 1.0]),
        "gap": (_not_negative, False, 0.0),
        "radius": (_not_negative, False, 0.0),
        "density": (_positive, False, 1.0),
        "repeat": (_counts, False, [1, 1]),
        "pitch": (_vector, False, None),
        "material": (_text, False, None),
    },
    "cushions": {
        "area": (_region, True, None),
        "height": (_positive, True, None),
        "width": (_positive, False, 0.05),
        "cloth": (_number, False, 0.0),
        "material": (_text, False, None),
    },
    "gas": {
        "count": (_count, True, None),
        "packing": (_positive, True, None),
        "radius": (_positive, True, None),
        "mass": (_positive, False, 1.0),
        "temperature": (_positive, False, 1.0),
        "seed": (_seed, False, 0),
        "material": (_text, False, None),
        "region": (_region, False, None),
        "drift": (_vector, False, None),
    },
    "joints": {
        "type": (
            _choice(
                "revolute",
                "prismatic",
                "distance",
                "weld",
                "fixed",
                "wheel",
                "spherical",
                "target",
            ),
            True,
            None,
        ),
        "bodies": (_pairs, True, None),
        "anchor": (_vector_or_rows, False, None),
        "anchors": (_vector_or_rows, False, None),
        "axis": (_vector_or_rows, False, None),
        "target": (_vector_or_rows, False, None),
        "length": (_not_negative, False, None),
        "min_length": (_not_negative, False, None),
        "max_length": (_not_negative, False, None),
        "limits": (_two, False, None),
        "motor": (_two, False, None),
        "spring": (_two, False, None),
        "angular_spring": (_two, False, None),
        "hertz": (_positive, False, 5.0),
        "damping_ratio": (_not_negative, False, 0.7),
        "max_force": (_positive, False, None),
        "collide": (_boolean, False, False),
    },
    "run": {
        "until": (_positive, True, None),
        "frame_interval": (_positive, False, None),
    },
    "outputs": {
        "trajectory": (_boolean, False, True),
        "events": (_boolean, False, True),
        "plots": (_boolean, False, True),
        "animation": (_choice("mp4", "gif", "none"), False, "mp4"),
    },
}
#: tables that may repeat ([[name]]); the generators place bodies in this order, after
#: [[bodies]] and before [[gas]] (which avoids everything placed before it)
GENERATORS = ("row", "rack", "lattice", "pegs", "pyramid", "cushions")
#: keys that carom once read under another name: table -> old key -> new key
RENAMED = {"world": {"wall_restitution": "walls", "tc": "t_c"}}
ARRAYS = ("materials", "bodies", *GENERATORS, "gas", "joints")


class Locator:
    """Finds the line of a key in the TOML text (best effort) and words the message."""

    def __init__(self, source: str, text: str) -> None:
        self.source = source
        self.lines = text.splitlines()

    def line_of(self, path: list[str], index: int | None) -> int | None:
        table = path[0]
        header = re.compile(
            r"^\s*\[\[\s*" + re.escape(table) + r"\s*\]\]"
            if table in ARRAYS
            else r"^\s*\[\s*" + re.escape(table) + r"\s*\]"
        )
        seen = -1
        start = None
        for number, line in enumerate(self.lines):
            if header.match(line):
                seen += 1
                if index is None or seen == index:
                    start = number
                    break
        if start is None:
            return None
        if len(path) == 1:
            return start + 1
        key = re.compile(r"^\s*" + re.escape(path[1]) + r"\s*=")
        for number in range(start + 1, len(self.lines)):
            if self.lines[number].lstrip().startswith("["):
                break
            if key.match(self.lines[number]):
                return number + 1
        return start + 1

    def refused(
        self, table: str, exc: CaromError, keys: Iterable[str], index: int | None = None
    ) -> SceneError:
        """What a carom class refused (its own check, the one check of the value), named at
        the key of ``table`` its message starts with ("restitution must lie in ...")."""
        key, _, rest = str(exc).partition(" ")
        if key in keys:
            return self.error([table, key], rest, "", index)
        return self.error([table], str(exc), "", index)

    def error(
        self, path: list[str], problem: str, fix: str, index: int | None = None
    ) -> SceneError:
        table = path[0]
        name = f"[[{table}]] #{index + 1}" if index is not None else f"[{table}]"
        if len(path) > 1:
            name += f" {path[1]}"
        line = self.line_of(path, index)
        where = f"{self.source}:{line}" if line is not None else self.source
        return SceneError(printable(f"{where}: {name}: {problem}" + (f"; {fix}" if fix else "")))
