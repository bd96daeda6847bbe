"""Sweep files: a base scene, the parameters to vary, the seeds and the observables.

A sweep file is TOML (``docs/sweeps.md``)::

    [sweep]
    title = "Equation of state of hard spheres"
    scene = "hard-sphere-gas"          # a built-in scene, or a file beside this one
    until = 20.0                       # simulated seconds [s] (default: the scene's)
    warmup = 5.0                       # seconds run before the averaging window [s]
    seeds = 4                          # 1, 2, 3, 4 (or a list: [11, 12])
    observables = ["compressibility", "collision_rate"]

    [parameters]
    "gas.count" = [200, 400, 600]              # a list of values
    "materials.restitution" = {from = 0.5, to = 1.0, steps = 6}
    "gas.temperature" = {from = 0.1, to = 10.0, steps = 5, log = true}

A parameter is a scene key by its dotted path: ``table.key`` (an array of tables with a
single entry needs no index), ``table.INDEX.key`` (``gas.1.count``), and list elements
by index (``world.walls.2``). Parameters are crossed (every combination, the first varying
slowest) or, with ``combine = "zip"``, taken together (lists of one length). Each point's
scene is checked like any scene file before anything runs.
"""

from __future__ import annotations

import copy
import hashlib
import itertools
import json
import math
import tomllib
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from carom._text import printable
from carom.errors import CaromError
from carom.scene import Scene, SceneError, find_scene
from carom.scene.schema import suggest

__all__ = [
    "MAX_POINTS",
    "Point",
    "SweepError",
    "SweepSpec",
    "builtin_sweeps",
    "find_sweep",
    "load_sweep",
]

#: the most points times seeds a sweep may hold (each is a task and a row of the table)
MAX_POINTS = 100_000


class SweepError(CaromError):
    """A sweep file that cannot be used: names the file, the key, what is wrong and the fix."""


@dataclass(frozen=True)
class Point:
    """One run of a sweep: a point of the parameter grid and a seed.

    Attributes
    ----------
    index : int
        The point's number in the grid, from 0, in the order the sweep file gives.
    seed : int or None
        The seed set into the scene; None when the sweep gives no seeds (the scene's own).
    values : dict
        Parameter path -> value at this point.
    scene : dict
        The base scene with those values and the seed set: nested dicts and lists, the shape
        of the TOML file.
    """

    index: int
    seed: int | None
    values: dict[str, Any]
    scene: dict[str, Any]

    @property
    def key(self) -> tuple[int, int | None]:
        """(index, seed): what identifies the point's row in the results table."""
        return (self.index, self.seed)


