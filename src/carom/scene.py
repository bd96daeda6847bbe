"""Scenes: a world, its bodies and a run, written in TOML (parsed with the standard library).

A scene file has the tables ``[world]``, ``[[materials]]``, ``[[bodies]]``, ``[[gas]]`` and
``[run]``; ``docs/scenes.md`` documents every key, unit and default. :func:`load_scene`
reads and checks a file and :meth:`Scene.build` makes the :class:`carom.World`; a scene can
also be made in Python (``Scene.from_dict``). Every error is a :class:`SceneError` (a
``CaromError``) that names the file, the key, its line when it can be found, what is wrong
and how to fix it.
"""

from __future__ import annotations

import math
import re
import tomllib
from collections.abc import Callable, Iterator, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from carom import generators
from carom.errors import CaromError
from carom.world import Material, World

__all__ = ["Scene", "SceneError", "builtin_scenes", "find_scene", "load_scene"]


class SceneError(CaromError):
    """A scene that cannot be used, with the file, key and line it concerns."""


# -- the schema: key -> (check, required, default) per table ----------------------------------

Check = Callable[[Any], str | None]  # returns what is wrong, or None


def _number(value: Any) -> str | None:
    if isinstance(value, bool) or not isinstance(value, int | float):
        return f"must be a number, got {_show(value)}"
    if not math.isfinite(value):
        return f"must be finite, got {value!r}"
    return None


def _positive(value: Any) -> str | None:
    return _number(value) or (None if value > 0 else f"must be > 0, got {value!r}")


def _unit_interval(value: Any) -> str | None:
    return _number(value) or (None if 0 <= value <= 1 else f"must lie in [0, 1], got {value!r}")


def _integer(value: Any) -> str | None:
    if isinstance(value, bool) or not isinstance(value, int):
        return f"must be an integer, got {_show(value)}"
    return None


def _dimension(value: Any) -> str | None:
    return _integer(value) or (None if value in (2, 3) else f"must be 2 or 3, got {value!r}")


def _choice(*options: str) -> Check:
    def check(value: Any) -> str | None:
        if value in options:
            return None
        return f"must be one of {', '.join(repr(o) for o in options)}, got {_show(value)}"

    return check


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
        if _vector(row):
            return f"must be a list of [x, y(, z)] rows of numbers, got {_show(row)}"
    return None


def _positive_or_list(value: Any) -> str | None:
    if isinstance(value, list):
        problem = _vector(value)
        if problem:
            return problem
        bad = [v for v in value if not v > 0]
        return f"must be > 0, got {bad[0]!r}" if bad else None
    return _positive(value)


def _show(value: Any) -> str:
    kind = type(value).__name__
    text = repr(value)
    return f"{text[:40]}{'...' if len(text) > 40 else ''} ({kind})"


def _boolean(value: Any) -> str | None:
    return None if isinstance(value, bool) else f"must be true or false, got {_show(value)}"


def _count(value: Any) -> str | None:
    return _integer(value) or (None if value >= 1 else f"must be >= 1, got {value!r}")


def _counts(value: Any) -> str | None:
    if not isinstance(value, list) or not value or any(_count(v) for v in value):
        return f"must be a list of whole numbers >= 1, got {_show(value)}"
    return None


def _not_negative(value: Any) -> str | None:
    return _number(value) or (None if value >= 0 else f"must be >= 0, got {value!r}")


def _region(value: Any) -> str | None:
    if not isinstance(value, list) or len(value) != 2 or any(_vector(c) for c in value):
        return f"must be [[low corner], [high corner]], got {_show(value)}"
    return None


