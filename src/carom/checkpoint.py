"""Checkpoints: a whole :class:`carom.World` in one ``.npz`` file, to continue bit for bit.

The file holds the world's settings, materials and planes as JSON (``meta``), the body table,
the engine's own arrays under ``engine.*`` (versioned per engine), and a caller's ``extra``
arrays. Orientations, spins and inertia tensors are written only when the table stores them
(not while every body is unrotated, still, or a sphere), and the table's motion is not
written at all when the event-driven engine's state, which holds it, is: for 10^6 spheres in
3D that keeps 167 MB of copies, identities and zeros out of the file (536 to 369 MB) and
out of memory.

A checkpoint is written beside its path and renamed over it, so the path always holds a whole
checkpoint. A checkpoint is read only by the format version that wrote it; an older or newer
one is refused with a message that says so.
"""

from __future__ import annotations

import json
import zipfile
from collections.abc import Callable, Iterator, Mapping
from dataclasses import asdict
from pathlib import Path
from typing import Any, Protocol, TypeVar

import numpy as np
from numpy.typing import NDArray

from carom.bodies import PIECE_ARRAYS, Bodies, pieces_from_arrays, pieces_to_arrays
from carom.engines import registry
from carom.engines.base import Counters, Engine
from carom.errors import CaromError
from carom.materials import CombineRule, Material

__all__ = ["FORMAT", "VERSION", "load_world", "save_world"]

FORMAT = "carom-checkpoint"
#: bumped whenever the layout of the file or of an engine's arrays changes
VERSION = 14
#: older versions this carom still reads: 12 kept the two built-in engines' settings under
#: "settings" and "rigid" where 13 keeps every engine's under "engine_settings"; 13 kept the
#: event-driven engine's collision counters as the schedule's fourth column and its
#: calendar's four per-body arrays apart, where 14 keeps ``state.counter`` and
#: ``state.cal_body`` (its ``restore`` reads either)
READS = (12, 13, VERSION)
#: the body table's motion, and its other fields (read as they are)
MOTION_FIELDS = ("position", "velocity", "orientation", "angular_velocity")
BODY_FIELDS = ("shape", "radius", "mass", "inertia_factor", "material", "kind")


class Checkpointed(Protocol):
    """What a checkpoint holds of a :class:`carom.World` (which calls this module: it is
    typed by this protocol, not imported) and how a World is set back to it."""

    dim: int
    box: NDArray[np.float64]
    boundary: str
    gravity: NDArray[np.float64]
    walls: tuple[Material, ...]
    planes: list[tuple[NDArray[np.float64], NDArray[np.float64], Material]]
    materials: list[Material]
    combine: CombineRule
    engine_choice: str
    engine_settings: dict[str, Any]
    bodies: Bodies

    @property
    def engine(self) -> Engine | None: ...

    @property
    def time(self) -> float: ...

    @property
    def pair_overrides(self) -> dict[tuple[int, int], float]: ...

    @property
    def counters_before(self) -> Counters: ...

    @property
    def collisions(self) -> NDArray[Any]: ...

    @property
    def collisions_dropped(self) -> int: ...

    def add_material(self, material: Material) -> int: ...

    def set_pair(self, material_a: int, material_b: int, restitution: float) -> None: ...

    def add_plane(self, point: Any, normal: Any, *, material: Material | None = None) -> int: ...

    def restore(
        self,
        time: float,
        engine_arrays: Mapping[str, NDArray[Any]] | None,
        counters_before: Counters,
        log: NDArray[Any],
        collisions_dropped: int,
        engine_name: str | None = None,
    ) -> None: ...


W = TypeVar("W", bound=Checkpointed)