@dataclass(frozen=True)
class SweepSpec:
    """A checked sweep.

    Attributes
    ----------
    title : str
        What the sweep studies (a line).
    description : str
        More words, for the plots' captions and the table's reader.
    scene_path : Path
        The base scene file.
    base : dict
        The base scene as read (nested dicts and lists), before any parameter is set.
    until : float
        Simulated time of each run [s].
    warmup : float
        Simulated time before the averaging window of the observables [s]; 0 by default.
    seeds : list of int or None
        The seeds; None: each point runs once with the scene's own seeds.
    seed_keys : list of str
        Where a seed goes in the scene (dotted paths). With several, key ``k`` gets
        ``seed * len(seed_keys) + k``, so that no two random generators share a stream.
    parameters : dict
        Path -> the list of its values (ranges expanded), in the file's order.
    combine : {"cross", "zip"}
        Every combination of the parameters, or the k-th value of each together.
    observables : list of str
        What to collect from each run (:mod:`carom.sweeps.observe`).
    source : str
        Where the sweep came from (a path, or ``"<dict>"``), for messages.
    text : str
        The sweep file's text (written beside the results as ``sweep.toml``).
    """

    title: str
    description: str
    scene_path: Path
    base: dict[str, Any]
    until: float
    warmup: float
    seeds: list[int] | None
    seed_keys: list[str]
    parameters: dict[str, list[Any]]
    combine: str
    observables: list[str]
    source: str = "<dict>"
    text: str = ""

    @property
    def name(self) -> str:
        """A short name: the sweep file's stem, or its title."""
        return Path(self.source).stem if self.source != "<dict>" else self.title

    def count(self) -> int:
        """How many points the grid has (without making it)."""
        lengths = [len(v) for v in self.parameters.values()]
        if self.combine == "zip":
            return lengths[0] if lengths else 1
        return math.prod(lengths)

    def grid(self) -> list[dict[str, Any]]:
        """The parameter values of every point, in order."""
        names = list(self.parameters)
        columns = [self.parameters[n] for n in names]
        rows = zip(*columns, strict=True) if self.combine == "zip" else itertools.product(*columns)
        return [dict(zip(names, row, strict=True)) for row in rows]

    def points(self) -> list[Point]:
        """Every run of the sweep: each point of the grid with each seed, point by point."""
        out = []
        for index, values in enumerate(self.grid()):
            for seed in self.seeds if self.seeds is not None else [None]:
                scene = copy.deepcopy(self.base)
                for path, value in values.items():
                    _assign(scene, path, value)
                if seed is not None:
                    for k, path in enumerate(self.seed_keys):
                        _assign(scene, path, seed * len(self.seed_keys) + k)
                out.append(Point(index, seed, values, scene))
        return out

    def task(self, point: Point) -> dict[str, Any]:
        """What :func:`carom.sweeps.observe.run_point` needs to run ``point`` (plain data, for
        Dask to send to a worker)."""
        return {
            "index": point.index,
            "seed": point.seed,
            "scene": point.scene,
            "source": str(self.scene_path),
            "until": self.until,
            "warmup": self.warmup,
            "observables": self.observables,
        }

    def check(self) -> list[Point]:
        """Every point, each checked as a scene (nothing is built or run); a
        :class:`SweepError` names the first bad one."""
        points = self.points()
        for point in points:
            try:
                Scene.from_dict(point.scene, str(self.scene_path))
            except SceneError as exc:
                shown = ", ".join(f"{k} = {_show(v)}" for k, v in point.values.items())
                raise SweepError(
                    f"{self.source}: point {point.index} ({shown or 'the base scene'}) is not a "
                    f"valid scene: {exc}"
                ) from None
        return points

    def digest(self) -> str:
        """A fingerprint of everything that decides the table: the base scene, the grid, the
        seeds, the run and the observables; ``--resume`` refuses another."""
        data = {
            "base": self.base,
            "until": self.until,
            "warmup": self.warmup,
            "seeds": self.seeds,
            "seed_keys": self.seed_keys,
            "parameters": self.parameters,
            "combine": self.combine,
            "observables": self.observables,
        }
        text = json.dumps(data, sort_keys=True, default=repr)
        return hashlib.sha256(text.encode()).hexdigest()

    @classmethod
    def from_dict(
        cls, data: Mapping[str, Any], source: str = "<dict>", text: str = ""
    ) -> SweepSpec:
        """Check a sweep given as nested dicts (the shape of the TOML file); a scene named by
        a relative path is found beside ``source``."""
        where = source
        unknown = set(data) - {"sweep", "parameters"}
        if unknown:
            raise SweepError(
                f"{where}: unknown table [{sorted(unknown)[0]}]; a sweep has [sweep] and "
                f"[parameters]"
            )
        head = data.get("sweep")
        if not isinstance(head, dict):
            raise SweepError(f"{where}: the [sweep] table is missing; add one naming the scene")
        known = {
            "title",
            "description",
            "scene",
            "until",
            "warmup",
            "seeds",
            "seed_keys",
            "combine",
            "observables",
        }
        for key in head:
            if key not in known:
                raise SweepError(
                    f"{where}: [sweep] {key} is not a known key; {suggest(key, sorted(known))}"
                )
        scene_name = head.get("scene")
        if not isinstance(scene_name, str) or not scene_name:
            raise SweepError(
                f"{where}: [sweep] scene is required: a built-in scene name or a scene file"
            )
        scene_path = _scene_beside(scene_name, source)
        base_scene = _load_raw(scene_path)
        try:
            checked = Scene.from_dict(base_scene, str(scene_path))
        except SceneError as exc:
            raise SweepError(f"{where}: its scene is not valid: {exc}") from None
        until = head.get("until", checked.run["until"])
        warmup = head.get("warmup", 0.0)
        for key, value in (("until", until), ("warmup", warmup)):
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise SweepError(f"{where}: [sweep] {key} must be a number of seconds")
            if not math.isfinite(value) or value < 0 or (key == "until" and value <= 0):
                raise SweepError(f"{where}: [sweep] {key} must be a finite time >= 0, got {value}")
        if warmup >= until:
            raise SweepError(
                f"{where}: [sweep] warmup = {warmup:g} s must end before until = {until:g} s: "
                f"the observables are averaged between them"
            )
        seeds = _seeds(head.get("seeds"), where)
        seed_keys = _seed_keys(head.get("seed_keys"), base_scene, seeds, where)
        combine = head.get("combine", "cross")
        if combine not in ("cross", "zip"):
            raise SweepError(
                f"{where}: [sweep] combine must be 'cross' (every combination) or 'zip' (the "
                f"k-th values together), got {_show(combine)}"
            )
        parameters = _parameters(data.get("parameters", {}), base_scene, where)
        if combine == "zip" and len({len(v) for v in parameters.values()}) > 1:
            lengths = ", ".join(f"{k}: {len(v)}" for k, v in parameters.items())
            raise SweepError(
                f"{where}: combine = 'zip' takes the k-th value of each parameter together, so "
                f"they need as many values each ({lengths}); give lists of one length, or use "
                f"combine = 'cross'"
            )
        observables = head.get("observables")
        if (
            not isinstance(observables, list)
            or not observables
            or not all(isinstance(o, str) and o for o in observables)
        ):
            raise SweepError(
                f"{where}: [sweep] observables must be a list of names, e.g. "
                f"['temperature', 'collision_rate'] (docs/sweeps.md lists them)"
            )
        if len(set(observables)) != len(observables):
            raise SweepError(f"{where}: [sweep] observables names one twice: {observables}")
        from carom.sweeps.observe import check_observable

        for name in observables:
            problem = check_observable(name)
            if problem:
                raise SweepError(f"{where}: [sweep] observables: {problem}")
        spec = cls(
            title=str(head.get("title") or Path(source).stem),
            description=str(head.get("description") or ""),
            scene_path=scene_path,
            base=base_scene,
            until=float(until),
            warmup=float(warmup),
            seeds=seeds,
            seed_keys=seed_keys,
            parameters=parameters,
            combine=combine,
            observables=list(observables),
            source=source,
            text=text,
        )
        runs = spec.count() * (len(seeds) if seeds else 1)
        if runs > MAX_POINTS:
            raise SweepError(
                f"{where}: {runs:,} runs (points times seeds), more than the {MAX_POINTS:,} a "
                f"sweep may hold; split it into several sweeps"
            )
        return spec


