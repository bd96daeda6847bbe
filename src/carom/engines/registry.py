"""The engines a :class:`carom.World` can run: one table, one entry an engine.

An entry says what the engine is called (the one name a World, a scene file, a checkpoint, the
trajectory files and the plots all use), which worlds it takes, and where the module that
builds it lives, one per dimension. That module (its *plug*) offers three functions, and the
World calls nothing else of it:

- ``refuses(world) -> str | None``: None when the engine can run ``world`` (a
  :class:`~carom.engines.base.WorldView`), else why not, in a sentence that says what to
  change; ``engine="auto"`` takes the first engine of the table that does not refuse;
- ``build(world) -> Engine``: the engine, started from the world's bodies at its clock, or a
  :class:`~carom.errors.CaromError` naming what it cannot start from (an overlap, a body
  outside the box);
- ``restore(world, arrays) -> Engine``: the engine that wrote ``arrays``
  (:meth:`~carom.engines.base.Engine.arrays`) into a checkpoint of ``world``, continuing bit
  for bit.

A new engine is a package of its own and one :func:`register` call; nothing else in carom
names it. The built-in engines are the table's first rows (Box2D and Rapier keep one solver
each; carom keeps an exact one beside a stepped one, and "auto" tries the exact one first).

>>> [entry.name for entry in engines()][:2]
['edmd', 'rigid']
>>> find("event-driven").name
'edmd'
"""

from __future__ import annotations

import importlib
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, Protocol, cast

from numpy.typing import NDArray

from carom.errors import CaromError

if TYPE_CHECKING:
    from carom.engines.base import Engine, WorldView

__all__ = [
    "AUTO",
    "EngineEntry",
    "Plug",
    "engine_choices",
    "engines",
    "find",
    "known",
    "pick",
    "register",
    "unregister",
]

#: the choice that lets the World pick: the first engine of the table that takes the world
AUTO = "auto"


class Plug(Protocol):
    """What an engine's plug module offers (see the module's docstring)."""

    def refuses(self, world: WorldView) -> str | None: ...

    def build(self, world: WorldView) -> Engine: ...

    def restore(self, world: WorldView, arrays: Mapping[str, NDArray[Any]]) -> Engine: ...


@dataclass(frozen=True)
class EngineEntry:
    """One engine of the table.

    Attributes
    ----------
    name : str
        Its one name: ``World(engine=...)``, ``[world] engine`` in a scene file, checkpoints,
        trajectory files, reports.
    title : str
        What it is, for help texts and reports ("event-driven", "time-stepped rigid-body").
    plugs : mapping of int to str
        The module that builds it in each dimension it runs (2, 3).
    settings : type, optional
        The dataclass of its settings (a World keeps one, :attr:`carom.World.engine_settings`);
        None: it has none.
    aliases : tuple of str
        Older spellings still read (scene files, checkpoints written before the table).
    stepped : bool
        Whether it advances by fixed steps (its settings' ``dt`` [s]); an event-driven engine
        stops at any time.
    turns : bool
        Whether bodies may turn without spinning at the start (rigid bodies in orbit), so
        that the reports keep an angular momentum panel.
    kinematic : bool
        Whether it moves kinematic bodies, whose work the energy ledger counts.
    gives_energy : str
        What the counter ``energy_given`` counts in reports ("solver", "parting floor").
    motion_in_arrays : bool
        Whether its checkpoint arrays hold the bodies' positions and velocities, so that the
        body table's copy is not written (:mod:`carom.checkpoint`).
    """

    name: str
    title: str
    plugs: Mapping[int, str]
    settings: type | None = None
    aliases: tuple[str, ...] = ()
    stepped: bool = False
    turns: bool = False
    kinematic: bool = False
    gives_energy: str = "engine"
    motion_in_arrays: bool = False
    _loaded: dict[int, Plug] = field(default_factory=dict, compare=False, repr=False)

    @property
    def dims(self) -> tuple[int, ...]:
        """The dimensions it runs."""
        return tuple(sorted(self.plugs))

    def _other_dims(self, dim: int) -> str | None:
        """None when it runs ``dim`` dimensions, else why not."""
        if dim in self.plugs:
            return None
        dims = " and ".join(f"{d}D" for d in self.dims)
        return f"the {self.title} engine ({self.name!r}) runs {dims} worlds only"

    def plug(self, dim: int) -> Plug:
        """Its plug module for ``dim`` dimensions (imported on first use)."""
        why = self._other_dims(dim)
        if why is not None:
            raise CaromError(why)
        if dim not in self._loaded:
            self._loaded[dim] = cast(Plug, importlib.import_module(self.plugs[dim]))
        return self._loaded[dim]

    def refuses(self, world: WorldView) -> str | None:
        """None when this engine can run ``world``, else why not."""
        return self._other_dims(world.dim) or self.plug(world.dim).refuses(world)


