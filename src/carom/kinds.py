"""Switching a body's kind between steps (issue 43, item 2), as Box2D's ``b2Body_SetType``.

:class:`Kinds` is the part of :class:`carom.World` that turns a dynamic body static (a crate
nailed down), kinematic (a platform taken over by the game) or back: ``world.set_kind(ids,
kind)``, or ``world.body(i).kind = "static"``. A body made static stops; a kinematic one keeps
its velocity and spin and moves at them whatever it meets; one made dynamic takes its mass
from ``density`` or ``mass``, else the mass it had when it was last dynamic, else density 1.
The mechanical energy the switched bodies gain or lose (a dynamic body's kinetic and
gravitational energy enters or leaves the count) is booked as work done, so the ledger closes.
The engine is built again with the new kinds, as when bodies are added between steps (the
state, the forces given for the next step, the warm starts and the sleep of the bodies left
alone are kept: :func:`carom.engines.stepped.memory.carried`). The
event-driven engine switches its spheres between dynamic and static the same way (it has no
kinematic bodies): a sphere made static stops at the clock, one made dynamic flies from there.

>>> import carom
>>> from carom.shapes import Box
>>> world = carom.World(2, [10.0, 10.0], gravity=[0.0, -9.81], boundary="open")
>>> crate = world.add_body(Box(1.0, 1.0), [5.0, 5.0])
>>> world.step()
>>> world.body(crate).kind = "static"
>>> world.step()
>>> world.velocities[crate].tolist()
[0.0, 0.0]
"""

from __future__ import annotations

import math
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from carom.body_input import dynamic_mass
from carom.engines.base import Counters
from carom.engines.edmd.driver import EdmdEngine
from carom.errors import CaromError
from carom.gameloop import _reachable, _rows, _Running
from carom.laws.kinds import BODY_KINDS, KIND_DYNAMIC, KIND_KINEMATIC, KIND_STATIC
from carom.shape_base import SHAPE_CODES
from carom.shapes import Circle, Shape2D
from carom.shapes3d import Shape3D, Sphere

__all__ = ["Kinds"]

#: shapes that can only be static: they have no area or volume, or are a surface
_STATIC_ONLY = {SHAPE_CODES["segment"], SHAPE_CODES["chain"], SHAPE_CODES["mesh"]}


class _Stored:
    """A stored body's pieces as a shape, for its mass properties."""

    kind = "body"

    def __init__(self, pieces: tuple[Any, ...]) -> None:
        self._pieces = pieces

    def pieces(self) -> tuple[Any, ...]:
        return self._pieces


class _Pieces2D(_Stored, Shape2D):
    """A 2D body's pieces as a shape."""


class _Pieces3D(_Stored, Shape3D):
    """A 3D body's pieces as a shape."""


class _World(_Running, Protocol):
    """What :class:`Kinds` takes from the World it is part of."""

    _counters_before: Counters
    _time: float

    def _invalidate(self) -> None: ...

    def _masses(
        self, rows: NDArray[np.int64], code: int, density: float | None, mass: float | None
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]: ...