def load_sweep(path: str | Path) -> SweepSpec:
    """Read and check a sweep file (a path, or the name of a built-in sweep).

    Raises
    ------
    SweepError
        Missing or unreadable file, bad TOML, an unknown key, a parameter that names no key of
        the scene, or a point whose scene breaks a rule of ``docs/scenes.md``.
    """
    path = find_sweep(path)
    try:
        text = path.read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as exc:
        raise SweepError(f"{path}: cannot be read ({exc})") from None
    try:
        data = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise SweepError(f"{path}: not valid TOML: {exc}; fix the syntax there") from None
    except RecursionError:
        raise SweepError(f"{path}: nested too deeply for Python's TOML reader") from None
    return SweepSpec.from_dict(data, str(path), text)


def builtin_sweeps() -> dict[str, Path]:
    """The sweeps that ship with carom (``carom/sweeps/library/*.toml``), by name."""
    folder = Path(__file__).parent / "library"
    return {path.stem: path for path in sorted(folder.glob("*.toml"))}


def find_sweep(name_or_path: str | Path) -> Path:
    """A sweep file: ``name_or_path`` if it is a file, else the built-in sweep of that name."""
    path = Path(name_or_path)
    if path.is_file():
        return path
    builtin = builtin_sweeps()
    if str(name_or_path) in builtin:
        return builtin[str(name_or_path)]
    raise SweepError(
        f"{printable(str(name_or_path))}: no such sweep file, and no built-in sweep of that "
        f"name; check the path, or use one of: {', '.join(builtin)}"
    )


# -- helpers --------------------------------------------------------------------------------


def _show(value: Any) -> str:
    text = repr(value)
    return printable(text if len(text) <= 60 else text[:57] + "...")


def _scene_beside(name: str, source: str) -> Path:
    """The scene a sweep names: a path relative to the sweep file, or a built-in name."""
    if source != "<dict>":
        beside = Path(source).parent / name
        if beside.is_file():
            return beside
    try:
        return find_scene(name)
    except SceneError as exc:
        raise SweepError(f"{source}: [sweep] scene: {exc}") from None


def _load_raw(path: Path) -> dict[str, Any]:
    try:
        data = tomllib.loads(path.read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, tomllib.TOMLDecodeError) as exc:
        raise SweepError(f"{path}: the sweep's scene cannot be read ({exc})") from None
    return data