_TABLE: dict[str, EngineEntry] = {}


def _lookup(name: str) -> EngineEntry | None:
    """The engine called ``name`` or by one of its older spellings, if any."""
    for entry in _TABLE.values():
        if name == entry.name or name in entry.aliases:
            return entry
    return None


def register(entry: EngineEntry) -> EngineEntry:
    """Add ``entry`` to the table (after the built-in engines: "auto" tries them first);
    return it. A name or alias already taken is refused."""
    clash = sorted(n for n in (entry.name, *entry.aliases) if known(n))
    if clash:
        raise CaromError(f"engine name {clash[0]!r} is taken; register the engine under another")
    _TABLE[entry.name] = entry
    return entry


def unregister(name: str) -> None:
    """Remove the engine ``name`` that :func:`register` added (the built-in ones stay)."""
    if name in _BUILT_IN:
        raise CaromError(f"the built-in engine {name!r} cannot be removed")
    _TABLE.pop(name, None)


def engines() -> tuple[EngineEntry, ...]:
    """Every engine, in the order "auto" tries them."""
    return tuple(_TABLE.values())


def engine_choices() -> tuple[str, ...]:
    """What ``World(engine=...)`` and a scene's ``[world] engine`` take: "auto" and every
    engine's name."""
    return (AUTO, *_TABLE)


def known(choice: str) -> bool:
    """Whether ``choice`` is "auto", an engine's name or one of its older spellings."""
    return choice == AUTO or _lookup(choice) is not None


def find(name: str) -> EngineEntry:
    """The engine called ``name`` (or by one of its older spellings), or a CaromError that
    lists the names there are."""
    entry = _lookup(name)
    if entry is None:
        raise CaromError(f"no engine {name!r}; the engines are {', '.join(map(repr, _TABLE))}")
    return entry


def pick(choice: str, world: WorldView) -> EngineEntry:
    """The engine that runs ``world`` for the choice ``choice`` ("auto" or a name); a
    CaromError says why the chosen engine, or every engine, refuses it."""
    if choice != AUTO:
        entry = find(choice)
        why = entry.refuses(world)
        if why is not None:
            raise CaromError(why)
        return entry
    reasons = []
    for entry in _TABLE.values():
        why = entry.refuses(world)
        if why is None:
            return entry
        reasons.append(why)
    raise CaromError("no engine runs this world: " + "; ".join(reasons))


# -- the built-in engines ---------------------------------------------------------------------


def _built_in() -> tuple[EngineEntry, ...]:
    from carom.engines.edmd.settings import EdmdSettings
    from carom.engines.stepped.settings import RigidSettings

    edmd = "carom.engines.edmd.assemble"
    return (
        EngineEntry(
            "edmd",
            "event-driven",
            {2: edmd, 3: edmd},
            EdmdSettings,
            aliases=("event-driven",),
            gives_energy="parting floor",
            motion_in_arrays=True,
        ),
        EngineEntry(
            "rigid",
            "time-stepped rigid-body",
            {2: "carom.engines.rigid.assemble", 3: "carom.engines.rigid3d.assemble"},
            RigidSettings,
            aliases=("rigid3d",),
            stepped=True,
            turns=True,
            kinematic=True,
            gives_energy="solver",
        ),
    )


_BUILT_IN = frozenset(register(entry).name for entry in _built_in())