class Kinds:
    """Switching bodies between dynamic, kinematic and static: mixed into
    :class:`carom.World`."""

    def set_kind(
        self: _World,
        ids: int | ArrayLike,
        kind: str,
        *,
        density: float | None = None,
        mass: float | None = None,
    ) -> None:
        """Make bodies ``ids`` ``kind`` from the next step on.

        Parameters
        ----------
        ids : int or (k,) array_like of int
            Body indices.
        kind : {"dynamic", "kinematic", "static"}
            A static body stops and never moves; a kinematic one moves at its velocity and
            spin whatever it meets; a dynamic one falls and collides.
        density, mass : float, optional
            For bodies made dynamic: [kg/m^2] (2D) or [kg/m^3] (3D), or [kg] each, one of
            them. Left out: the mass a body had when it was last dynamic, else density 1.

        Raises
        ------
        CaromError
            An index out of range or removed; an unknown kind; a mass for bodies not made
            dynamic; a segment, chain or mesh made anything but static; a kinematic body in
            the event-driven engine. Nothing has changed then.
        """
        if kind not in BODY_KINDS:
            raise CaromError(f"kind must be one of {tuple(BODY_KINDS)}; got {kind!r}")
        code = BODY_KINDS[kind]
        if code != KIND_DYNAMIC and (density is not None or mass is not None):
            raise CaromError(
                f"a {kind} body is not moved by impacts and has no mass; drop density= and "
                "mass=, or make it dynamic"
            )
        rows = np.unique(_rows(self, np.atleast_1d(np.asarray(ids))))
        engine = _reachable(self)
        if isinstance(engine, EdmdEngine) and code == KIND_KINEMATIC:
            raise CaromError(
                "the event-driven engine's spheres are dynamic or static: none moves at a "
                'velocity of its own whatever it meets (a kinematic body: engine="rigid")'
            )
        table = self.bodies
        for i in rows.tolist():
            if code != KIND_STATIC and int(table.shape[i]) in _STATIC_ONLY:
                raise CaromError(
                    f"body {i} is a segment, chain or mesh: a surface, static only; a body "
                    "of it that moves needs an area or volume (a Polygon, a Hull)"
                )
        if np.all(table.kind[rows] == code) and density is None and mass is None:
            return  # (nothing to switch: the engine is not built again)
        masses, inertias = self._masses(rows, code, density, mass)
        before = engine.energy_of(rows)
        kept = _kept_of(self)
        undo = (dict(kept), table.kinds_kept(), self._counters_before, self._time)
        for i in rows.tolist():
            if table.kind[i] == KIND_DYNAMIC and code != KIND_DYNAMIC:
                kept[i] = (float(table.mass[i]), _inertia_of(table, i))
        try:
            self._invalidate()  # (the table takes the engine's state; it is built again)
            table.switch_kind(rows, code, masses, inertias)
            if code == KIND_STATIC:  # it stops
                velocity, spin = table.velocity.copy(), table.angular_velocity.copy()
                velocity[rows] = 0.0
                spin[rows] = 0.0
                table.set_state(table.position, velocity, table.orientation, spin)
            built = _reachable(self)  # (refused: a body made dynamic deep in another)
        except BaseException:
            kept.clear()
            kept.update(undo[0])
            table.restore_kinds(undo[1])
            # the engine as it was, never told
            self.__dict__.update(
                _engine=engine, _counters_before=undo[2], _time=undo[3], _loads_kept=None,
                _memory_kept=None,
            )  # fmt: skip
            raise
        built.book_work(built.energy_of(rows) - before)

    def _masses(
        self: _World, rows: NDArray[np.int64], code: int, density: float | None,
        mass: float | None,
    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:  # fmt: skip
        """The masses (k,) [kg] and inertias ((k,) or (k, 3, 3)) [kg m^2] bodies ``rows``
        take as kind ``code``."""
        k, dim = rows.shape[0], self.dim
        if code != KIND_DYNAMIC:
            inertia = (
                np.full(k, math.inf) if dim == 2 else np.tile(np.diag([math.inf] * 3), (k, 1, 1))
            )
            return np.full(k, math.inf), inertia
        table, kept = self.bodies, _kept_of(self)
        masses = np.empty(k)
        inertias = np.empty(k) if dim == 2 else np.empty((k, 3, 3))
        for r, i in enumerate(rows.tolist()):
            if table.kind[i] == KIND_DYNAMIC and density is None and mass is None:
                masses[r], inertias[r] = table.mass[i], _inertia_of(table, i)
                continue
            if i in kept and density is None and mass is None:
                masses[r], inertias[r] = kept[i]
                continue
            pieces = table.pieces[i]
            shape: Shape2D | Shape3D
            if not pieces:  # a sphere: its radius
                shape = (
                    Circle(float(table.radius[i])) if dim == 2 else Sphere(float(table.radius[i]))
                )
            else:
                shape = _Pieces2D(tuple(pieces)) if dim == 2 else _Pieces3D(tuple(pieces))
            body_mass, moment, _ = dynamic_mass(shape, density, mass)
            masses[r], inertias[r] = body_mass, moment
        return masses, inertias


def _inertia_of(table: Any, i: int) -> Any:
    """Body ``i``'s inertia as the table keeps it: a moment [kg m^2] in 2D, the body-frame
    tensor (3, 3) in 3D."""
    if table.dim == 2:
        return float(table.inertia[i])
    return np.array(table.inertia_tensor[i])


def _kept_of(world: Any) -> dict[int, tuple[float, Any]]:
    """The masses and inertias bodies had when last dynamic, by index (a world's)."""
    kept: dict[int, tuple[float, Any]] = world.__dict__.setdefault("_dynamic_masses", {})
    return kept
