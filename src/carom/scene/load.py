"""Reading a scene: TOML (parsed with the standard library) or nested dicts, checked against
:mod:`carom.scene.schema` into a :class:`Scene`; finding built-in scenes by name."""

from __future__ import annotations

import sys
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

from carom.engines import registry
from carom.errors import CaromError
from carom.scene.schema import (
    ARRAYS,
    GENERATORS,
    RENAMED,
    SCHEMA,
    Locator,
    SceneError,
    all_tables,
    suggest,
)
from carom.shape_base import SHAPES

if TYPE_CHECKING:
    from carom.world import World

__all__ = ["Scene", "builtin_scenes", "find_scene", "load_scene"]


@dataclass
class Scene:
    """A checked scene: plain data, ready to :meth:`build`.

    Attributes
    ----------
    scene : dict
        The optional ``[scene]`` table: ``title`` and ``description``.
    world : dict
        The ``[world]`` table, defaults filled in.
    materials, bodies, row, rack, lattice, pegs, pyramid, cushions, gas : list of dict
        The ``[[materials]]``, ``[[bodies]]``, generator (``[[row]]``, ``[[rack]]``,
        ``[[lattice]]``, ``[[pegs]]``, ``[[pyramid]]``, ``[[cushions]]``) and ``[[gas]]``
        tables, defaults filled in.
    joints : list of dict
        The ``[[joints]]`` tables (:mod:`carom.joints`), defaults filled in; each joins
        bodies by their index in the order the scene places them.
    settings : dict of str to settings
        Each engine's settings (its dataclass, made from the table named as the engine:
        ``[rigid]``, ``[edmd]``; the dataclass's defaults for what the file leaves out).
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
    pyramid: list[dict[str, Any]] = field(default_factory=list)
    cushions: list[dict[str, Any]] = field(default_factory=list)
    gas: list[dict[str, Any]] = field(default_factory=list)
    joints: list[dict[str, Any]] = field(default_factory=list)
    run: dict[str, Any] = field(default_factory=dict)
    settings: dict[str, Any] = field(default_factory=dict)
    outputs: dict[str, Any] = field(default_factory=dict)
    source: str = "<dict>"
    text: str = ""

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "<dict>", text: str = "") -> Scene:
        """Check a scene given as nested dicts and lists (the shape of the TOML file)."""
        where = Locator(source, text)
        tables = all_tables()
        for table in data:
            if table not in tables:
                raise where.error(
                    [table], f"unknown table [{table}]", suggest(table, tables, wrap="[{}]")
                )
        parts: dict[str, Any] = {}
        for table in tables:
            value = data.get(table)
            if table in ARRAYS:
                entries = [] if value is None else value
                if not isinstance(entries, list) or not all(isinstance(e, dict) for e in entries):
                    raise where.error([table], "must be written as [[" + table + "]] tables", "")
                parts[table] = [
                    _check_table(table, tables[table], entry, where, index)
                    for index, entry in enumerate(entries)
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
                parts[table] = _check_table(table, tables[table], value, where, None)
        settings = _engine_settings(parts, tables, data, where)
        scene = cls(source=source, text=text, settings=settings, **parts)
        scene._check_consistency(where)
        return scene

    def _check_consistency(self, where: Locator) -> None:
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
        for index, name in enumerate(names):
            if name in names[:index]:
                raise where.error(
                    ["materials", "name"],
                    f"{name!r} is defined twice (also [[materials]] #{names.index(name) + 1})",
                    "give each material its own name",
                    index,
                )
        walls = self.world["walls"]
        for name in walls if isinstance(walls, list) else [walls]:
            if isinstance(name, str) and name not in names:
                raise where.error(
                    ["world", "walls"],
                    f"names material {name!r}, which no [[materials]] table defines",
                    f"define it, or use one of {names}" if names else "define it",
                )
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
            "pyramid": ("base",),
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
        for index, entry in enumerate(self.lattice):
            if (entry["radius"] is None) == (entry["body"] is None):
                raise where.error(
                    ["lattice"],
                    "needs radius = ... (spheres) or body = {shape = ...} (rigid bodies), "
                    "one of them",
                    "",
                    index,
                )
        for index, entry in enumerate(self.bodies):
            other = SHAPES[entry["shape"]].dims
            if dim not in other:
                *some, last = (n for n, shape in SHAPES.items() if dim in shape.dims)
                raise where.error(
                    ["bodies", "shape"],
                    f"{entry['shape']!r} is a {other[0]}D shape",
                    f"in {dim}D use {', '.join(some)} or {last}, or a {other[0]}D world",
                    index,
                )
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

    def build(self, *, engine: bool = True) -> World:
        """The :class:`carom.World` this scene describes (bodies placed, nothing run yet).

        Parameters
        ----------
        engine : bool
            Also build the world's engine, which refuses bodies outside the box or overlapping
            (:meth:`carom.World.build`) and so compiles the kernels that find contacts, or
            loads them from the cache. With False that check waits for the first run.
        """
        from carom.scene.build import build_world

        return build_world(self, engine=engine)


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
    except RecursionError:
        raise SceneError(
            f"{path}: nested too deeply for Python's TOML reader (arrays or tables inside "
            f"each other about {sys.getrecursionlimit() // 4} levels or more); a scene needs "
            f"at most three"
        ) from None
    return Scene.from_dict(data, str(path), text)


def builtin_scenes() -> dict[str, Path]:
    """The scenes that ship with carom (``carom/scenarios/*.toml``), by name."""
    folder = Path(__file__).parent.parent / "scenarios"
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


def _engine_settings(
    parts: dict[str, Any], tables: Mapping[str, Any], data: Mapping[str, Any], where: Locator
) -> dict[str, Any]:
    """Each engine's settings, made from (and taken out of) its table in ``parts`` (those of
    ``tables`` not in :data:`SCHEMA`): the one check of every setting is its dataclass's; a
    setting it refuses is named by line. The older ``[world] t_c`` is the event-driven
    engine's ``t_c``."""
    older = parts["world"].pop("t_c")
    settings: dict[str, Any] = {}
    for name, rows in tables.items():
        if name in SCHEMA:
            continue
        table = parts.pop(name)
        if name == "edmd" and older is not None:
            if "t_c" in (data.get("edmd") or {}):
                raise where.error(
                    ["world", "t_c"], "is also given as [edmd] t_c", "give it once, in [edmd]"
                )
            table["t_c"] = older
        kind = registry.find(name).settings
        assert kind is not None
        try:
            settings[name] = kind(**table)
        except CaromError as exc:
            moved = name == "edmd" and str(exc).startswith("t_c ") and older is not None
            raise (
                where.refused("world", exc, ["t_c"]) if moved else where.refused(name, exc, rows)
            ) from None
    return settings


def _check_table(
    table: str,
    schema: Mapping[str, tuple[Any, bool, Any]],
    entry: Mapping[str, Any],
    where: Locator,
    index: int | None,
) -> dict[str, Any]:
    result: dict[str, Any] = {}
    for key, value in entry.items():
        if key in RENAMED.get(table, {}):
            new = RENAMED[table][key]
            raise where.error(
                [table, key], f"was renamed to {new}", f"write {new} = ... instead", index
            )
        if key not in schema:
            raise where.error([table, key], "is not a known key", suggest(key, schema), index)
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