def save_world(world: Checkpointed, path: Path, extra: Mapping[str, NDArray[Any]]) -> None:
    """Write ``world`` (and ``extra`` arrays, by name) to ``path``, atomically."""
    engine = world.engine
    meta = {
        "format": FORMAT,
        "version": VERSION,
        "engine": None if engine is None else engine.name,
        "dim": world.dim,
        "box": world.box.tolist(),
        "boundary": world.boundary,
        "gravity": world.gravity.tolist(),
        "walls": [asdict(m) for m in world.walls],
        "engine_settings": {name: asdict(value) for name, value in world.engine_settings.items()},
        "engine_choice": world.engine_choice,
        "combine": world.combine,
        "time": world.time,
        "materials": [asdict(m) for m in world.materials],
        "pair_overrides": [[a, b, e] for (a, b), e in world.pair_overrides.items()],
        "planes": [[p.tolist(), q.tolist(), asdict(m)] for p, q, m in world.planes],
        "counters_before": list(world.counters_before),
        "collisions_dropped": world.collisions_dropped,
    }
    arrays: dict[str, Any] = {"meta": np.array(json.dumps(meta))}
    motion: dict[str, Any] = {}
    if not _motion_in_engine(meta["engine"]):
        # (orientations and spins are None while the table would not store them)
        motion = dict(zip(MOTION_FIELDS, world.bodies.stored_motion(), strict=True))
    motion["inertia_tensor"] = world.bodies.stored_tensors  # None: every body a sphere
    arrays |= {f"body.{name}": value for name, value in motion.items() if value is not None}
    for name in BODY_FIELDS:
        arrays[f"body.{name}"] = getattr(world.bodies, name)
    pieces = pieces_to_arrays(world.bodies.pieces, world.dim)
    arrays |= {f"pieces.{k}": v for k, v in pieces.items()}
    if engine is not None:
        arrays |= {f"engine.{k}": v for k, v in engine.arrays().items()}
    arrays["log"] = world.collisions
    filters = getattr(world, "collision_filters", None)  # (a World's, issue 43)
    if filters is not None and len(filters):
        arrays["filters"] = filters
        arrays["alive"] = world.alive  # type: ignore[attr-defined]
    sensors = getattr(world, "sensors", None)
    sensor_pieces = getattr(world, "sensor_pieces", np.zeros((0, 2), np.int64))
    if sensors is not None and (np.any(sensors) or len(sensor_pieces)):
        arrays["sensors"] = sensors
        arrays["sensor_pieces"] = sensor_pieces
    if getattr(world, "n_joints", 0):  # the joints, their impulses too (to go on bit for bit)
        arrays["joints.ints"], arrays["joints.floats"] = world.joint_rows  # type: ignore[attr-defined]
    arrays |= {f"extra.{k}": v for k, v in extra.items()}
    tmp = path.with_name(path.name + ".partial")
    with tmp.open("wb") as handle:
        np.savez(handle, **arrays)
    tmp.replace(path)


def load_world(path: Path, make: Callable[..., W]) -> tuple[W, dict[str, NDArray[Any]]]:
    """The world saved by :func:`save_world` at ``path``, made again by ``make`` (the World
    class, called as ``World(dim, box, ...)``), and its ``extra`` arrays."""
    try:
        handle = path.open("rb")
    except OSError as exc:
        raise CaromError(f"cannot read checkpoint {path}: {exc.strerror}") from None
    with handle:
        try:
            data = np.load(handle, allow_pickle=False)
        except (OSError, ValueError, EOFError, zipfile.BadZipFile) as exc:
            raise CaromError(f"cannot read checkpoint {path}: {exc}") from None
        try:
            with data:
                return _read(path, data, make)
        except CaromError:
            raise
        except (KeyError, ValueError, OSError, zipfile.BadZipFile, EOFError) as exc:
            raise CaromError(
                f"checkpoint {path} is damaged or incomplete ({type(exc).__name__}: {exc}); "
                f"start the run again"
            ) from None