def _seeds(value: Any, where: str) -> list[int] | None:
    if value is None:
        return None
    if isinstance(value, int) and not isinstance(value, bool):
        if not 1 <= value <= MAX_POINTS:
            raise SweepError(
                f"{where}: [sweep] seeds = {value} must be a count from 1 to {MAX_POINTS} "
                f"(seeds 1 ... n), or a list of seeds"
            )
        return list(range(1, value + 1))
    if (
        isinstance(value, list)
        and value
        and all(isinstance(s, int) and not isinstance(s, bool) and 0 <= s < 2**32 for s in value)
    ):
        if len(set(value)) != len(value):
            raise SweepError(f"{where}: [sweep] seeds lists a seed twice: {_show(value)}")
        return list(value)
    raise SweepError(
        f"{where}: [sweep] seeds must be a count (4 means 1, 2, 3, 4) or a list of whole "
        f"numbers from 0 to 2^32 - 1, got {_show(value)}"
    )


def _seed_paths(node: Any, prefix: str = "") -> list[str]:
    """Every ``seed`` key of a raw scene, as dotted paths."""
    found = []
    if isinstance(node, dict):
        for key, value in node.items():
            path = f"{prefix}{key}"
            if key == "seed":
                found.append(path)
            else:
                found += _seed_paths(value, path + ".")
    elif isinstance(node, list):
        for k, value in enumerate(node):
            found += _seed_paths(value, f"{prefix}{k}.")
    return found


def _seed_keys(value: Any, base: dict[str, Any], seeds: list[int] | None, where: str) -> list[str]:
    if value is None:
        keys = _seed_paths(base)
        if seeds is not None and not keys:
            raise SweepError(
                f"{where}: [sweep] seeds are given but the scene has no seed key to set; name "
                f"where each seed goes with seed_keys = ['gas.seed'], or drop seeds"
            )
        return keys if seeds is not None else []
    if not isinstance(value, list) or not all(isinstance(k, str) for k in value) or not value:
        raise SweepError(f"{where}: [sweep] seed_keys must be a list of dotted scene keys")
    if seeds is None:
        raise SweepError(f"{where}: [sweep] seed_keys needs seeds = ... (a count or a list)")
    for path in value:
        _resolve(base, path, where, "seed_keys")
    return [_canonical(base, p) for p in value]


def _parameters(table: Any, base: dict[str, Any], where: str) -> dict[str, list[Any]]:
    if not isinstance(table, dict):
        raise SweepError(f"{where}: [parameters] must be a table of dotted scene keys")
    out: dict[str, list[Any]] = {}
    for path, spec in _flatten(table):
        _resolve(base, path, where, f"[parameters] {path}")
        values = _values(spec, f"{where}: [parameters] {path}")
        canonical = _canonical(base, path)
        if canonical in out:
            raise SweepError(f"{where}: [parameters] names {canonical} twice")
        out[canonical] = values
    return out


_RANGE_KEYS = {"from", "to", "steps", "step", "log"}


def _flatten(table: dict[str, Any], prefix: str = "") -> list[tuple[str, Any]]:
    """``{"gas": {"count": [..]}}`` and ``{"gas.count": [..]}`` alike, as (path, values)."""
    out = []
    for key, value in table.items():
        path = f"{prefix}{key}"
        if isinstance(value, dict) and not (set(value) & _RANGE_KEYS):
            out += _flatten(value, path + ".")
        else:
            out.append((path, value))
    return out


def _values(spec: Any, where: str) -> list[Any]:
    """A parameter's values: a list as given, or a range ``{from, to, steps[, log]}`` or
    ``{from, to, step}`` expanded (ends included)."""
    if isinstance(spec, list):
        if not spec:
            raise SweepError(f"{where}: the list of values is empty; give at least one")
        return list(spec)
    if not isinstance(spec, dict):
        raise SweepError(
            f"{where}: give a list of values, or a range {{from = a, to = b, steps = n}} "
            f"(log = true for a geometric one) or {{from = a, to = b, step = s}}; got "
            f"{_show(spec)}"
        )
    unknown = set(spec) - _RANGE_KEYS
    if unknown:
        raise SweepError(f"{where}: unknown range key {sorted(unknown)[0]!r}; use from, to, steps")
    for name in ("from", "to"):
        v = spec.get(name)
        if isinstance(v, bool) or not isinstance(v, int | float) or not math.isfinite(v):
            raise SweepError(f"{where}: the range needs {name} = a number")
    lo, hi = spec["from"], spec["to"]
    log = spec.get("log", False)
    if not isinstance(log, bool):
        raise SweepError(f"{where}: log must be true or false")
    if ("steps" in spec) == ("step" in spec):
        raise SweepError(f"{where}: give steps = n (how many values) or step = s, one of them")
    if "step" in spec:
        step = spec["step"]
        if log:
            raise SweepError(f"{where}: a log range takes steps = n, not step")
        if isinstance(step, bool) or not isinstance(step, int | float) or not step > 0:
            raise SweepError(f"{where}: step must be a number > 0")
        if hi < lo:
            raise SweepError(f"{where}: to must not be below from with step = s")
        count = math.floor((hi - lo) / step * (1 + 1e-12)) + 1
        if count > MAX_POINTS:
            raise SweepError(f"{where}: {count:,} values; more than {MAX_POINTS:,}")
        if all(isinstance(v, int) for v in (lo, hi, step)):
            return [lo + k * step for k in range(count)]
        return [_clean(lo + k * step) for k in range(count)]
    steps = spec["steps"]
    if isinstance(steps, bool) or not isinstance(steps, int) or not 1 <= steps <= MAX_POINTS:
        raise SweepError(f"{where}: steps must be a whole number from 1 to {MAX_POINTS}")
    if steps == 1:
        return [lo]
    if log:
        if not (lo > 0 and hi > 0):
            raise SweepError(f"{where}: a log range needs from and to > 0")
        a, b = math.log(lo), math.log(hi)
        return [_clean(math.exp(a + (b - a) * k / (steps - 1))) for k in range(steps)]
    return [_clean(lo + (hi - lo) * k / (steps - 1)) for k in range(steps)]


