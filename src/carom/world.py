"""The World: bodies, materials and boundaries, advanced by an engine.

A World holds what a simulation is made of, engine-neutral: the body table
(:class:`carom.bodies.Bodies`), materials (:mod:`carom.materials`), the box, its walls and
planes, gravity, and each engine's settings. Running it builds an engine from the table of
engines (:mod:`carom.engines.registry`) and advances it: the exact event-driven one
(:mod:`carom.engines.edmd`) for spheres and disks, the time-stepped rigid-body one (2D and 3D
bodies of any shape), or any engine registered beside them. Frames, collisions and
observables read the engine's state in the caller's numbering of bodies.

>>> import carom
>>> world = carom.World(2, box=[1.0, 1.0])
>>> _ = world.add_spheres([[0.3, 0.5], [0.7, 0.5]], [[1.0, 0.0], [-1.0, 0.0]], radius=0.05)
>>> world.run(until=0.2, log=True)  # the gap of 0.3 m closes at 2 m/s: impact at 0.15 s
>>> round(float(world.collisions[0]["time"]), 12)
0.15
>>> world.velocities.tolist()        # equal masses, elastic: velocities exchanged
[[-1.0, 0.0], [1.0, 0.0]]
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from carom import body_input as given
from carom._inputs import as_float_array
from carom.bodies import Bodies
from carom.collision_log import LOG_LIMIT, CollisionLog
from carom.engines import registry
from carom.engines.base import Counters, Engine, FrameArrays, describe_partner
from carom.errors import CaromError
from carom.gameloop import GameLoop, hand_down, kept_overlap
from carom.joints import Joints
from carom.kinds import Kinds
from carom.limits import check_body_count
from carom.materials import Material
from carom.observables import Stats
from carom.queries import Queries
from carom.recording import (
    RECORD_BYTES,
    Frame,
    Recording,
    advance_frame_by_frame,
    alive_of,
    check_interval,
    check_span,
    check_times,
    check_until,
    frame_grid,
)
from carom.scenery import Scenery
from carom.sensing import Sensing
from carom.shapes import Shape2D, check_inertia_factor, default_inertia_factor
from carom.shapes3d import Shape3D

__all__ = ["LOG_LIMIT", "RECORD_BYTES", "Frame", "Material", "Recording", "World"]

FloatArray = NDArray[np.float64]


class World(Scenery, GameLoop, Queries, Joints, Sensing, Kinds):
    """Bodies in a box, advanced by an engine: spheres (3D) or disks (2D) simulated exactly,
    event by event, or rigid bodies of any shape in 2D and 3D, step by step.

    Parameters
    ----------
    dim : {2, 3}
        Dimension.
    box : (d,) array_like
        Box side lengths [m]; the box spans ``[0, box[k]]``.
    boundary : {"walls", "periodic", "open"}, default "walls"
        Reflecting walls, periodic boundaries, or none ("open", rigid-body engine only: the
        box then only frames the pictures).
    gravity : (d,) array_like, optional
        Uniform acceleration [m/s^2], e.g. ``[0, -9.81]``.
    walls : Material, float, or a sequence of 2 d of them, default 1.0
        The walls' material: one for all, or the lower and upper wall of each axis in turn
        (``x-, x+, y-, ...``); a number is a smooth material of that restitution [-]. A wall's
        restitution is its own, not combined with the body's.
    t_c : float, optional
        TC-model time [s] (:class:`carom.engines.edmd.settings.EdmdSettings`, whose default
        it keeps when not given).
    combine : {"mean", "min", "max", "geometric", "product"}, default "mean"
        How two materials' coefficients combine; :meth:`set_pair` overrides a pair.
    shell_thickness : float, optional
        Neighbour-shell thickness [m] (:class:`carom.engines.edmd.settings.EdmdSettings`).
    engine : str, default "auto"
        An engine's name (:func:`carom.engines.registry.engine_choices`): "edmd", the exact
        event-driven engine for spheres and disks; "rigid", the time-stepped rigid-body
        engine (2D and 3D); or "auto": the first engine that takes the world ("edmd" for
        spheres or disks in walls or a periodic box, "rigid" otherwise).
    rigid : RigidSettings, optional
        The rigid-body engine's step and solver settings
        (:class:`carom.engines.stepped.settings.RigidSettings`).
    settings : mapping of str to settings, optional
        Any engine's settings by its name (an engine registered beside the built-in ones).
    """

    def _start(self) -> None:
        """The World's own start (:class:`Scenery` sets the rest): no bodies, no engine."""
        self.bodies = Bodies(self.dim)
        self._engine: Engine | None = None
        self._built_with: Any = None  # (name, settings) it was built with (others: rebuilt)
        self._time = 0.0
        self._log = CollisionLog()
        #: whether the last run got to its target (False: its stop request ended it early)
        self.reached = True
        # totals of the engines dropped so far (adding bodies or materials rebuilds it)
        self._counters_before = Counters(0, 0, 0, 0, 0, 0.0, 0.0, 0, 0.0, 0.0)
        self.stats = Stats(self)
        #: the deepest overlap the engine dropped last had [m]: its successor refuses deeper
        self.overlap_kept = 0.0

    # -- building ---------------------------------------------------------------------------

    def add_spheres(
        self,
        positions: ArrayLike,
        velocities: ArrayLike | None = None,
        *,
        radius: ArrayLike,
        mass: ArrayLike = 1.0,
        restitution: float | None = None,
        material: Material | int | None = None,
        angular_velocities: ArrayLike | None = None,
        inertia_factor: float | None = None,
    ) -> NDArray[np.int64]:
        """Add moving spheres (disks in 2D); return their indices.

        Parameters
        ----------
        positions : (n, d) or (d,) array_like
            Centres [m].
        velocities : (n, d) or (d,) array_like, optional
            [m/s]; default at rest.
        radius, mass : float or (n,) array_like
            [m] and [kg], positive.
        restitution : float, optional
            Shorthand for ``material=Material(restitution)``; default 1 (elastic).
        material : Material or int, optional
            A material or the index of one added with :meth:`add_material`.
        angular_velocities : (n, 3) array_like, or (n,) in 2D, optional
            [rad/s]; default not spinning.
        inertia_factor : float, optional
            ``q`` in ``I = q m a^2``; default 2/5 (solid sphere), 1/2 in 2D (disk).
        """
        x, v = given.motion(positions, velocities, self.dim)
        mat = self._material_index(restitution, material)
        w = given.angular_velocities(angular_velocities, len(x), self.dim)
        q = check_inertia_factor(
            default_inertia_factor(self.dim) if inertia_factor is None else inertia_factor
        )
        radii = given.radii(radius, len(x), self.box)
        masses = given.per_body("mass", mass, len(x), "kg")
        self._invalidate()  # the bodies' state now, out of the engine; it is rebuilt on run
        return self.bodies.append_spheres(x, v, w, radii, masses, q, mat)

    def add_static_spheres(
        self,
        positions: ArrayLike,
        *,
        radius: ArrayLike,
        restitution: float | None = None,
        material: Material | int | None = None,
    ) -> NDArray[np.int64]:
        """Add spheres that never move (pegs, obstacles); return their indices."""
        x = given.rows("positions", positions, self.dim)
        n = x.shape[0]
        mat = self._material_index(restitution, material)
        radii = given.radii(radius, n, self.box)
        self._invalidate()
        return self.bodies.append_spheres(
            x, np.zeros_like(x), np.zeros((n, 3)), radii, np.full(n, np.inf), 0.4, mat
        )

    def add_body(
        self,
        shape: Shape2D | Shape3D,
        position: ArrayLike,
        *,
        velocity: ArrayLike | None = None,
        angle: float = 0.0,
        orientation: ArrayLike | None = None,
        angular_velocity: float | ArrayLike = 0.0,
        density: float | None = None,
        mass: float | None = None,
        restitution: float | None = None,
        material: Material | int | None = None,
        kind: str = "dynamic",
    ) -> int:
        """Add one rigid body of any shape; return its index: :meth:`add_bodies` for one
        body, whose ``position``, ``velocity``, ``angle``, ``orientation`` and
        ``angular_velocity`` are the ``positions``, ... of that one."""
        return int(
            self.add_bodies(
                shape,
                position,
                velocity,
                angles=angle,
                orientations=orientation,
                angular_velocities=angular_velocity,
                density=density,
                mass=mass,
                restitution=restitution,
                material=material,
                kind=kind,
            )[0]
        )

    def add_bodies(
        self,
        shape: Shape2D | Shape3D,
        positions: ArrayLike,
        velocities: ArrayLike | None = None,
        *,
        angles: ArrayLike = 0.0,
        orientations: ArrayLike | None = None,
        angular_velocities: ArrayLike = 0.0,
        density: float | None = None,
        mass: float | None = None,
        restitution: float | None = None,
        material: Material | int | None = None,
        kind: str = "dynamic",
    ) -> NDArray[np.int64]:
        """Add rigid bodies of one shape; return their indices.

        Parameters
        ----------
        shape : Shape2D or Shape3D
            2D (:mod:`carom.shapes`): Circle, Capsule, Box, Polygon, Compound; Segment and
            Chain (static only). 3D (:mod:`carom.shapes3d`): Sphere, Capsule, Box, Hull,
            Compound; :class:`carom.meshes.Mesh` (static only).
        positions : (n, d) or (d,) array_like
            Where each body's shape origin goes [m]. A body's position as the World reports
            it (:attr:`positions`, frames) is its centre of mass, which is the origin for
            every shape centred on it (all but a Polygon or Compound drawn off-centre).
        velocities : (n, d) or (d,) array_like, optional
            Of the centres of mass [m/s]; default at rest.
        angles : float or (n,) array_like, default 0
            2D: the shape's turn about its origin [rad], anticlockwise.
        orientations : (n, 4), (4,), (n, 3, 3) or (3, 3) array_like, optional
            3D: the shape's turn about its origin, unit quaternions ``(w, x, y, z)`` or
            rotation matrices (shape to world); default unturned.
        angular_velocities : float or (n,) array_like (2D), (n, 3) or (3,) (3D), default 0
            [rad/s]: anticlockwise in 2D, a vector in the world frame in 3D.
        density, mass : float, optional
            [kg/m^2] (2D) or [kg/m^3] (3D), or [kg], one of them for dynamic bodies (default
            density 1); neither for static or kinematic ones, which impacts do not move.
        restitution, material
            As for :meth:`add_spheres`; give the material ``friction=`` for Coulomb friction.
        kind : {"dynamic", "static", "kinematic"}, default "dynamic"
            Dynamic bodies fall and collide; static ones never move; kinematic ones move at
            their own velocity and angular velocity whatever they meet (a paddle, a turning
            tumbler). With ``engine="auto"`` a world with such bodies runs the rigid-body
            engine; spheres (disks) from :meth:`add_spheres` join it as balls (circles).
        """
        rows = given.shaped_bodies(
            self.dim,
            shape,
            positions,
            velocities,
            angles=angles,
            orientations=orientations,
            spins=angular_velocities,
            density=density,
            mass=mass,
            kind=kind,
        )
        mat = self._material_index(restitution, material)
        self._invalidate()
        return self.bodies.append_bodies(*rows, mat)

    def _invalidate(self) -> None:
        """Bring the body table up to date and drop the engine (it is rebuilt on run)."""
        if self._engine is not None:
            self._time = self._engine.time
            self.bodies.set_state(*self._engine.sample())
            self._counters_before = self.counters()
            hand_down(self, self._engine)  # (its loads, sleep and warm starts: rebuilt)
            self.overlap_kept = kept_overlap(self._engine)
        self._engine = None

    # -- the engine -------------------------------------------------------------------------

    @property
    def engine_entry(self) -> registry.EngineEntry:
        """The engine this world runs (:mod:`carom.engines.registry`): the one built, else the
        one chosen, or with ``engine="auto"`` the first that takes the world."""
        if self._engine is not None:
            return registry.find(self._engine.name)
        if self.engine_choice != registry.AUTO:
            return registry.find(self.engine_choice)
        return registry.pick(registry.AUTO, self)

    @property
    def engine_name(self) -> str:
        """The name of the engine this world runs ("edmd", "rigid", ...)."""
        return self.engine_entry.name

    @property
    def fixed_step(self) -> float | None:
        """The engine's step [s], or None for an engine that stops at any time."""
        entry = self.engine_entry
        return float(self.settings_of(entry.name).dt) if entry.stepped else None

    def build(self) -> Engine:
        """Build the engine now (running does it when needed), refusing bodies outside the
        box, on the wrong side of a plane, or overlapping; return it."""
        built = self._built_with  # (the engine's name and the settings it was built with)
        if self._engine is not None and built[1] is not self.engine_settings.get(built[0]):
            self._invalidate()  # settings assigned since it was built: built again with them
        if self._engine is None:
            if self.bodies.n == 0:
                raise CaromError("the world has no bodies; add some with add_spheres or add_body")
            check_body_count(self.bodies.n, "the world")
            entry = registry.pick(self.engine_choice, self)
            self._engine = entry.plug(self.dim).build(self)
            self._built_with = (entry.name, self.settings_of(entry.name))
        return self._engine

    def prepare(self) -> None:
        """Build the engine and compile its kernels now (or load them from the cache), so
        that a timed run times the simulation alone. Changes nothing."""
        self.build().warm_up()
        self.record(np.empty(0))  # the path of record() and frames(), frame-less

    @property
    def engine(self) -> Engine | None:
        """The engine, once built (:meth:`build`); None before."""
        return self._engine

    def counters(self) -> Counters:
        """The engine's running totals since the world was first run (:class:`Stats`)."""
        base = self._counters_before
        if self._engine is None:
            return base
        return base.plus(self._engine.counters())

    # -- running ------------------------------------------------------------------------------

    @property
    def time(self) -> float:
        """Simulation time [s]: the engine's clock, once built."""
        return self._time if self._engine is None else self._engine.time

    def run(
        self,
        until: float,
        *,
        frame_interval: float | None = None,
        log: bool | ArrayLike = False,
        on_collisions: Callable[[NDArray[Any]], object] | None = None,
        callback: Callable[[Frame], object] | None = None,
        stop: Callable[[], bool] | None = None,
    ) -> list[Frame] | None:
        """Advance to time ``until`` [s], exactly.

        With ``frame_interval`` [s], frames at ``time + k frame_interval`` (and at ``until``)
        are collected and returned, and ``callback`` is called with each; without it, nothing
        is kept. Collisions: ``log`` True keeps them in :attr:`collisions` (up to
        :data:`LOG_LIMIT`; a list of body indices keeps only those involving one of them);
        ``on_collisions`` receives every block of them as they come (a structured array of
        :data:`carom.engines.base.COLLISION_DTYPE`), with memory flat however long the run.

        ``stop`` is asked between blocks of events (a fraction of a second apart); when it
        returns True the run ends early, at the last event processed (:attr:`time` says
        when), and can be continued with another call. Ctrl-C likewise interrupts between
        blocks and leaves the world consistent.
        """
        if frame_interval is None:
            if callback is not None:
                raise CaromError("callback needs frame_interval: the time between frames [s]")
            for _ in self.frames(until, None, log=log, on_collisions=on_collisions, stop=stop):
                pass
            return None
        frames = []
        for frame in self.frames(
            until, frame_interval, log=log, on_collisions=on_collisions, stop=stop
        ):
            if callback is not None:
                callback(frame)
            frames.append(frame)
        return frames

    def run_events(self, count: int = 1, *, log: bool | ArrayLike = False) -> None:
        """Process the next ``count`` events (collisions and neighbour-list rebuilds).

        The clock moves to the time of the last one; nothing else is skipped over.
        """
        if isinstance(count, bool) or not isinstance(count, int | np.integer) or count < 1:
            raise CaromError(f"count must be a whole number >= 1; got {count!r}")
        self.build().advance(math.inf, int(count), self._sink(log, None))

    def frames(
        self,
        until: float,
        frame_interval: float | None,
        *,
        log: bool | ArrayLike = False,
        on_collisions: Callable[[NDArray[Any]], object] | None = None,
        stop: Callable[[], bool] | None = None,
    ) -> Iterator[Frame]:
        """Advance to ``until``, yielding a :class:`Frame` every ``frame_interval`` (lazily);
        ``log``, ``on_collisions``, ``stop`` as for :meth:`run` (stopped: no more frames)."""
        until = check_until(until, self.time)
        if frame_interval is not None:
            check_interval(frame_interval)
        check_span(self.time, until, self.fixed_step, frame_interval)
        engine, sink = self.build(), self._sink(log, on_collisions)

        def reached(done: bool) -> None:
            self.reached = done

        yield from advance_frame_by_frame(engine, until, frame_interval, sink, stop, reached, self)

    def record(
        self,
        times: ArrayLike,
        *,
        log: bool | ArrayLike = False,
        on_collisions: Callable[[NDArray[Any]], object] | None = None,
        stop: Callable[[], bool] | None = None,
    ) -> Recording:
        """Advance through each of ``times`` in turn and return every body's state at each.

        The frames of :meth:`frames`, all at once: the event-driven engine runs the whole
        stretch in one compiled call, where :meth:`frames` makes a call per frame. The world
        ends at the last time.

        Parameters
        ----------
        times : (F,) array_like
            Frame times [s], finite, non-decreasing, none before :attr:`time`.
        log, on_collisions, stop
            As for :meth:`run`. A stopped run returns the frames done before the stop.

        Returns
        -------
        Recording
            ``times`` (F,) and the states (F, N, ...) at them.

        Raises
        ------
        CaromError
            Times not finite, decreasing or before now, or frames that would take more than
            :data:`RECORD_BYTES` of memory (use :meth:`frames` to stream them instead).
        """
        grid = np.ascontiguousarray(as_float_array("times", times))
        check_times(grid, self.time, self.n_bodies, self.dim)
        check_span(self.time, float(grid[-1]) if grid.size else self.time, self.fixed_step)
        engine, sink = self.build(), self._sink(log, on_collisions)
        out = FrameArrays.empty(grid.size, self.n_bodies, self.dim)
        done = engine.advance_frames(grid, sink, stop, out)
        if grid.size:  # no frame asked, nothing said (prepare() warms this path so)
            self.reached = done == grid.size
        return Recording.of(out, done, self.dim, alive_of(self))

    def frame_times(self, until: float, frame_interval: float) -> FloatArray:
        """The times [s] at which :meth:`frames` yields, (F,): ``time + k frame_interval``
        for k = 1, 2, ... while before ``until``, then ``until`` (for :meth:`record`)."""
        return frame_grid(self.time, until, frame_interval)

    def _sink(
        self, log: bool | ArrayLike, stream: Callable[[NDArray[Any]], object] | None
    ) -> Callable[[NDArray[Any]], None] | None:
        """Where the engine's collisions go (:meth:`CollisionLog.sink`)."""
        return self._log.sink(log, stream, self.n_bodies)

    def frame(self) -> Frame:
        """The current state as a :class:`Frame`."""
        x, v, orient, w = self._state_now()
        return Frame(self.time, x, v, orient[:, 0] if self.dim == 2 else orient, w, alive_of(self))

    # -- reading ------------------------------------------------------------------------------

    def _state_now(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        if self._engine is None:
            b = self.bodies
            x, v, q, w = b.position, b.velocity, b.orientation, b.angular_velocity
            return x.copy(), v.copy(), q.copy(), w.copy()
        return self._engine.sample()

    @property
    def n_bodies(self) -> int:
        return self.bodies.n

    def _motion_now(self) -> tuple[FloatArray, FloatArray]:
        """Positions and velocities now: :meth:`_state_now`'s first two, alone."""
        if self._engine is None:
            return self.bodies.position.copy(), self.bodies.velocity.copy()
        return self._engine.sample_motion()

    @property
    def positions(self) -> FloatArray:
        """Centres now, (N, d) [m] (periodic: wrapped into the box)."""
        only = getattr(self._engine, "sample_positions", None)  # (a rigid engine's: one copy)
        return self._motion_now()[0] if only is None else only()

    @property
    def velocities(self) -> FloatArray:
        """Velocities now, (N, d) [m/s]."""
        return self._motion_now()[1]

    @property
    def angular_velocities(self) -> FloatArray:
        """Angular velocities now, (N, 3) [rad/s] (2D: column 2)."""
        return self._state_now()[3]

    @property
    def orientations(self) -> FloatArray:
        """Orientations now: (N,) angles [rad] in 2D, (N, 4) unit quaternions in 3D."""
        turns = getattr(self._engine, "sample_turns", None)  # (a rigid engine's: one copy)
        return self.frame().orientations if turns is None else turns()

    @property
    def resting(self) -> NDArray[np.int64]:
        """The wall face or plane each body rests on (-1: none), (N,) int."""
        if self._engine is None:
            return np.full(self.n_bodies, -1, np.int64)
        return self._engine.resting()

    @property
    def radii(self) -> FloatArray:
        return self.bodies.radius.copy()

    @property
    def masses(self) -> FloatArray:
        return self.bodies.mass.copy()

    @property
    def collisions(self) -> NDArray[Any]:
        """The collisions kept with ``log=True`` so far, a structured array of
        :data:`carom.engines.base.COLLISION_DTYPE`: ``time`` [s]; ``body``; ``kind`` and
        ``partner`` (a body, a wall face or a plane, see :meth:`describe_partner`);
        ``impulse`` on ``body`` [N s], always 3 components; ``un_before``, ``un_after`` the
        normal relative speeds [m/s]."""
        return self._log.collisions

    @property
    def collisions_dropped(self) -> int:
        """Collisions not kept because the log was full (:data:`LOG_LIMIT`)."""
        return self._log.dropped

    describe_partner = staticmethod(describe_partner)  # ``body 3``, ``wall x-``, ``plane 0``

    # -- checkpoints --------------------------------------------------------------------------

    def save(self, path: str | Path, *, extra: Mapping[str, NDArray[Any]] | None = None) -> None:
        """Write a checkpoint of the whole world (:mod:`carom.checkpoint`) to ``path``.

        A world loaded from it continues exactly, bit for bit, as this one would. ``extra``
        arrays are stored beside it under their names and come back from
        :meth:`load_with_extra`.
        """
        from carom.checkpoint import save_world

        save_world(self, Path(path), extra or {})

    @classmethod
    def load(cls, path: str | Path) -> World:
        """Read a checkpoint written by :meth:`save`."""
        return cls.load_with_extra(path)[0]

    @classmethod
    def load_with_extra(cls, path: str | Path) -> tuple[World, dict[str, NDArray[Any]]]:
        """Read a checkpoint written by :meth:`save`, and the ``extra`` arrays saved with it."""
        from carom.checkpoint import load_world

        return load_world(Path(path), cls)

    @property
    def counters_before(self) -> Counters:
        """Totals of engines this world built and dropped before its current one."""
        return self._counters_before

    def restore(
        self,
        time: float,
        engine_arrays: Mapping[str, NDArray[Any]] | None,
        counters_before: Counters,
        log: NDArray[Any],
        collisions_dropped: int,
        engine_name: str | None = None,
    ) -> None:
        """Continue from a checkpoint (:mod:`carom.checkpoint`): the clock, the arrays of the
        engine called ``engine_name`` (None: not built yet), the totals and the kept log."""
        self._time = time
        self._counters_before = counters_before
        self._log = CollisionLog(log, collisions_dropped)
        if engine_arrays is None:
            return
        entry = registry.find(engine_name) if engine_name else self.engine_entry
        self._engine = entry.plug(self.dim).restore(self, engine_arrays)
        self._built_with = (entry.name, self.settings_of(entry.name))