def _read(path: Path, data: Any, make: Callable[..., W]) -> tuple[W, dict[str, NDArray[Any]]]:
    meta = json.loads(str(data["meta"]))
    _check_version(path, meta)
    kept = (
        meta["engine_settings"]
        if meta["version"] > 12
        else {"edmd": meta["settings"], "rigid": meta["rigid"]}
    )
    settings = {}
    for name, values in kept.items():
        kind = registry.find(name).settings
        if kind is not None:
            settings[name] = kind(**values)
    world = make(
        meta["dim"],
        meta["box"],
        meta["boundary"],
        meta["gravity"],
        walls=[Material(**m) for m in meta["walls"]],
        combine=meta["combine"],
        engine=meta["engine_choice"],
        settings=settings,
    )
    for m in meta["materials"]:
        world.add_material(Material(**m))
    for a, b, e in meta["pair_overrides"]:
        world.set_pair(a, b, e)
    for p, q, m in meta["planes"]:
        world.add_plane(p, q, material=Material(**m))
    for name in BODY_FIELDS:
        setattr(world.bodies, name, data[f"body.{name}"])
    if "body.inertia_tensor" in data:
        world.bodies.inertia_tensor = data["body.inertia_tensor"]
    for name in MOTION_FIELDS if not _motion_in_engine(meta["engine"]) else ():
        # (identities and zeros are not written: a table without them stores none)
        if name in ("position", "velocity") or f"body.{name}" in data:
            setattr(world.bodies, name, data[f"body.{name}"])
    world.bodies.pieces = pieces_from_arrays(
        {k: data[f"pieces.{k}"] for k in PIECE_ARRAYS}, world.bodies.n
    )
    engine = _Members(data, "engine.")
    world.restore(
        meta["time"],
        engine if meta["engine"] is not None else None,
        Counters(*meta["counters_before"]),
        data["log"],
        meta["collisions_dropped"],
        meta["engine"],
    )
    if "filters" in data.files:
        world.restore_filters(data["filters"], data["alive"])  # type: ignore[attr-defined]
    if "sensors" in data.files:
        pieces = data["sensor_pieces"] if "sensor_pieces" in data.files else None
        world.restore_sensors(data["sensors"], pieces)  # type: ignore[attr-defined]
    if "joints.ints" in data.files:
        world.restore_joints(data["joints.ints"], data["joints.floats"])  # type: ignore[attr-defined]
    extra = {k[len("extra.") :]: data[k] for k in data.files if k.startswith("extra.")}
    return world, extra


def _motion_in_engine(engine: str | None) -> bool:
    """Whether the engine's arrays hold the bodies' motion, so that the file holds no copy
    of it (its entry's ``motion_in_arrays``): the event-driven engine's state does, and lends
    it to the table while it runs (:meth:`carom.bodies.Bodies.lend`). The stepped engines
    assemble their model from the table's positions before they restore their own arrays,
    so theirs is written."""
    return engine is not None and registry.find(engine).motion_in_arrays


def _check_version(path: Path, meta: dict[str, Any]) -> None:
    if meta.get("format") == "carom-world":  # what carom wrote before version 4
        raise CaromError(
            f"checkpoint {path} was written by an older carom (format 'carom-world', version "
            f"{meta.get('version')}); this carom reads {FORMAT} version {VERSION}: re-run the "
            f"simulation, or load it with the carom that wrote it"
        )
    if meta.get("format") != FORMAT:
        raise CaromError(f"{path} is not a carom checkpoint")
    if meta.get("version") not in READS:
        raise CaromError(
            f"checkpoint {path} has format version {meta.get('version')}, this carom reads "
            f"version {VERSION}; re-run the simulation with this version, or load it with the "
            f"carom that wrote it"
        )
    engine = meta.get("engine")
    if engine is not None and not (isinstance(engine, str) and registry.known(engine)):
        raise CaromError(f"checkpoint {path} is of engine {engine!r}, unknown here")


class _Members(Mapping[str, NDArray[Any]]):
    """The arrays of an open ``.npz`` file whose names start with ``prefix``, by the rest of
    their names, each read from the file when it is asked for: an engine restoring itself
    can then let go of one array (made again in its own layout) before it reads the next."""

    def __init__(self, data: Any, prefix: str) -> None:
        self._data = data
        self._prefix = prefix
        self._names = [k[len(prefix) :] for k in data.files if k.startswith(prefix)]

    def __getitem__(self, name: str) -> NDArray[Any]:
        if name not in self._names:
            raise KeyError(name)
        value: NDArray[Any] = self._data[self._prefix + name]
        return value

    def __contains__(self, name: object) -> bool:
        return name in self._names

    def __iter__(self) -> Iterator[str]:
        return iter(self._names)

    def __len__(self) -> int:
        return len(self._names)