def _clean(x: float) -> float:
    """``x`` rounded to 12 significant digits: 0.1 + 2 * 0.1 is written 0.3, as a reader of
    the table would."""
    return float(f"{x:.12g}")


def _resolve(base: dict[str, Any], path: str, where: str, what: str) -> None:
    """Check that ``path`` reaches a key the scene has or may have (its table exists)."""
    parts = path.split(".")
    node: Any = base
    for depth, part in enumerate(parts):
        last = depth == len(parts) - 1
        if isinstance(node, list):
            if not part.isdigit() and all(isinstance(e, dict) for e in node) and len(node) == 1:
                node = node[0]  # [[gas]] with one entry: gas.count
            elif part.isdigit() and int(part) < len(node):
                node = node[int(part)]
                continue
            else:
                raise SweepError(
                    f"{where}: {what}: {'.'.join(parts[:depth])} holds {len(node)} entries; "
                    f"name one by its index from 0, e.g. {'.'.join(parts[:depth])}.0"
                    + (f".{part}" if not part.isdigit() else "")
                )
        if isinstance(node, dict):
            if part in node:
                node = node[part]
                continue
            if last and depth > 0:
                return  # a key the scene leaves at its default: checked with the scene
            if depth == 0:
                from carom.scene.schema import ARRAYS, all_tables

                if part in all_tables() and not last and part not in ARRAYS:
                    node = {}
                    continue
            raise SweepError(
                f"{where}: {what}: the scene has no {'.'.join(parts[: depth + 1])}; "
                f"check the key against the scene file (docs/scenes.md)"
            )
        raise SweepError(
            f"{where}: {what}: {'.'.join(parts[:depth])} is a value, not a table or list"
        )


def _canonical(base: dict[str, Any], path: str) -> str:
    """``path`` with the index of one-entry arrays of tables written out (gas.count ->
    gas.0.count), so that every point names keys the same way."""
    parts = path.split(".")
    out: list[str] = []
    node: Any = base
    for part in parts:
        if isinstance(node, list) and not part.isdigit():
            out.append("0")
            node = node[0]
        out.append(part)
        if isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        elif isinstance(node, dict):
            node = node.get(part)
        else:
            node = None
    return ".".join(out)


def _assign(scene: dict[str, Any], path: str, value: Any) -> None:
    """Set the canonical dotted ``path`` of a raw scene to ``value`` (tables made as needed)."""
    parts = path.split(".")
    node: Any = scene
    for depth, part in enumerate(parts[:-1]):
        if isinstance(node, list):
            node = node[int(part)]
        else:
            if part not in node:
                node[part] = [] if parts[depth + 1].isdigit() else {}
            node = node[part]
    last = parts[-1]
    if isinstance(node, list):
        node[int(last)] = value
    else:
        node[last] = value


def show_value(value: Any) -> str:
    """A parameter value as a table cell: numbers in full (repr), lists as JSON."""
    if isinstance(value, float):
        return repr(value)
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, int | str):
        return str(value)
    return json.dumps(value)


def parameter_label(path: str) -> str:
    """A parameter's name for a plot's axis: ``gas.0.count`` -> ``gas count``."""
    parts = [p for p in path.split(".") if not p.isdigit()]
    return " ".join(parts)