SCHEMA: dict[str, dict[str, tuple[Check, bool, Any]]] = {
    "scene": {
        "title": (_text, False, None),
        "description": (_text, False, None),
    },
    "world": {
        "dimension": (_dimension, True, None),
        "box": (_vector, True, None),
        "boundary": (_choice("walls", "periodic"), False, "walls"),
        "gravity": (_vector, False, None),
        "wall_restitution": (_number_or_vector, False, 1.0),
        "tc": (_positive, False, 1e-6),
        "combine": (_choice("mean", "min", "max", "geometric", "product"), False, "mean"),
    },
    "materials": {
        "name": (_text, True, None),
        "restitution": (_unit_interval, True, None),
        "beta": (_number, False, None),
        "friction": (_number, False, None),
        "beta0": (_number, False, None),
    },
    "bodies": {
        "positions": (_rows, True, None),
        "velocities": (_rows, False, None),
        "radius": (_positive_or_list, True, None),
        "mass": (_positive_or_list, False, 1.0),
        "material": (_text, False, None),
        "static": (_boolean, False, False),
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
        "radius": (_positive, True, None),
        "mass": (_positive, False, 1.0),
        "velocity": (_vector, False, None),
        "temperature": (_not_negative, False, 0.0),
        "seed": (_integer, False, 0),
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
    "gas": {
        "count": (_count, True, None),
        "packing": (_positive, True, None),
        "radius": (_positive, True, None),
        "mass": (_positive, False, 1.0),
        "temperature": (_positive, False, 1.0),
        "seed": (_integer, False, 0),
        "material": (_text, False, None),
        "region": (_region, False, None),
        "drift": (_vector, False, None),
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
GENERATORS = ("row", "rack", "lattice", "pegs")
ARRAYS = ("materials", "bodies", *GENERATORS, "gas")


# -- reading --------------------------------------------------------------------------------


@dataclass
class Scene:
    """A checked scene: plain data, ready to :meth:`build`.

    Attributes
    ----------
    scene : dict
        The optional ``[scene]`` table: ``title`` and ``description``.
    world : dict
        The ``[world]`` table, defaults filled in.
    materials, bodies, row, rack, lattice, pegs, gas : list of dict
        The ``[[materials]]``, ``[[bodies]]``, generator (``[[row]]``, ``[[rack]]``,
        ``[[lattice]]``, ``[[pegs]]``) and ``[[gas]]`` tables, defaults filled in.
    run : dict
        The ``[run]`` table: ``until`` [s] and ``frame_interval`` [s] (None: no frames).
    outputs : dict
        The ``[outputs]`` table: which files ``carom run`` writes.
    source : str
        Where it came from (a path, or ``"<dict>"``), for messages.
    """

    world: dict[str, Any]
    scene: dict[str, Any] = field(default_factory=dict)
    materials: list[dict[str, Any]] = field(default_factory=list)
    bodies: list[dict[str, Any]] = field(default_factory=list)
    row: list[dict[str, Any]] = field(default_factory=list)
    rack: list[dict[str, Any]] = field(default_factory=list)
    lattice: list[dict[str, Any]] = field(default_factory=list)
    pegs: list[dict[str, Any]] = field(default_factory=list)
    gas: list[dict[str, Any]] = field(default_factory=list)
    run: dict[str, Any] = field(default_factory=dict)
    outputs: dict[str, Any] = field(default_factory=dict)
    source: str = "<dict>"
    text: str = ""

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "<dict>", text: str = "") -> Scene:
        """Check a scene given as nested dicts and lists (the shape of the TOML file)."""
        where = _Locator(source, text)
        for table in data:
            if table not in SCHEMA:
                raise where.error(
                    [table],
                    f"unknown table [{table}]",
                    f"use one of {', '.join('[' + t + ']' for t in SCHEMA)}",
                )
        parts: dict[str, Any] = {}
        for table in SCHEMA:
            value = data.get(table)
            if table in ARRAYS:
                entries = [] if value is None else value
                if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
                    raise where.error([table], "must be written as [[" + table + "]] tables", "")
                parts[table] = [
                    _check_table(table, entry, where, index) for index, entry in enumerate(entries)
                ]
            else:
                if value is None:
                    if table in ("world", "run"):
                        raise where.error(
                            [table], f"the [{table}] table is missing", f"add a [{table}] table"
                        )
                    value = {}
                if not isinstance(value, dict):
                    raise where.error([table], f"[{table}] must be a table", "")
                parts[table] = _check_table(table, value, where, None)
        scene = cls(source=source, text=text, **parts)
        scene._check_consistency(where)
        return scene

    def _check_consistency(self, where: _Locator) -> None:
        dim = self.world["dimension"]
        for key in ("box", "gravity"):
            value = self.world[key]
            if value is not None and len(value) != dim:
                raise where.error(
                    ["world", key],
                    f"has {len(value)} components for a {dim}D world",
                    f"give {dim} numbers",
                )
        if any(not side > 0 for side in self.world["box"]):
            raise where.error(["world", "box"], "sides must be > 0", "give positive lengths [m]")
        names = [m["name"] for m in self.materials]
        for table in ("bodies", *GENERATORS, "gas"):
            for index, entry in enumerate(getattr(self, table)):
                name = entry.get("material")
                if name is not None and name not in names:
                    raise where.error(
                        [table, "material"],
                        f"names material {name!r}, which no [[materials]] table defines",
                        f"define it, or use one of {names}" if names else "define it",
                        index,
                    )
        for index, entry in enumerate(self.gas):
            points = [("drift", entry["drift"])] + [("region", c) for c in entry["region"] or []]
            for key, value in points:
                if value is not None and len(value) != dim:
                    raise where.error(
                        ["gas", key],
                        f"needs {dim} numbers per point in a {dim}D world, got {len(value)}",
                        f"give {dim} numbers",
                        index,
                    )
        vectors = {
            "row": ("start", "direction", "velocity"),
            "rack": ("apex", "direction", "velocity"),
            "lattice": ("origin", "velocity", "shape"),
            "pegs": ("top",),
        }
        for table, keys in vectors.items():
            for index, entry in enumerate(getattr(self, table)):
                for key in keys:
                    value = entry[key]
                    if value is not None and len(value) != dim:
                        raise where.error(
                            [table, key],
                            f"has {len(value)} components for a {dim}D world",
                            f"give {dim} numbers",
                            index,
                        )
                direction = entry.get("direction")
                if direction is not None and not any(direction):
                    raise where.error(
                        [table, "direction"], "is the zero vector", "give a direction", index
                    )
        for index, entry in enumerate(self.pegs):
            if len(entry["spacing"]) != 2 or not all(v > 0 for v in entry["spacing"]):
                raise where.error(
                    ["pegs", "spacing"],
                    f"must be [dx, dy] with both > 0, got {entry['spacing']!r}",
                    "give the gap between pegs in a row and between rows [m]",
                    index,
                )
            if entry["layout"] == "staggered" and entry["columns"] is None:
                raise where.error(
                    ["pegs", "columns"],
                    "is required for layout = 'staggered'",
                    "add columns = ... (pegs per row)",
                    index,
                )
        for index, entry in enumerate(self.bodies):
            for key in ("positions", "velocities"):
                rows = entry[key]
                if rows is not None and any(len(row) != dim for row in rows):
                    raise where.error(
                        ["bodies", key],
                        f"rows must have {dim} numbers in a {dim}D world",
                        f"write each as [x, y{', z' if dim == 3 else ''}]",
                        index,
                    )
            if entry["velocities"] is not None and len(entry["velocities"]) != len(
                entry["positions"]
            ):
                raise where.error(
                    ["bodies", "velocities"],
                    f"has {len(entry['velocities'])} rows for {len(entry['positions'])} positions",
                    "give one velocity per position, or none",
                    index,
                )

    def build(self) -> World:
        """The :class:`carom.World` this scene describes (bodies placed, nothing run yet)."""
        where = _Locator(self.source, self.text)
        w = self.world
        try:
            world = World(
                w["dimension"],
                w["box"],
                w["boundary"],
                w["gravity"],
                wall_restitution=w["wall_restitution"],
                t_c=w["tc"],
                combine=w["combine"],
            )
        except CaromError as exc:
            raise where.error(["world"], str(exc), "") from None
        materials: dict[str, Material] = {}
        for index, m in enumerate(self.materials):
            try:
                materials[m["name"]] = Material(
                    m["restitution"], beta=m["beta"], friction=m["friction"], beta0=m["beta0"]
                )
            except CaromError as exc:
                raise where.error(["materials"], str(exc), "", index) from None
        for table, index, b in self._placed_bodies():
            material = materials.get(b["material"]) if b["material"] else None
            try:
                if b["static"]:
                    world.add_static_spheres(b["positions"], radius=b["radius"], material=material)
                else:
                    world.add_spheres(
                        b["positions"],
                        b["velocities"],
                        radius=b["radius"],
                        mass=b["mass"],
                        material=material,
                    )
            except CaromError as exc:
                raise where.error([table], str(exc), "", index) from None
        for index, g in enumerate(self.gas):
            try:
                _add_gas(world, g, materials.get(g["material"]) if g["material"] else None)
            except CaromError as exc:
                raise where.error(["gas"], str(exc), "", index) from None
        if world.n_bodies == 0:
            raise where.error(
                ["bodies"],
                "the scene has no bodies",
                "add [[bodies]], [[gas]] or generator ([[row]], [[rack]], ...) tables",
            )
        try:
            world._ensure_built()  # refuses overlapping spheres and spheres outside the box
        except CaromError as exc:
            raise SceneError(f"{self.source}: {exc}") from None
        return world

    def _placed_bodies(self) -> Iterator[tuple[str, int, dict[str, Any]]]:
        """(table, index, [[bodies]]-shaped entry) for [[bodies]] and every generator, in the
        order they are added to the world."""
        dim = self.world["dimension"]
        for index, entry in enumerate(self.bodies):
            yield "bodies", index, entry
        for table in GENERATORS:
            for index, entry in enumerate(getattr(self, table)):
                positions = _generated_positions(table, entry, dim)
                count = len(positions)
                velocity = entry.get("velocity")
                velocities = (
                    np.zeros((count, dim)) if velocity is None else np.tile(velocity, (count, 1))
                )
                if table == "lattice" and entry["temperature"] > 0:
                    rng = np.random.default_rng(entry["seed"])
                    velocities += rng.normal(
                        scale=math.sqrt(entry["temperature"] / entry["mass"]), size=(count, dim)
                    )
                yield (
                    table,
                    index,
                    {
                        "positions": positions,
                        "velocities": velocities,
                        "radius": entry["radius"],
                        "mass": entry.get("mass", 1.0),
                        "material": entry["material"],
                        "static": table == "pegs",
                    },
                )


def _generated_positions(table: str, entry: Mapping[str, Any], dim: int) -> np.ndarray:
    """The centres a generator table places, (n, dim) [m]."""
    if table == "row":
        spacing = entry["spacing"] or 2.0 * entry["radius"]
        return generators.row_positions(entry["count"], entry["start"], spacing, entry["direction"])
    if table == "rack":
        return generators.rack_positions(
            entry["rows"], entry["apex"], 2.0 * entry["radius"] + entry["gap"], entry["direction"]
        )
    if table == "lattice":
        return generators.lattice_positions(entry["shape"], entry["origin"], entry["spacing"])
    assert table == "pegs"
    return generators.peg_positions(
        entry["rows"], entry["top"], entry["spacing"], entry["layout"], entry["columns"]
    )


def load_scene(path: str | Path) -> Scene:
    """Read and check a scene file.

    Parameters
    ----------
    path : str or Path
        A ``.toml`` scene file.

    Returns
    -------
    Scene

    Raises
    ------
    SceneError
        The file is missing or unreadable, is not valid TOML (with its line and column), or
        breaks a rule of ``docs/scenes.md`` (with the key and its line).
    """
    path = Path(path)
    try:
        text = path.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise SceneError(f"{path}: no such scene file; check the path") from None
    except (OSError, UnicodeDecodeError) as exc:
        raise SceneError(f"{path}: cannot be read ({exc})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SceneError(f"{path}: not valid TOML: {exc}; fix the syntax there") from None
    return Scene.from_dict(data, str(path), text)


def builtin_scenes() -> dict[str, Path]:
    """The scenes that ship with carom (``carom/scenarios/*.toml``), by name."""
    folder = Path(__file__).parent / "scenarios"
    return {path.stem: path for path in sorted(folder.glob("*.toml"))}


def find_scene(name_or_path: str | Path) -> Path:
    """A scene file: ``name_or_path`` itself if it is a file, else the built-in scene of that
    name; a :class:`SceneError` naming both possibilities otherwise."""
    path = Path(name_or_path)
    if path.is_file():
        return path
    builtin = builtin_scenes()
    if str(name_or_path) in builtin:
        return builtin[str(name_or_path)]
    raise SceneError(
        f"{name_or_path}: no such scene file, and no built-in scene of that name; check the "
        f"path, or use one of: {', '.join(builtin)} (carom scenes lists them)"
    )


def _check_table(
    table: str, entry: Mapping[str, Any], where: _Locator, index: int | None
) -> dict[str, Any]:
    schema = SCHEMA[table]
    result: dict[str, Any] = {}
    for key, value in entry.items():
        if key not in schema:
            raise where.error(
                [table, key], "is not a known key", f"use one of {', '.join(schema)}", index
            )
        problem = schema[key][0](value)
        if problem:
            raise where.error([table, key], problem, "", index)
        result[key] = value
    for key, (_, required, default) in schema.items():
        if key not in result:
            if required:
                raise where.error(
                    [table, key], "is required", f"add {key} = ... to this table", index
                )
            result[key] = default
    return result


def _add_gas(world: World, gas: Mapping[str, Any], material: Material | None) -> None:
    """``count`` spheres of one radius placed at random, without overlap, at the packing
    fraction ``packing`` of the box, with Maxwell velocities at ``temperature`` (k_B = 1)."""
    dim = world.dim
    count, radius, packing = gas["count"], gas["radius"], gas["packing"]
    if gas["region"] is None:
        volume = float(np.prod(world.box))
    else:
        volume = float(np.prod(np.subtract(gas["region"][1], gas["region"][0])))
    unit = math.pi * radius**2 if dim == 2 else 4.0 / 3.0 * math.pi * radius**3
    if count * unit > packing * volume * (1 + 1e-12):
        raise CaromError(
            f"{count} spheres of radius {radius} need a packing of "
            f"{count * unit / volume:.4g}, more than packing = {packing}; enlarge the box, "
            f"or lower count or radius"
        )
    rng = np.random.default_rng(gas["seed"])
    region = gas["region"]
    low = np.zeros(dim) if region is None else np.asarray(region[0], dtype=float)
    high = world.box.copy() if region is None else np.asarray(region[1], dtype=float)
    if np.any(low < 0) or np.any(high > world.box) or np.any(high <= low):
        raise CaromError(
            f"region {region} must be a box inside [0, {world.box.tolist()}] with its high "
            f"corner above its low one; fix its corners"
        )
    positions = _random_positions(world, count, radius, rng, low, high)
    velocities = rng.normal(scale=math.sqrt(gas["temperature"] / gas["mass"]), size=(count, dim))
    velocities -= velocities.mean(axis=0)
    if gas["drift"] is not None:
        velocities += np.asarray(gas["drift"], dtype=float)
    world.add_spheres(positions, velocities, radius=radius, mass=gas["mass"], material=material)


def _random_positions(
    world: World,
    count: int,
    radius: float,
    rng: np.random.Generator,
    low: np.ndarray,
    high: np.ndarray,
) -> np.ndarray:
    """Random sequential addition in the box ``[low, high]``: uniform trial points, each kept
    if it overlaps nothing placed before (walls, earlier gas, bodies already in the world)."""
    dim = world.dim
    box = world.box
    walled = world.boundary == "walls" or np.any(low > 0) or np.any(high < box)
    margin = radius if walled else 0.0
    cell = 2.0 * radius
    grid: dict[tuple[int, ...], list[int]] = {}
    others = [(p, r) for p, r in zip(world.positions, world._radius, strict=True)]
    placed: list[np.ndarray] = []
    tries = 0
    while len(placed) < count:
        tries += 1
        if tries > 200 * count + 10_000:
            raise CaromError(
                f"could place only {len(placed)} of {count} spheres at random without overlap; "
                f"lower packing (random placement jams near 0.38 in 3D, 0.55 in 2D)"
            )
        p = low + margin + rng.random(dim) * (high - low - 2 * margin)
        key = tuple(int(c) for c in np.floor(p / cell))
        clash = False
        for offset in np.ndindex(*([3] * dim)):
            near = tuple((k + o - 1) for k, o in zip(key, offset, strict=True))
            if world.boundary == "periodic":
                near = tuple(n % max(1, int(box[d] // cell)) for d, n in enumerate(near))
            for j in grid.get(near, []):
                d = p - placed[j]
                if world.boundary == "periodic":
                    d -= box * np.round(d / box)
                if d @ d < (2 * radius) ** 2:
                    clash = True
                    break
            if clash:
                break
        if not clash:
            for q, r in others:
                d = p - q
                if world.boundary == "periodic":
                    d -= box * np.round(d / box)
                if d @ d < (radius + r) ** 2:
                    clash = True
                    break
        if clash:
            continue
        if world.boundary == "periodic":
            key = tuple(k % max(1, int(box[d] // cell)) for d, k in enumerate(key))
        grid.setdefault(key, []).append(len(placed))
        placed.append(p)
    return np.array(placed)


class _Locator:
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

    def error(
        self, path: list[str], problem: str, fix: str, index: int | None = None
    ) -> SceneError:
        table = path[0]
        name = f"[[{table}]] #{index + 1}" if index is not None else f"[{table}]"
        if len(path) > 1:
            name += f" {path[1]}"
        line = self.line_of(path, index)
        where = f"{self.source}:{line}" if line is not None else self.source
        return SceneError(f"{where}: {name}: {problem}" + (f"; {fix}" if fix else ""))
