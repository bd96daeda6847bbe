"""A world a game drives, frame by frame: :meth:`GameLoop.step` (issue 43).

A game loop advances the world by one frame at a time and reaches into it between frames.
:class:`GameLoop` is the part of :class:`carom.World` that does that: ``world.step()`` takes
one step of the engine's own length (the rigid engines' ``1 / rate``), ``world.step(dt)`` one
of any length, and :attr:`GameLoop.steps` counts them. Stepping by hand and ``run`` take the
same steps, so they give the same bits at the same times. Between steps, ``world.body(i)``
reads and sets a body's motion and takes impulses, and forces and torques for the next step;
``world.apply_impulses``, ``world.apply_forces``, ``world.apply_torques``,
``world.set_velocities``, ``world.set_positions`` and ``world.set_angular_velocities`` do so
for many bodies in one call. The event-driven engine takes all but torques (its spheres keep
their spin between impacts), at its clock, and predicts the changed bodies' events again; a
force it takes through the next step, its spheres flying the parabolas of ``g + F / m``.

>>> import carom
>>> from carom.shapes import Box
>>> world = carom.World(2, [10.0, 10.0], gravity=[0.0, -9.81], boundary="open")
>>> _ = world.add_body(Box(1.0, 1.0), [5.0, 5.0])
>>> for frame in range(60):
...     world.step()
>>> world.steps, round(world.time, 12)
(60, 1.0)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from carom.bodies import Bodies
from carom.engines.base import Engine
from carom.engines.edmd.driver import EdmdEngine
from carom.engines.registry import EngineEntry
from carom.engines.stepped.driver import SteppedEngine
from carom.engines.stepped.events import EventArrays
from carom.engines.stepped.filters import bits64, default_filters, whole_number
from carom.engines.stepped.memory import Remembered
from carom.errors import CaromError
from carom.laws.kinds import KIND_DYNAMIC, KIND_NAMES
from carom.limits import LARGEST

__all__ = ["Body", "EventArrays", "GameLoop"]


class _Running(Protocol):
    """What :class:`GameLoop` takes from the World it is part of."""

    reached: bool

    @property
    def time(self) -> float: ...

    @property
    def engine(self) -> Engine | None: ...

    @property
    def dim(self) -> int: ...

    @property
    def n_bodies(self) -> int: ...

    @property
    def bodies(self) -> Bodies: ...

    @property
    def engine_entry(self) -> EngineEntry: ...

    def build(self) -> Engine: ...

    def _sink(
        self, log: bool | Any, stream: Callable[[NDArray[Any]], object] | None
    ) -> Callable[[NDArray[Any]], None] | None: ...


#: the attribute in which a world keeps its event-driven engine and the steps taken on it
_HAND = "_hand_steps"
#: the attribute in which a world keeps its hit threshold [m/s]
_THRESHOLD = "_hit_threshold"
#: the attribute that says contact events were asked for (the event-driven engine logs its
#: steps' collisions from then on, through rebuilds)
_ASKED = "_events_asked"
#: the attribute in which a world keeps the loads of an engine it dropped (World._invalidate)
_LOADS_KEPT = "_loads_kept"
#: the attribute in which a world keeps the sleep and warm starts of an engine it dropped
_MEMORY_KEPT = "_memory_kept"


class GameLoop:
    """Stepping a :class:`carom.World` by hand, one frame at a time."""

    def step(self: _Running, dt: float | None = None) -> None:
        """Advance the world by one step.

        Parameters
        ----------
        dt : float, optional
            The step [s]. By default the engine's own: the rigid engines' ``1 / rate``; the
            event-driven engine has none and needs one. The rigid engines take another
            ``dt`` as one step of that length in every stage (as Box2D's ``b2World_Step``
            takes the frame's time); the clock's origin moves to where it ends, and later
            steps are whole steps from there. The event-driven engine advances exactly
            ``dt``, every impact on the way at its own time.

        Raises
        ------
        CaromError
            ``dt`` not a positive finite time, shorter than a millionth of the engine's step,
            or reaching past carom's largest time; no ``dt`` for the event-driven engine.
            Nothing has moved then.
        """
        engine = self.build()
        sink = self._sink(False, None)
        if isinstance(engine, SteppedEngine):
            step = engine.dt if dt is None else _positive_time(dt)
            if step < 1e-6 * engine.dt:
                raise CaromError(
                    f"dt = {step:g} s is under a millionth of the engine's step "
                    f"({engine.dt:g} s); take dt >= {1e-6 * engine.dt:g} s"
                )
            _within_limits(step, self.time)
            events = engine.events
            events.threshold = float(getattr(self, _THRESHOLD, 1.0))
            events.on = True
            engine.step_of(step, sink)
            self.reached = True
            return
        if dt is None:
            raise CaromError(
                "the event-driven engine has no step of its own: give the time to advance, "
                "e.g. world.step(1 / 60) [s]"
            )
        step = _positive_time(dt)
        _within_limits(step, self.time)
        # contact events, once asked for (contact_events): the step's collisions, gathered
        asked = getattr(self, _ASKED, False)  # (else the steps log nothing)
        met = engine.events if isinstance(engine, EdmdEngine) and asked else None
        if met is not None:
            met.threshold = float(getattr(self, _THRESHOLD, 1.0))
            met.gathering = True
            sink = sink or _no_sink  # (the engine logs its collisions only for a sink)
        try:
            if isinstance(engine, EdmdEngine):  # (with the forces given for this step)
                self.reached = engine.advance_step(self.time + step, sink)
            else:
                self.reached = engine.advance(self.time + step, np.iinfo(np.int64).max, sink)
        finally:
            if met is not None:
                met.gathering = False
        if met is not None:
            met.close(np.flatnonzero(engine.resting() >= 0))
        kept, count = getattr(self, _HAND, (None, 0))
        setattr(self, _HAND, (engine, (count if kept is engine else 0) + 1))

    def contact_events(self: _Running) -> EventArrays:
        """The contact events of the last step (the rigid engines), as NumPy structured
        arrays: no Python object a contact.

        Returns
        -------
        EventArrays
            ``begin``: pairs that began touching (``a``, ``b``, ``point`` (d,) [m], ``normal``
            (d,) from a to b); ``end``: pairs that stopped (``a``, ``b``); ``hit``: impacts
            approaching at least :attr:`hit_threshold` (``a``, ``b``, ``time`` [s], ``point``,
            ``normal``, ``speed`` [m/s], the approach speed along the normal). Bodies are the
            world's indices, ``a < b``; -1 is a wall or plane of the world's scenery
            (its box, :meth:`add_plane`).

        Notes
        -----
        A pair touches when a point of its contact lies within the linear slop (the soft
        contacts rest a little inside it), or when the two met in an impact solved exactly
        during the step: such a pair touches in that step, and ends in the next if it bounced
        apart. An impact solved exactly is a hit at its own time; a solver contact is a hit
        when it pushed and its points approached at least the threshold at the step's start.
        Gathered by :meth:`step` (a game loop's steps) and, once this has been called, by
        every step (``run`` and ``frames``, which otherwise do not pay for them). Empty before
        the first step gathered; that step's ``begin`` holds every pair touching then.

        The event-driven engine gathers them in the steps after this is first called: hard
        spheres touch for an instant, so a pair that collides begins, ends and (fast enough)
        hits in that step; a sphere that comes to rest on a wall or plane touches the scenery
        (-1) until it lifts off.
        """
        engine = self.build()
        if not isinstance(engine, SteppedEngine | EdmdEngine):
            raise CaromError(_NOT_YET_EVENTS)
        if isinstance(engine, SteppedEngine):
            engine.events.on = True
        setattr(self, _ASKED, True)
        return engine.events.last

    @property
    def hit_threshold(self: _Running) -> float:
        """The least approach speed [m/s] of a hit event (default 1 m/s, as Box2D's)."""
        return float(getattr(self, _THRESHOLD, 1.0))

    @hit_threshold.setter
    def hit_threshold(self: _Running, speed: float) -> None:
        value = _positive_time(speed, "hit_threshold", "speed [m/s]")
        setattr(self, _THRESHOLD, value)
        engine = self.engine
        if engine is not None and isinstance(engine, SteppedEngine):
            engine.events.threshold = value

    @property
    def steps(self: _Running) -> int:
        """Steps taken since the engine was built: every step of the rigid engines (by
        :meth:`step`, ``run``, ``frames`` or ``record``); the calls of :meth:`step` for the
        event-driven engine, whose runs take no steps. 0 before the engine is built."""
        engine = self.engine
        if engine is None:
            return 0
        if isinstance(engine, SteppedEngine):
            return engine.steps
        kept, count = getattr(self, _HAND, (None, 0))
        return int(count) if kept is engine else 0

    # -- reaching bodies between steps ------------------------------------------------------

    def hand_over_loads(self: _Running) -> tuple[NDArray[np.float64], NDArray[np.float64]] | None:
        """The forces and torques given for the next step to an engine this world dropped to
        build it again (bodies added, kinds switched), once: for the new engine
        (:func:`carom.engines.stepped.assemble.checked_start`); None when there are none."""
        kept: tuple[NDArray[np.float64], NDArray[np.float64]] | None = _once(self, _LOADS_KEPT)
        return kept

    def hand_over_memory(self: _Running) -> Remembered | None:
        """The sleep and warm starts of the rigid engine this world dropped to build it again,
        once: for the new engine (:func:`carom.engines.stepped.assemble.checked_start`,
        :func:`carom.engines.stepped.memory.carried`); None when there are none."""
        kept: Remembered | None = _once(self, _MEMORY_KEPT)
        return kept

    def body(self: _Running, index: int) -> Body:
        """A light handle on body ``index`` (:class:`Body`): read and set its motion, push it."""
        return Body(self, _index(self, index))

    def apply_impulses(
        self: _Running, ids: ArrayLike, impulses: ArrayLike, points: ArrayLike | None = None
    ) -> None:
        """Impulses on many dynamic bodies at once, in order (a body may appear twice).

        Parameters
        ----------
        ids : (k,) array_like of int
            Body indices.
        impulses : (k, d) or (d,) array_like
            Impulses [N s] (one for all when (d,)).
        points : (k, d) or (d,) array_like, optional
            World points where they act [m]; at each centre of mass when left out (no spin).

        Raises
        ------
        CaromError
            An index out of range, a body not dynamic, a value not finite or beyond carom's
            limits, a shape that does not fit; an impulse off the centre of a sphere of the
            event-driven engine that keeps no spins. Nothing has changed then.
        """
        engine = self.build()
        if isinstance(engine, SteppedEngine):
            given = _plain(self, ids, impulses, points)
            if given is not None and engine.apply_impulses(*given, _alive_of(self)):
                return
        # something is wrong (or given in an unusual form): the checks that say what
        reached, rows = _dynamic_rows(self, ids, "impulses")
        j = _vectors(self, "impulses", impulses, rows.size)
        at = None if points is None else _vectors(self, "points", points, rows.size)
        reached.apply_impulses(rows, j, at)

    def apply_forces(
        self: _Running, ids: ArrayLike, forces: ArrayLike, points: ArrayLike | None = None
    ) -> None:
        """Forces on many dynamic bodies through the next step, then cleared (as Box2D's
        ``b2Body_ApplyForce``); given twice, they add up.

        Parameters
        ----------
        ids : (k,) array_like of int
            Body indices.
        forces : (k, d) or (d,) array_like
            Forces [N] (one for all when (d,)).
        points : (k, d) or (d,) array_like, optional
            World points where they act [m] now; at each centre of mass when left out (no
            torque). The arm is taken now and kept through the step.

        Notes
        -----
        The force is constant through the step. Free flight stays exact under it (the
        centre follows ``x + v t + (g + F / m) t^2 / 2``); the solver takes it each substep,
        as it takes gravity. Its work is booked in the energy ledger. The event-driven
        engine flies its spheres on that parabola through the next :meth:`step`, exactly
        (:meth:`carom.engines.edmd.driver.EdmdEngine.advance_step`); having no step of its
        own, it keeps them for that call (a ``run`` in between leaves them waiting).

        Raises
        ------
        CaromError
            As :meth:`apply_impulses`; in the event-driven engine, a force off a sphere's
            centre (it would turn it: torques are the rigid engines').
        """
        engine, rows = _dynamic_rows(self, ids, "forces")
        f = _vectors(self, "forces", forces, rows.size)
        at = None if points is None else _vectors(self, "points", points, rows.size)
        if isinstance(engine, SteppedEngine):
            engine.apply_forces(rows, f, at)
            return
        if at is not None:  # (taken when on the force's line through the centre)
            flat = ((0, 0), (0, 3 - self.dim))
            arm = np.pad(at - engine.motion_of(rows)[0], flat)
            if np.any(np.cross(arm, np.pad(f, flat)) != 0.0):
                raise CaromError(_NO_TORQUES.format("a force off a sphere's centre"))
        engine.apply_forces(rows, f)

    def apply_torques(self: _Running, ids: ArrayLike, torques: ArrayLike) -> None:
        """Torques on many dynamic bodies through the next step, then cleared: (k,) or one
        number in 2D, (k, 3) or (3,) (world axes) in 3D [N m]. As :meth:`apply_impulses` for
        what is refused."""
        engine = _rigid(self, _NO_TORQUES.format("a torque"))
        _, rows = _dynamic_rows(self, ids, "torques")
        shape: tuple[int, ...] = () if self.dim == 2 else (3,)
        engine.apply_torques(rows, _vectors(self, "torques", torques, rows.size, shape))

    def set_filter(
        self: _Running,
        ids: int | ArrayLike,
        *,
        category: int | None = None,
        mask: int | None = None,
        group: int | None = None,
    ) -> None:
        """Which bodies ``ids`` touch (Box2D's ``b2Filter``); what is left out is kept.

        Parameters
        ----------
        ids : int or (k,) array_like of int
            Body indices (any kind).
        category : int, optional
            The bits the bodies are, 0 to 2**64 - 1, or a signed 64-bit integer (two's
            complement: -1 is every bit, ``~0b10`` all but bit 1) (default for every body: 1).
        mask : int, optional
            The bits they touch (default: all).
        group : int, optional
            Two bodies of the same nonzero group always touch when it is positive and never
            when it is negative, whatever their bits (default 0: the bits decide).

        Notes
        -----
        Two bodies touch when each one's mask holds a bit of the other's category. A pair
        kept apart has no contact, no impact and no sweep against the other: it passes
        through. Filters hold from the next step, through rebuilds and runs; bodies added
        later start with the defaults. Set before the engine is built, they are its from the
        start (bodies kept apart may start overlapping). The rigid engines.

        Raises
        ------
        CaromError
            An index out of range; bits not a whole number in range; the event-driven
            engine. Nothing has changed then.
        """
        rows = _rows(self, np.atleast_1d(np.asarray(ids)))
        values = [
            None if category is None else bits64("category", category),
            None if mask is None else bits64("mask", mask),
            None if group is None else whole_number("group", group, -(2**63), 2**63 - 1),
        ]
        engine = rigid_if_built(self)
        table = _filters_of(self)
        for column, value in enumerate(values):
            if value is not None:
                table[rows, column] = value
        if engine is not None:
            engine.use_filters(table, rows)

    def remove_body(self: _Running, index: int) -> None:
        """Take body ``index`` out of the world; every other body keeps its index.

        The body stops where it is and never moves again; nothing touches it, no ray sees it,
        and its index is refused from then on (:attr:`alive` says which bodies are in). The
        kinetic energy it had leaves the ledger as work done on it. Its place in the arrays
        (positions, frames) stays, frozen. In the event-driven engine it stops at the clock,
        and every sphere flies through its place from then on. A body whose addition the
        rigid engine refused (added deep in another) can be taken out this way before the
        next step: the engine built then takes the running one's sleep and warm starts.

        Raises
        ------
        CaromError
            An index out of range or already removed. Nothing has changed then.
        """
        i = _index(self, index)
        if self.engine is None and self.engine_entry.stepped:
            # a rigid engine not built (or refused: this body was added deep in another):
            # the next one built takes the filters and the mask, and retires the body
            _filters_of(self)[i] = 0
            _alive_of(self)[i] = False
            return
        built = self.build()
        if isinstance(built, EdmdEngine):
            built.retire(np.array([i]))
            _alive_of(self)[i] = False
            return
        engine = _rigid(self)
        table = _filters_of(self)
        table[i] = 0  # no category, no mask: nothing touches it, no ray sees it
        alive = _alive_of(self)
        alive[i] = False
        engine.use_filters(table)
        engine.retire(np.array([i]))

    @property
    def alive(self: _Running) -> NDArray[np.bool_]:
        """Which bodies are in the world (n,): False for those removed (:meth:`remove_body`).
        A copy."""
        return _alive_of(self).copy()

    def restore_filters(
        self: _Running, table: NDArray[np.int64], alive: NDArray[np.bool_] | None = None
    ) -> None:
        """Take every body's filter from ``table`` (n, 3), as :attr:`collision_filters` gave
        it, and which bodies are in from ``alive`` (n,) (a checkpoint's); the engine, if
        built, takes the filters too (it kept the removed bodies' rest itself)."""
        kept = np.array(table, dtype=np.int64)
        self._filter_table = kept
        if alive is not None:
            self._alive = np.array(alive, dtype=np.bool_)
        engine = self.engine
        if engine is not None and isinstance(engine, SteppedEngine):
            engine.use_filters(kept)

    @property
    def collision_filters(self: _Running) -> NDArray[np.int64]:
        """Every body's filter (n, 3) int64: category bits, mask bits (as signed 64-bit
        integers: -1 is every bit) and group (:meth:`set_filter`). A copy."""
        return _filters_of(self).copy()

    def set_velocities(self: _Running, ids: ArrayLike, velocities: ArrayLike) -> None:
        """Set the velocities (k, d) or (d,) [m/s] of the dynamic bodies ``ids`` (k,); as
        :meth:`apply_impulses` for what is refused."""
        engine, rows = _dynamic_rows(self, ids, "velocities")
        engine.set_motion(rows, "v", _vectors(self, "velocities", velocities, rows.size))

    def set_positions(self: _Running, ids: ArrayLike, positions: ArrayLike) -> None:
        """Move the dynamic bodies ``ids`` (k,) to ``positions`` (k, d) or (d,) [m] (their
        centres of mass), at once: a body put into another is pushed out by the next step's
        contacts. As :meth:`apply_impulses` for what is refused."""
        engine, rows = _dynamic_rows(self, ids, "positions")
        engine.set_motion(rows, "x", _vectors(self, "positions", positions, rows.size))

    def set_angular_velocities(self: _Running, ids: ArrayLike, spins: ArrayLike) -> None:
        """Set the spins of the dynamic bodies ``ids`` (k,) [rad/s]: (k,) or one number in 2D,
        (k, 3) or (3,) in 3D. As :meth:`apply_impulses` for what is refused."""
        engine, rows = _dynamic_rows(self, ids, "spins")
        if self.dim == 2:
            engine.set_motion(rows, "omega", _vectors(self, "spins", spins, rows.size, ()))
        else:
            engine.set_motion(rows, "w", _vectors(self, "spins", spins, rows.size, (3,)))


class Body:
    """Body ``index`` of a world, between steps (:meth:`GameLoop.body`).

    Reads give the state now; writes take effect at once and wake the body (the energy they
    change is booked as work done on it, so the ledger still closes). The event-driven
    engine reads and sets its bodies at its clock and predicts their events again; it takes
    forces at the centres, and torques are the rigid engines'.
    """

    __slots__ = ("_world", "index")

    def __init__(self, world: Any, index: int) -> None:
        self._world = world
        #: the body's index in the world
        self.index = index

    def __repr__(self) -> str:
        return f"<carom body {self.index}, {self.kind}>"

    def _engine(self) -> SteppedEngine | EdmdEngine:
        engine, _ = _dynamic_rows(self._world, [self.index], None)
        return engine

    def _read(self, field: str) -> NDArray[np.float64]:
        engine = self._world.build()
        if isinstance(engine, SteppedEngine):
            return np.array(getattr(engine.state, field)[self.index], dtype=np.float64)
        # the event-driven engine: the body at its clock
        x, v, orient, w = engine.motion_of(np.array([self.index]))
        at: dict[str, NDArray[np.float64]] = {
            "x": x[0], "v": v[0], "angle": orient[0, 0], "q": orient[0], "omega": w[0, 2],
            "w": w[0],
        }  # fmt: skip
        return at[field]

    def _write(self, field: str, value: ArrayLike, shape: tuple[int, ...], name: str) -> None:
        engine = self._engine()
        values = _vectors(self._world, name, value, 1, shape)
        engine.set_motion(np.array([self.index]), field, values)

    @property
    def kind(self) -> str:
        """ "dynamic", "kinematic" or "static"; set, it switches the body's kind
        (:meth:`carom.kinds.Kinds.set_kind`, the rigid engines)."""
        return KIND_NAMES[int(self._world.bodies.kind[self.index])]

    @kind.setter
    def kind(self, value: str) -> None:
        self._world.set_kind([self.index], value)

    @property
    def awake(self) -> bool:
        """Whether the engine moves it now (False: asleep, or not dynamic)."""
        engine = self._world.build()
        if not isinstance(engine, SteppedEngine):
            return self.kind == "dynamic"
        return bool(engine.memory.awake[self.index])

    @property
    def position(self) -> NDArray[np.float64]:
        """Centre of mass (d,) [m]."""
        return self._read("x")

    @position.setter
    def position(self, value: ArrayLike) -> None:
        self._write("x", value, (self._world.dim,), "position")

    @property
    def velocity(self) -> NDArray[np.float64]:
        """Velocity of the centre of mass (d,) [m/s]."""
        return self._read("v")

    @velocity.setter
    def velocity(self, value: ArrayLike) -> None:
        self._write("v", value, (self._world.dim,), "velocity")

    @property
    def angle(self) -> float:
        """Orientation [rad] (2D)."""
        self._planar("angle")
        return float(self._read("angle"))

    @angle.setter
    def angle(self, value: float) -> None:
        self._planar("angle")
        self._write("angle", value, (), "angle")

    @property
    def orientation(self) -> NDArray[np.float64]:
        """Orientation (4,), a unit quaternion ``w, x, y, z`` (3D)."""
        self._spatial("orientation")
        return self._read("q")

    @orientation.setter
    def orientation(self, value: ArrayLike) -> None:
        self._spatial("orientation")
        q = _vectors(self._world, "orientation", value, 1, (4,))
        size = float(np.linalg.norm(q))
        if abs(size - 1.0) > 1e-6:
            raise CaromError(
                f"orientation must be a unit quaternion w, x, y, z; got one of norm {size:.9g}"
                " (divide it by its norm)"
            )
        self._engine().set_motion(np.array([self.index]), "q", q / size)

    @property
    def angular_velocity(self) -> Any:
        """Spin [rad/s]: a number in 2D, a vector (3,) in 3D."""
        if self._world.dim == 2:
            return float(self._read("omega"))
        return self._read("w")

    @angular_velocity.setter
    def angular_velocity(self, value: ArrayLike) -> None:
        if self._world.dim == 2:
            self._write("omega", value, (), "angular_velocity")
        else:
            self._write("w", value, (3,), "angular_velocity")

    def apply_impulse(self, impulse: ArrayLike, point: ArrayLike | None = None) -> None:
        """An impulse (d,) [N s] at the world point ``point`` (d,) [m] (the centre of mass
        when left out): velocity and spin change at once (:meth:`GameLoop.apply_impulses`)."""
        self._world.apply_impulses([self.index], impulse, point)

    def apply_force(self, force: ArrayLike, point: ArrayLike | None = None) -> None:
        """A force (d,) [N] through the next step, at the world point ``point`` (d,) [m] (the
        centre of mass when left out), then cleared (:meth:`GameLoop.apply_forces`)."""
        self._world.apply_forces([self.index], force, point)

    def apply_torque(self, torque: ArrayLike) -> None:
        """A torque through the next step, then cleared: a number in 2D, a world vector (3,)
        in 3D [N m] (:meth:`GameLoop.apply_torques`)."""
        self._world.apply_torques([self.index], torque)

    def _planar(self, name: str) -> None:
        if self._world.dim != 2:
            raise CaromError(f"{name} is a 2D body's; a 3D body has an orientation (w, x, y, z)")

    def _spatial(self, name: str) -> None:
        if self._world.dim != 3:
            raise CaromError(f"{name} is a 3D body's; a 2D body has an angle [rad]")


_NOT_YET_EVENTS = "contact events are the rigid and event-driven engines'"


def _no_sink(records: NDArray[Any]) -> None:
    """A sink that keeps nothing (the event-driven engine logs collisions only for one)."""


_NO_TORQUES = (
    "{} through a step is the rigid engines': the event-driven engine's spheres keep their "
    "spin between impacts (it turns them at a constant rate, exactly); turn one with an "
    "impulse at a point (apply_impulses(ids, impulses, points)), or push it at its centre"
)

_NOT_YET = (
    "this is the rigid engines' so far; the event-driven engine's bodies take new motion and "
    "impulses between steps (World.body, set_velocities, apply_impulses), not this"
)


def _index(world: _Running, index: object) -> int:
    """``index`` as a body index of ``world``, or a CaromError naming it."""
    if isinstance(index, bool) or not isinstance(index, int | np.integer):
        raise CaromError(f"a body index is a whole number; got {index!r}")
    if not 0 <= int(index) < world.n_bodies:
        raise CaromError(
            f"body {index} is not in the world: its indices run from 0 to {world.n_bodies - 1}"
        )
    if not _alive_of(world)[int(index)]:
        raise CaromError(
            f"body {index} was removed (World.remove_body); World.alive says which are in"
        )
    return int(index)


def _plain(
    world: _Running, ids: ArrayLike, values: ArrayLike, points: ArrayLike | None
) -> tuple[NDArray[np.int64], NDArray[np.float64], NDArray[np.float64] | None] | None:
    """``ids`` (k,), ``values`` (k, d) or (1, d) and ``points`` (the same, or None) as the
    engine takes them when they have the plain forms (the game loop's fast path, checked in
    the engine's compiled call); None otherwise."""
    d = world.dim
    rows = np.asarray(ids)
    if rows.ndim != 1 or rows.size == 0 or rows.dtype.kind not in "iu":
        return None
    try:
        j = np.asarray(values, dtype=np.float64)
        at = None if points is None else np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError):
        return None
    shapes = ((d,), (rows.size, d))
    if j.shape not in shapes or (at is not None and at.shape not in shapes):
        return None
    return (
        rows.astype(np.int64, copy=False),
        j.reshape(-1, d),
        None if at is None else at.reshape(-1, d),
    )


def _dynamic_rows(
    world: _Running, ids: ArrayLike, what: str | None
) -> tuple[SteppedEngine | EdmdEngine, NDArray[np.int64]]:
    """The world's engine and the indices ``ids`` (k,), each a dynamic body (``what``: what is
    given to them, for the message; None: any kind)."""
    rows = _rows(world, ids)
    engine = _reachable(world)
    if what is not None:
        kinds = engine.model.kind if isinstance(engine, SteppedEngine) else world.bodies.kind
        if np.any(kinds[rows] != KIND_DYNAMIC):
            bad = int(rows[np.flatnonzero(kinds[rows] != KIND_DYNAMIC)[0]])
            raise CaromError(
                f"body {bad} is {KIND_NAMES[int(kinds[bad])]}: {what} move dynamic bodies only"
            )
    return engine, rows


def _reachable(world: _Running) -> SteppedEngine | EdmdEngine:
    """The world's engine, built: a rigid one or the event-driven one."""
    engine = world.build()
    if not isinstance(engine, SteppedEngine | EdmdEngine):
        raise CaromError(_NOT_YET)
    return engine


def _rigid(world: _Running, why: str = "") -> SteppedEngine:
    """The world's engine, built, when it is a rigid one; else a CaromError (saying ``why``,
    or that the call is the rigid engines' so far)."""
    engine = world.build()
    if not isinstance(engine, SteppedEngine):
        raise CaromError(why or _NOT_YET)
    return engine


def _once(world: Any, attribute: str) -> Any:
    """What ``world`` keeps in ``attribute`` (None if nothing), which it keeps no longer."""
    kept = getattr(world, attribute, None)
    setattr(world, attribute, None)
    return kept


def hand_down(world: Any, engine: Engine) -> None:
    """Keep on ``world`` what the engine it builds in place of the running ``engine`` takes
    over: the loads given for the next step and a rigid engine's sleep and warm starts."""
    setattr(world, _LOADS_KEPT, getattr(engine, "loads_now", lambda: None)())
    setattr(world, _MEMORY_KEPT, getattr(engine, "remembered", lambda: None)())


def kept_overlap(engine: Engine) -> float:
    """The deepest overlap [m] a running rigid engine has now between any of its bodies,
    asleep or awake (0 for another engine): the engine built in its place (bodies added,
    kinds or settings changed between steps) takes overlaps up to it, which the solver made
    and will resolve, and refuses deeper ones, which only what changed can have made. (A
    stack that settled deeper than the linear slop and fell asleep is taken when a change
    wakes it.)"""
    deepest = getattr(engine, "deepest_overlap", None)
    if deepest is None or engine.time <= 0.0:
        return 0.0
    return float(deepest(asleep=True)[2])


def rigid_if_built(world: Any) -> SteppedEngine | None:
    """The world's engine when it is built, None while it is not and will be a rigid one
    (what is set now, it takes when built); else a CaromError."""
    engine = world.engine
    if engine is None and world.engine_entry.stepped:
        return None
    return _rigid(world)


def _rows(world: _Running, ids: ArrayLike) -> NDArray[np.int64]:
    """``ids`` as a 1-D array of body indices of ``world``, or a CaromError naming the first
    wrong one."""
    raw = np.asarray(ids)
    if raw.ndim != 1 or raw.size == 0 or raw.dtype.kind not in "iu":
        raise CaromError(f"ids must be a 1-D array of body indices; got {ids!r}")
    rows = raw.astype(np.int64)
    wrong = (rows < 0) | (rows >= world.n_bodies)
    if not wrong.any():
        wrong = ~_alive_of(world)[rows]
    if wrong.any():
        _index(world, int(rows[wrong][0]))  # (names the first one outside or removed)
    return rows


def _vectors(
    world: _Running, name: str, values: ArrayLike, k: int, shape: tuple[int, ...] | None = None
) -> NDArray[np.float64]:
    """``values`` as (k, *shape) floats (one for all broadcast), finite and within carom's
    limits, or a CaromError naming ``name``; ``shape`` defaults to (d,)."""
    each = (world.dim,) if shape is None else shape
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise CaromError(f"{name} must be numbers; got {values!r}") from None
    if array.shape == each:
        array = np.broadcast_to(array, (k, *each))
    if array.shape != (k, *each):
        raise CaromError(f"{name} must have shape {each} or {(k, *each)}; got {array.shape}")
    if not np.all(np.isfinite(array)) or np.any(np.abs(array) > LARGEST):
        raise CaromError(
            f"{name} must be finite, within carom's limits (|x| <= {LARGEST:g}); got {values!r}"
        )
    return np.array(array)


def per_body(world: Any, name: str, fill: Callable[[int], NDArray[Any]]) -> NDArray[Any]:
    """The world's per-body array kept as attribute ``name``, grown with ``fill(k)`` (k
    rows of its default) to the world's bodies (bodies added since it was set)."""
    array: NDArray[Any] | None = getattr(world, name, None)
    if array is None:
        array = fill(0)
    if array.shape[0] < world.n_bodies:
        array = np.concatenate((array, fill(world.n_bodies - array.shape[0])))
        setattr(world, name, array)
    return array


def _alive_of(world: Any) -> NDArray[np.bool_]:
    """The world's mask of bodies in it (n,), grown with True to its bodies."""
    return per_body(world, "_alive", lambda k: np.ones(k, np.bool_))


def _filters_of(world: Any) -> NDArray[np.int64]:
    """The world's filter table (n, 3), grown with the defaults to its bodies."""
    return per_body(world, "_filter_table", default_filters)


def _positive_time(dt: object, name: str = "dt", what: str = "time [s]") -> float:
    """``dt`` as a positive finite float, or a CaromError naming it (``name``, a ``what``)."""
    wrong = CaromError(f"{name} must be a positive finite {what}; got {dt!r}")
    if isinstance(dt, str | bytes | bool):
        raise wrong
    try:
        value = float(dt)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise wrong from None
    if not (math.isfinite(value) and value > 0.0):
        raise wrong
    return value


def _within_limits(dt: float, now: float) -> None:
    """Refuse a step that would take the clock past carom's largest time."""
    if now + dt > LARGEST:
        raise CaromError(
            f"dt = {dt:g} s takes the clock from {now:g} s past {LARGEST:g} s; carom accepts "
            f"magnitudes up to {LARGEST:g} in SI units (docs/scenes.md, Limits)"
        )
