"""The event-driven engine as a :class:`carom.engines.base.Engine`: builds Model and State from
the World's bodies, runs the loop, grows what overflows, and hands over the log.

The engine numbers bodies along a space-filling curve (:mod:`carom.engines.edmd.ordering`):
engine index ``e`` is body ``order[e]``; everything this class returns is in the caller's
numbering.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom._memory import release_free_memory
from carom.bodies import Bodies, identity_orientations
from carom.engines.base import (
    COLLISION_DTYPE,
    PARTNER_BODY,
    PARTNER_PLANE,
    PARTNER_WALL,
    STOP_CHECK_EVENTS,
    Counters,
    FrameArrays,
    Sink,
)
from carom.engines.edmd import aside, codes, loop, neighbours
from carom.engines.edmd.calendar import Calendar, calendar_build, calendar_views
from carom.engines.edmd.events import EdmdEvents
from carom.engines.edmd.handle import new_handle, sample_motion_now, sample_now
from carom.engines.edmd.model import Environment, Model
from carom.engines.edmd.neighbours import FITS, LIST_FULL, build_all
from carom.engines.edmd.ordering import spatial_order
from carom.engines.edmd.reach import bodies_now, retire_bodies, set_bodies, set_pulls
from carom.engines.edmd.renumber import cell_ranks, renumber
from carom.engines.edmd.settings import SHELL_DEFAULT, EdmdSettings
from carom.engines.edmd.state import (
    KIN_V,
    N_SUMS,
    SCHED_STAMP,
    SCHED_WIDTH,
    Records,
    State,
    aligned_records,
    aligned_rows,
    allocate_state,
    scratch,
)
from carom.engines.edmd.threads import in_ranges
from carom.errors import CaromError
from carom.laws.kernels import LAW_SMOOTH

__all__ = ["OVERLAP_TOLERANCE", "EdmdEngine", "grid_cells"]

FloatArray = NDArray[np.float64]

#: Engines of at least this many bodies renumber them along the Morton curve as they run
#: (:mod:`carom.engines.edmd.renumber`); below it all of a gas's arrays stay in the caches
#: (a random numbering of 10^4 spheres cost 0-2% more a collision, of 32768 6-7%)
RENUMBER_MIN_BODIES = 1 << 14
#: Events a body, on average, between two renumberings
RENUMBER_EVENTS_PER_BODY = 64
LOG_CAPACITY = 1 << 16
#: Overlaps and box excursions smaller than this fraction of the radii are round-off, not errors
OVERLAP_TOLERANCE = 1e-12


#: what a call that samples nothing passes for the frames it does not write
_NO_FRAMES = FrameArrays.empty(1, 1, 3)

#: The cell grid holds at most this many cells per body (and at least MIN_CELLS in all)
CELLS_PER_BODY = 16
MIN_CELLS = 4096


def grid_cells(box: FloatArray, reach: float, n: int) -> NDArray[np.int64]:
    """How many cells of the neighbour grid lie along each axis.

    Cells are at least ``reach`` wide, so that bodies whose shells touch are in adjacent
    cells; as many as fit, but no more than ``max(MIN_CELLS, CELLS_PER_BODY n)`` in all: a
    sparse scene (two 1 cm spheres in a 1 km box) or a huge box then gets wider cells, not a
    grid of 1e13 cells, and the count never overflows (a box of 1e300 m). Wider cells are
    always correct; they only put more bodies in each.

    Parameters
    ----------
    box : (d,) float64
        Box sides [m].
    reach : float
        The smallest cell side [m]: the largest shell diameter.
    n : int
        Number of bodies.

    Returns
    -------
    (d,) int64
        Cells along each axis, each at least 1.
    """
    limit = float(max(MIN_CELLS, CELLS_PER_BODY * n))
    cells = np.maximum(1.0, np.floor(np.minimum(box / reach, limit)))  # in float: no overflow
    total = float(np.prod(cells))
    if total > limit:
        cells = np.maximum(1.0, np.floor(cells * (limit / total) ** (1.0 / box.shape[0])))
    return cells.astype(np.int64)


class EdmdEngine:
    """Spheres or disks simulated exactly, event by event (docs/engine.md).

    Parameters
    ----------
    bodies : Bodies
        Their state at ``time``.
    env : Environment
        The box, gravity, materials and faces.
    settings : EdmdSettings
        ``t_c`` and the shell thickness.
    time : float
        The clock at the start [s].

    Raises
    ------
    CaromError
        Bodies that overlap, or a periodic box too small for them.
    """

    name = "edmd"
    _handle: Any = None
    _events: EdmdEvents | None = None

    @property
    def events(self) -> EdmdEvents:
        """The contact events a game loop's steps gather (:mod:`carom.engines.edmd.events`),
        made on first use."""
        if self._events is None:
            self._events = EdmdEvents(self.bodies.n, self.env.dim)
        return self._events

    @property
    def state(self) -> State:
        """The changing arrays (:mod:`carom.engines.edmd.state`), in engine order."""
        return self._state

    @state.setter
    def state(self, value: State) -> None:
        self._state = value
        self._handle = None  # it held the arrays replaced

    def __getstate__(self) -> dict[str, Any]:
        """Copies and pickles leave the handle behind; it is made again on first use."""
        attributes = self.__dict__.copy()
        attributes["_handle"] = None
        return attributes

    @property
    def handle(self) -> Any:
        """The compiled handle on the model, state and order that the kernels of
        :mod:`carom.engines.edmd.handle` take, made again after the state's arrays were
        replaced."""
        if self._handle is None:
            self._handle = new_handle(self.model, self._state, self.order)
        return self._handle

    def __init__(
        self,
        bodies: Bodies,
        env: Environment,
        settings: EdmdSettings,
        time: float,
        *,
        state: State | None = None,
        order: NDArray[np.int64] | None = None,
        capacity: int | None = None,
        cell_capacity: int = 0,
        gone: NDArray[np.bool_] | None = None,
    ) -> None:
        self.bodies = bodies
        self.env = env
        self.settings = settings
        n = bodies.n
        self.renumber_every = RENUMBER_EVENTS_PER_BODY * n if n >= RENUMBER_MIN_BODIES else 0
        self._renumbered_at = -1
        self._cell_rank: NDArray[np.int32] | None = None  # (renumber's, made when first used)
        self.capacity = capacity if capacity is not None else (16 if env.dim == 2 else 32)
        self.cell_capacity = cell_capacity
        if state is not None:
            assert order is not None
            self.order = order
            self.model = self._build_model(order, state.w is not None, state.acc is not None)
            self.state = state
            return
        x = bodies.position.copy()
        if env.periodic:
            x -= env.box * np.floor(x / env.box)
        # the grid only orders the bodies; the model below sets the shells (the same sizes)
        _, ncell = self._shell_grid(bodies.radius, bodies.mobile)
        order = self.order = spatial_order(x, env.box / ncell, ncell)
        model = self._build_model(order, spinning(bodies, env))
        cells = np.clip(np.floor(x / model.cell_size).astype(np.int64), 0, model.ncell - 1)
        occupancy = np.bincount(np.ravel_multi_index(cells.T, model.ncell)).max()
        self.cell_capacity = max(self.cell_capacity, 8, 2 * int(occupancy))
        del x, cells  # the state is filled from the bodies, block by block
        spins = model.q is not None  # (else the bodies' spins and turns are not read)
        # the bodies' motion is lent to this engine once copied into the state: the table
        # keeps none while the engine runs (Bodies.lend), and takes it back if the build fails
        start: list[Records] = []

        def copied(records: Records) -> None:
            start.append(records)
            bodies.lend(self)
            release_free_memory()  # (the table's motion, freed in the heap: carom._memory)

        try:
            state = allocate_state(
                bodies,
                order,
                model,
                time,
                self.cell_capacity,
                self.capacity,
                LOG_CAPACITY,
                copied=copied,
            )
            # a cold cache: the build kernels compile in a helper process while the loop
            # compiles here (engines/edmd/aside.py)
            helper = aside.start(model.gravity is not None, spins)
            aside.compile_beside(helper, model, state, order)
            state, self.capacity, self.cell_capacity = _fit_lists(
                model, state, self.capacity, self.cell_capacity
            )
            in_ranges(loop.initialise, n, model, state)  # every body's first event
            calendar_build(state.ev_time, _calendar(state))
            self.model, self.state = model, state
            if gone is not None and gone.any():  # (bodies taken out: none can overlap them)
                self._retire_rows(self._engine_rows(np.flatnonzero(gone)))
            self._check_overlaps()
        except BaseException:
            if start:
                bodies.set_state(*self._motion_at_start(start[0]))
            raise

    # -- building ---------------------------------------------------------------------------

    def _shell_grid(
        self, radius: FloatArray, mobile: NDArray[np.bool_]
    ) -> tuple[float, NDArray[np.int64]]:
        """The shell thickness ``delta`` [m] and the cells along each axis for spheres of
        ``radius`` (N,) [m], of which ``mobile`` (N,) move (their mean diameter sets the
        default thickness)."""
        n = radius.shape[0]
        mean_diameter = 2.0 * float(np.mean(radius[mobile])) if mobile.any() else 1.0
        thickness = self.settings.shell_thickness
        delta = thickness if thickness is not None else SHELL_DEFAULT * mean_diameter
        largest = float(radius.max()) if n else 0.0
        shell_diameter = 2.0 * (largest + delta)
        env = self.env
        if env.periodic and np.any(env.box < 2.0 * shell_diameter):
            raise CaromError(
                f"the box is too small for periodic boundaries with spheres of radius "
                f"{largest:g} m: each side must exceed 4 (radius + shell) = "
                f"{2.0 * shell_diameter:g} m"
            )
        return delta, grid_cells(env.box, shell_diameter, n)

    def _build_model(
        self, order: NDArray[np.int64], spins: bool, accelerations: bool = False
    ) -> Model:
        """The Model with bodies in engine order ``order``; without inertia factors (``q``
        None: the engine holds no spins) unless some body ``spins`` (:func:`spinning`);
        without gravity (None: no accelerations) unless the world has some or the state
        keeps ``accelerations`` (a force has acted: :meth:`advance_step`)."""
        b, env = self.bodies, self.env
        mass = b.mass[order]
        mobile = np.isfinite(mass)
        radius = b.radius[order]
        delta, ncell = self._shell_grid(radius, mobile)
        with np.errstate(divide="ignore"):
            inv_mass = np.where(mobile, 1.0 / mass, 0.0)
        return Model(
            box=env.box.copy(),
            inv_box=1.0 / env.box,
            periodic=env.periodic,
            gravity=env.gravity.copy() if accelerations or np.any(env.gravity != 0.0) else None,
            mobile=mobile,
            radius=radius,
            mass=mass,
            inv_mass=inv_mass,
            q=b.inertia_factor[order] if spins else None,
            material=b.material[order],
            pair_law=env.pairs.law,
            pair_e=env.pairs.e,
            pair_beta=env.pairs.beta,
            pair_friction=env.pairs.friction,
            face_e=env.face_e,
            plane_point=env.plane_point,
            plane_normal=env.plane_normal,
            t_c=self.settings.t_c,
            shell_thickness=delta,
            cell_size=env.box / ncell,
            ncell=ncell,
        )

    def _check_overlaps(self) -> None:
        """Refuse overlapping spheres: every overlapping pair shares a neighbour list."""
        model, state = self.model, self.state
        found = in_ranges(
            neighbours.first_overlap,
            model.mobile.shape[0],
            state.kin,
            state.nbr,
            state.nbr_count,
            model.mobile,
            model.radius,
            model.box,
            model.periodic,
            OVERLAP_TOLERANCE,
        )
        i, j, overlap = next((f for f in found if f[0] >= 0), found[0])
        if i >= 0:
            a, b = sorted((int(self.order[i]), int(self.order[j])))
            pos, rad = self.bodies.position, self.bodies.radius
            raise CaromError(
                f"spheres {a} and {b} overlap by {overlap:.3g} m at the start (centres "
                f"{pos[a].tolist()} and {pos[b].tolist()}, radii {rad[a]:g} and "
                f"{rad[b]:g}); place them at least the sum of their radii apart"
            )

    # -- running ----------------------------------------------------------------------------

    @property
    def time(self) -> float:
        """The engine's clock [s]: the time of the last event, or where it was stopped."""
        return float(self.state.clock[0])

    def advance(
        self,
        until: float,
        max_events: int,
        sink: Sink | None,
        stop: Callable[[], bool] | None = None,
    ) -> bool:
        """Process events in time order until ``until`` [s] (the clock then reads ``until``)
        or ``max_events`` events; collisions go to ``sink`` if given (the log buffer is
        emptied into it whenever it fills), and the lists grow whenever one overflows.
        Returns False if ``stop`` said True (see :meth:`_drive`)."""
        reached, _ = self._drive(np.array([until], dtype=np.float64), max_events, sink, stop)
        return reached

    def advance_frames(
        self,
        times: FloatArray,
        sink: Sink | None,
        stop: Callable[[], bool] | None,
        out: FrameArrays,
    ) -> int:
        """Process events up to each of ``times`` in turn and write every body's state there
        into frame ``f`` of ``out``, in one compiled call for the lot
        (:func:`carom.engines.edmd.loop.run_frames`); returns the frames written."""
        _, done = self._drive(times, np.iinfo(np.int64).max, sink, stop, out)
        return done

    def _drive(
        self,
        times: FloatArray,
        max_events: int,
        sink: Sink | None,
        stop: Callable[[], bool] | None,
        out: FrameArrays | None = None,
    ) -> tuple[bool, int]:
        """Run the kernel through ``times`` (sampling into ``out`` if given): whether it got
        through them (or through ``max_events`` events), and how many frames it finished.

        The kernel runs in blocks of :data:`STOP_CHECK_EVENTS` events, so Python's signal
        handlers run between them (Ctrl-C is seen within a fraction of a second) and ``stop``
        is asked; if it says True, the clock stays at the last event. Blocks change no bit:
        the loop ends and resumes between two events.
        """
        frames = out if out is not None else _NO_FRAMES
        done = np.zeros(1, dtype=np.int64)
        remaining = max_events
        every = self.renumber_every
        while True:
            counts = self.state.counts
            before = int(counts[codes.C_EVENTS])
            block = min(remaining, STOP_CHECK_EVENTS)
            if every > 0:
                # renumbered after every `every`-th event, however the run is cut into calls
                # and blocks (a permutation: the same event order up to ties in time)
                if before > 0 and before % every == 0 and before != self._renumbered_at:
                    self._renumbered_at = before
                    if self._cell_rank is None:
                        self._cell_rank = cell_ranks(self.model.ncell)
                    renumber(self.model, self.state, self.order, self._cell_rank)
                block = min(block, every - before % every)
            status = loop.run_frames(
                self.handle, times, block, sink is not None, out is not None, done, *frames
            )
            self._drain(sink)
            remaining -= int(counts[codes.C_EVENTS]) - before
            if status == codes.DONE or (status == codes.MAX_EVENTS and remaining <= 0):
                return True, int(done[0])
            if stop is not None and stop():
                return False, int(done[0])
            if status in (codes.LISTS_FULL, codes.CELLS_FULL):
                self._grow(status)
                self.resize_grid(self.capacity, self.cell_capacity)

    def _grow(self, status: int) -> None:
        """Double the capacity that ran out: neighbour lists or cell rows."""
        if status == codes.LISTS_FULL:
            self.capacity *= 2
        else:
            self.cell_capacity *= 2

    def resize_grid(self, capacity: int, cell_capacity: int) -> None:
        """Rebuild every neighbour list and cell row with room for ``capacity`` neighbours and
        ``cell_capacity`` bodies per cell (more if needed).

        Lists only say which pairs to examine; every scheduled event stays valid.
        """
        state = with_capacities(self.state, self.model.dim, capacity, cell_capacity)
        self.state, self.capacity, self.cell_capacity = _fit_lists(
            self.model, state, capacity, cell_capacity
        )

    def _drain(self, sink: Sink | None) -> None:
        """Hand the log buffer's collisions to ``sink``, in the caller's numbering (and to
        :attr:`events` when on)."""
        state = self.state
        n = int(state.log_n[0])
        if n == 0:
            return
        state.log_n[0] = 0
        if self.events.gathering:
            self._gather_events(n)
        if sink is None:
            return
        record = np.empty(n, dtype=COLLISION_DTYPE)
        record["time"] = state.log_time[:n]
        record["body"] = self.order[state.log_a[:n]]
        b = state.log_b[:n]
        face = -1 - b
        n_walls = 2 * self.env.dim
        record["kind"] = np.where(
            b >= 0, PARTNER_BODY, np.where(face < n_walls, PARTNER_WALL, PARTNER_PLANE)
        )
        record["partner"] = np.where(
            b >= 0, self.order[np.maximum(b, 0)], np.where(face < n_walls, face, face - n_walls)
        )
        record["impulse"] = state.log_impulse[:n]
        record["un_before"] = state.log_un[:n, 0]
        record["un_after"] = state.log_un[:n, 1]
        point = state.log_point[:n].copy()
        if self.env.periodic:  # the kernel writes raw coordinates: wrap them into the box
            dim = self.env.dim
            point[:, :dim] -= self.env.box * np.floor(point[:, :dim] / self.env.box)
        record["point"] = point
        sink(record)

    def _gather_events(self, n: int) -> None:
        """The log buffer's first ``n`` collisions to :attr:`events`: a face is partner -1."""
        state, dim = self.state, self.env.dim
        b = state.log_b[:n]
        point = state.log_point[:n, :dim].copy()
        if self.env.periodic:
            point -= self.env.box * np.floor(point / self.env.box)
        self.events.gather(
            state.log_time[:n], self.order[state.log_a[:n]],
            np.where(b >= 0, self.order[np.maximum(b, 0)], -1), state.log_un[:n, 0], point,
            state.log_normal[:n, :dim],
        )  # fmt: skip

    # -- reading ----------------------------------------------------------------------------

    def _to_user(self, rows: NDArray[Any]) -> NDArray[Any]:
        """Engine-ordered rows in the caller's numbering."""
        out = np.empty_like(rows)
        out[self.order] = rows
        return out

    def _motion_at_start(
        self, records: Records
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Every body's position, velocity, orientation and spin in the caller's numbering,
        from a new state's ``records`` (its ``kin``, ``w`` and ``orient``) before any event:
        what a failed build gives back to the bodies that lent them (positions wrapped into
        a periodic box, as the state holds them)."""
        kin, w, orient = records
        n, dim = kin.shape[0], self.env.dim
        x, v = self._to_user(kin[:, :dim]), self._to_user(kin[:, KIN_V : KIN_V + dim])
        if w is None or orient is None:
            return x, v, identity_orientations(n, dim), np.zeros((n, 3))
        return x, v, self._to_user(orient[:, : 4 if dim == 3 else 1]), self._to_user(w)

    def sample(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Positions (N, d), velocities (N, d), orientations ((N, 1) or (N, 4)) and angular
        velocities (N, 3) at the engine's clock, in the caller's numbering."""
        out = FrameArrays.empty(1, self.bodies.n, self.env.dim)
        sample_now(self.handle, *out)
        return out.positions[0], out.velocities[0], out.orientations[0], out.angular_velocities[0]

    def sample_motion(self) -> tuple[FloatArray, FloatArray]:
        """:meth:`sample`'s positions (N, d) and velocities (N, d) alone, the same numbers:
        half the memory of a sample of spheres in 3D, none of it spent on orientations."""
        n, dim = self.bodies.n, self.env.dim
        x, v = np.empty((1, n, dim)), np.empty((1, n, dim))
        sample_motion_now(self.handle, np.empty(1), x, v)
        return x[0], v[0]

    @property
    def spinning(self) -> bool:
        """False when the model has no spins: every body stays unrotated and still (a smooth
        law, and every body unrotated and still at the build)."""
        return self.model.q is not None

    def warm_up(self) -> None:
        """Load (or compile) the kernels of a run and of a sample, without a step or a
        sample (:meth:`load_sampler`); changes nothing."""
        self.advance(self.time, 0, None)  # no event is processed
        self.load_sampler()

    def load_sampler(self) -> None:
        """Load the kernels of :meth:`sample` and :meth:`sample_motion` from the cache (or
        compile them) without sampling: a sample of 10^6 spheres is 100 MB of new arrays that
        ``World.prepare`` would drop."""
        tiny = FrameArrays.empty(1, 1, self.env.dim)
        for kernel, arrays in ((sample_now, tiny), (sample_motion_now, tiny[:3])):
            compile_for = getattr(kernel, "compile", None)  # none without the JIT
            if compile_for is not None:
                compile_for(tuple(aside.typeof(a) for a in (self.handle, *arrays)))

    def counters(self) -> Counters:
        c, s = self.state.counts, self.state.sums
        return Counters(
            events=int(c[codes.C_EVENTS]),
            collisions=int(c[codes.C_PAIR]),
            wall_collisions=int(c[codes.C_WALL]),
            tc_collisions=int(c[codes.C_TC]),
            rests=int(c[codes.C_REST]),
            virial=float(s[codes.S_VIRIAL]),
            energy_lost=float(s[codes.S_KE_LOST]),
            floor_collisions=int(c[codes.C_FLOOR]),
            energy_given=float(s[codes.S_KE_GIVEN]),
            work_done=float(s[codes.S_WORK]),
        )

    def resting(self) -> NDArray[np.int64]:
        support = self.state.support
        if support is None:  # no gravity: nothing rests
            return np.full(self.bodies.n, -1, np.int64)
        return self._to_user(support)

    def neighbour_counts(self) -> NDArray[np.int64]:
        """How many neighbours each body's list holds now, (N,) (diagnostics and tests)."""
        return self._to_user(self.state.nbr_count)

    def max_cell_occupancy(self) -> int:
        """The most bodies in one cell now (diagnostics and tests)."""
        return int(self.state.cell_count.max())

    # -- reaching bodies between calls ------------------------------------------------------

    def _engine_rows(self, bodies: NDArray[np.int64]) -> NDArray[np.int64]:
        """Engine rows of the caller's ``bodies`` (k,)."""
        rank = np.empty_like(self.order)
        rank[self.order] = np.arange(self.order.shape[0])
        return rank[bodies]

    def motion_of(
        self, bodies: NDArray[np.int64]
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """The caller's ``bodies`` (k,) at the clock: positions (k, d), velocities (k, d),
        orientations ((k, 1) angles or (k, 4) quaternions) and spins (k, 3); nothing moves."""
        return self._motion(self._engine_rows(bodies))

    def _motion(
        self, rows: NDArray[np.int64]
    ) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """:meth:`motion_of` for engine ``rows`` (k,)."""
        k, dim = rows.shape[0], self.env.dim
        x, v = np.empty((1, k, dim)), np.empty((1, k, dim))  # (frame 0 of a sample)
        orient, w = np.empty((k, 4 if dim == 3 else 1)), np.empty((k, 3))
        bodies_now(self.handle, rows, x, v, orient, w)
        return x[0], v[0], orient, w

    def set_motion(self, bodies: NDArray[np.int64], field: str, values: FloatArray) -> None:
        """Give the caller's mobile ``bodies`` (k,) new ``values`` of ``field`` at the clock:
        "x" positions (k, d) [m], "v" velocities (k, d) [m/s], "w" spins (k, 3) or "omega"
        (k,) (2D, about z) [rad/s], "q" orientations (k, 4) or "angle" (k,) [rad]; their events
        are predicted again. The kinetic energy changed is booked as work done.

        Raises
        ------
        CaromError
            A spin or orientation in a world whose spheres do not spin; a position outside
            the box or the planes, or overlapping another sphere. Nothing has changed then.
        """
        rows = self._engine_rows(bodies)
        x, v, orient, w = self._motion(rows)
        before = self._kinetic(bodies, v, w)
        if field == "x":
            x = self._placed(bodies, values)
        elif field == "v":
            v = values
        else:
            if not self.spinning:
                raise CaromError(_NO_SPINS)
            if field == "w":
                w = values
            elif field == "omega":
                w[:, 2] = values
            elif field == "q":
                orient = values
            else:  # "angle"
                orient = values.reshape(-1, 1)
        self._give(bodies, rows, (x, v, orient, w), before, moved=field == "x")

    def apply_impulses(
        self, bodies: NDArray[np.int64], impulses: FloatArray, points: FloatArray | None
    ) -> None:
        """Impulses ``impulses`` (k, d) [N s] on the caller's mobile ``bodies`` (k,), in order,
        at the world ``points`` (k, d) [m] (the centres when None): velocity and spin change
        at the clock and the bodies' events are predicted again; the kinetic energy changed is
        booked as work done.

        Raises
        ------
        CaromError
            An impulse off the centre of a sphere that does not spin (a world without spins).
            Nothing has changed then.
        """
        rows = self._engine_rows(bodies)
        x, v, orient, w = self._motion(rows)
        b = self.bodies
        inv_mass = 1.0 / b.mass[bodies]
        dim = self.env.dim
        turns = np.zeros((bodies.shape[0], 3))
        if points is not None:
            arm = np.zeros((bodies.shape[0], 3))
            arm[:, :dim] = points - x
            push = np.zeros_like(arm)
            push[:, :dim] = impulses
            moment = b.inertia_factor[bodies] * b.mass[bodies] * b.radius[bodies] ** 2
            turns = np.cross(arm, push) / moment[:, None]
            if dim == 2:
                turns[:, :2] = 0.0
            if not self.spinning and np.any(turns != 0.0):
                raise CaromError(_NO_SPINS + "; or give the impulse at the centre (no point)")
        # in order: a body given twice takes both, the second after the first
        _, first, into = np.unique(bodies, return_index=True, return_inverse=True)
        before = self._kinetic(bodies[first], v[first], w[first])
        for r in range(bodies.shape[0]):
            j = first[into[r]]
            v[j] = v[j] + impulses[r] * inv_mass[r]
            w[j] = w[j] + turns[r]
        motion = (x[first], v[first], orient[first], w[first])
        self._give(bodies[first], rows[first], motion, before, moved=False)

    def _give(
        self, bodies: NDArray[np.int64], rows: NDArray[np.int64],
        motion: tuple[FloatArray, ...], before: float, *, moved: bool,
    ) -> None:  # fmt: skip
        """New ``motion`` (positions, velocities, orientations, spins) at the clock for the
        caller's ``bodies``, engine ``rows``, whose kinetic energy was ``before`` [J]: the
        change booked as work done, their events predicted again."""
        arrays = [np.ascontiguousarray(a, dtype=np.float64) for a in motion]
        while (status := set_bodies(self.handle, rows, *arrays, moved)) != FITS:  # type: ignore[call-arg]
            self._grow(codes.LISTS_FULL if status == LIST_FULL else codes.CELLS_FULL)
            self.resize_grid(self.capacity, self.cell_capacity)
        # (the bodies hold these velocities and spins now, bit for bit)
        after = self._kinetic(bodies, arrays[1], arrays[3])
        self.state.sums[codes.S_WORK] += after - before

    def energy_of(self, bodies: NDArray[np.int64]) -> float:
        """Mechanical energy [J] of the mobile ones among the caller's ``bodies`` (k,) at the
        clock: kinetic (translation and spin) and potential in gravity, ``-m g . x``."""
        moving = bodies[self.bodies.mobile[bodies]]
        x, v, _, w = self.motion_of(moving)
        potential = -float(np.sum(self.bodies.mass[moving] * (x @ self.env.gravity)))
        return self._kinetic(moving, v, w) + potential

    def book_work(self, work: float) -> None:
        """Book ``work`` [J] done on the bodies from outside the engine (their kinds switched:
        the energy that entered or left the count)."""
        self.state.sums[codes.S_WORK] += work

    # -- forces through a step (issue 43) ----------------------------------------------------

    _force: FloatArray | None = None

    def apply_forces(self, bodies: NDArray[np.int64], forces: FloatArray) -> None:
        """Forces ``forces`` (k, d) [N] at the centres of the caller's mobile ``bodies`` (k,)
        through the next :meth:`advance_step`, then cleared; given twice, they add up."""
        if self._force is None:
            self._force = np.zeros((self.bodies.n, self.env.dim))
        np.add.at(self._force, bodies, forces)

    def loads_now(self) -> tuple[FloatArray, FloatArray] | None:
        """The forces (n, d) [N] given for the next step and the torques (n,) (none: this
        engine takes none), copies; None when no force is given."""
        if self._force is None:
            return None
        return self._force.copy(), np.zeros(self.bodies.n)

    def take_loads(self, kept: tuple[FloatArray, FloatArray]) -> None:
        """The forces :meth:`loads_now` gave (an engine's this one replaces, over its first
        bodies), on the bodies still mobile, for the next step."""
        force = kept[0]
        rows = np.flatnonzero(self.bodies.mobile[: force.shape[0]])
        if rows.size:
            self.apply_forces(rows, force[rows])

    def advance_step(self, until: float, sink: Sink | None) -> bool:
        """:meth:`advance` to ``until`` [s] with the forces given for this step
        (:meth:`apply_forces`) acting throughout, then cleared.

        A force F on a body of mass m adds F / m to its pull from the clock on: it flies on
        the parabola of ``g + F / m``, exactly as under gravity, slides along a face it rests
        on (which bears the force's push into it) or lifts off one it pulls away from. At
        ``until`` the pull is gravity again and the events are predicted anew. The work the
        force did, ``F . (x(until) - x(start))`` (the path unwrapped in a periodic box), is
        booked in the ledger: a constant force's work whatever the impacts on the way.
        """
        force, self._force = self._force, None
        pushed = np.flatnonzero(np.any(force != 0.0, axis=1)) if force is not None else None
        if force is None or pushed is None or pushed.size == 0:
            return self.advance(until, np.iinfo(np.int64).max, sink)
        self._ready_for_forces()  # (and the wraps counted, in a periodic box)
        rows = self._engine_rows(pushed)
        given = force[pushed]
        extra = given / self.bodies.mass[pushed][:, None]
        set_pulls(self.handle, rows, extra)
        start = self._unwrapped(rows)
        try:
            return self.advance(until, np.iinfo(np.int64).max, sink)
        finally:  # (interrupted too: the force acted up to the clock, and stops there)
            rows = self._engine_rows(pushed)  # (a long step may have renumbered the rows)
            set_pulls(self.handle, rows, np.zeros_like(extra))
            moved = self._unwrapped(rows) - start
            self.state.sums[codes.S_WORK] += float(np.sum(given * moved))

    def _ready_for_forces(self) -> None:
        """Give an engine built without gravity (no accelerations kept) zero gravity and the
        arrays of accelerations, pulls and supports it needs to take a force; every path
        stays what it was (a straight line is the parabola of a zero acceleration). In a
        periodic box, the wraps are counted from now on (:attr:`State.wraps`)."""
        n, dim = self.state.kin.shape[0], self.env.dim
        if self.env.periodic and len(self.state.wraps) == 0:
            self.state = self.state._replace(wraps=np.zeros((n, dim)))
        if self.state.pull is not None:
            return
        self.model = self.model._replace(gravity=np.zeros(dim))
        acc = np.zeros((n, dim))
        self.state = self.state._replace(
            acc=acc, pull=acc.copy(), support=np.full(n, -1, np.int64)
        )  # (the handle is made again: see the state's setter)

    def _unwrapped(self, rows: NDArray[np.int64]) -> FloatArray:
        """Engine ``rows``' positions (k, d) [m] as of their own clocks, unwrapped: a
        periodic box's wraps (:attr:`State.wraps`) added back."""
        s, dim = self.state, self.env.dim
        x = s.kin[rows, :dim].copy()
        if len(s.wraps):  # (a periodic box, counted since the first force)
            x += s.wraps[rows] * self.env.box
        return x

    def retire(self, ids: NDArray[np.int64]) -> None:
        """Take the caller's bodies ``ids`` (k,) out of the world for good, their indices
        kept: each stops where it is at the clock (the kinetic energy it had leaves the
        ledger as work done on it), no other sphere meets it again, and it has no event
        (:func:`carom.engines.edmd.reach.retire_bodies`)."""
        bodies = np.unique(ids)
        rows = self._engine_rows(bodies)
        _, v, _, w = self._motion(rows)
        moving = self.bodies.mobile[bodies]  # (a static sphere has no kinetic energy)
        before = self._kinetic(bodies[moving], v[moving], w[moving])
        self._retire_rows(rows)
        self.state.sums[codes.S_WORK] -= before

    def _retire_rows(self, rows: NDArray[np.int64]) -> None:
        while (status := retire_bodies(self.handle, rows)) != FITS:
            self._grow(codes.LISTS_FULL if status == LIST_FULL else codes.CELLS_FULL)
            self.resize_grid(self.capacity, self.cell_capacity)

    def _kinetic(self, bodies: NDArray[np.int64], v: FloatArray, w: FloatArray) -> float:
        """Kinetic energy [J] of the caller's ``bodies`` (k,) at velocities ``v`` (k, d) and
        spins ``w`` (k, 3)."""
        b = self.bodies
        mass = b.mass[bodies]
        spin = b.inertia_factor[bodies] * mass * b.radius[bodies] ** 2
        return float(0.5 * np.sum(mass * np.sum(v * v, axis=1) + spin * np.sum(w * w, axis=1)))

    def _placed(self, bodies: NDArray[np.int64], at: FloatArray) -> FloatArray:
        """Positions ``at`` (k, d) for the caller's ``bodies`` (k,), wrapped into a periodic
        box; a CaromError if one leaves the box or the planes or overlaps another sphere."""
        env, radius = self.env, self.bodies.radius
        at = np.array(at, dtype=np.float64)
        if np.unique(bodies).shape[0] != bodies.shape[0]:
            raise CaromError("positions: each body once (a body cannot be in two places)")
        if env.periodic:
            at -= env.box * np.floor(at / env.box)
        r = radius[bodies]
        for k, body in enumerate(bodies.tolist()):
            inside = at[k] - r[k] >= 0.0
            inside &= at[k] + r[k] <= env.box
            if not env.periodic and not inside.all():
                raise CaromError(
                    f"body {body} at {at[k].tolist()} would leave the box "
                    f"{env.box.tolist()} (radius {r[k]:g} m); place its centre at least its "
                    "radius inside the walls"
                )
            depth = (at[k] - env.plane_point) @ np.asarray(env.plane_normal).T
            if np.any(np.atleast_1d(depth) < r[k]):
                raise CaromError(
                    f"body {body} at {at[k].tolist()} would cut a plane of the world; place "
                    "its centre at least its radius on the planes' open side"
                )
        x, _ = self.sample_motion()
        x[bodies] = at
        gone = self.order[np.isnan(self.state.shell[:, 3])]  # (taken out: met by none)
        for k, body in enumerate(bodies.tolist()):
            gap = x - at[k]
            if env.periodic:
                gap -= env.box * np.round(gap / env.box)
            reach = np.sqrt(np.sum(gap * gap, axis=1)) - radius - r[k]
            reach[body] = np.inf
            reach[gone] = np.inf
            other = int(np.argmin(reach))
            if reach[other] < -OVERLAP_TOLERANCE * (radius[other] + r[k]):
                raise CaromError(
                    f"body {body} at {at[k].tolist()} would overlap body {other} (at "
                    f"{x[other].tolist()}) by {-reach[other]:.3g} m; place the spheres at "
                    "least the sum of their radii apart"
                )
        return at

    # -- checkpoints ------------------------------------------------------------------------

    def arrays(self) -> dict[str, NDArray[Any]]:
        # (a field that is None is not written: OPTIONAL names them)
        arrays: dict[str, NDArray[Any]] = {
            f"state.{name}": value
            for name, value in self.state._asdict().items()
            if value is not None
        }
        arrays["order"] = self.order
        arrays["capacity"] = np.array([self.capacity, self.cell_capacity])
        return arrays

    @classmethod
    def restore(
        cls,
        bodies: Bodies,
        env: Environment,
        settings: EdmdSettings,
        arrays: Mapping[str, NDArray[Any]],
    ) -> EdmdEngine:
        """The engine saved by :meth:`arrays`, continuing bit for bit. The records are copied
        onto cache lines (``aligned_records``) as soon as they are read, and the array read is
        let go before the next one (a checkpoint's arrays are read as they are asked for)."""
        fields: dict[str, Any] = {}
        for name in State._fields:  # (kin first)
            value = arrays.get(f"state.{name}")
            if value is not None and name == "kin":
                value = aligned_records(len(value), value)
            elif value is not None and name == "nbr":  # (its rows on cache lines too)
                aligned = aligned_rows(value.shape[0], value.shape[1], np.int32)
                aligned[...] = value
                value = aligned
            fields[name] = value
        apart = [f"state.{name}" for name in ("cal_next", "cal_prev", "cal_loc", "cur_where")]
        if fields["cal_body"] is None and all(name in arrays for name in apart):
            # (saved when the calendar's four per-body arrays were apart)
            fields["cal_body"] = np.stack([arrays[name] for name in apart], axis=1).astype(np.int32)
        sched = fields["sched"]
        if fields["counter"] is None and sched is not None and sched.shape[1] == 4:
            # (saved when the counters were the schedule's fourth column; stamps as they
            # compare with 4-byte counters)
            fields["counter"] = sched[:, 3].astype(np.int32)
            fields["sched"] = sched[:, :SCHED_WIDTH].copy()
            fields["sched"][:, SCHED_STAMP] = sched[:, SCHED_STAMP].astype(np.int32)
        missing = [name for name, v in fields.items() if v is None and name not in OPTIONAL]
        for group in (GRAVITY_FIELDS, SPIN_FIELDS):  # each all there or all absent
            there = [fields[name] is not None for name in group]
            if any(there) and not all(there):
                missing.append(group[there.index(False)])
        if missing:
            raise KeyError(f"state.{missing[0]}")  # (the checkpoint reader calls it damaged)
        order = arrays["order"]
        if fields["acc"] is not None and fields["pull"] is None:  # (saved before forces)
            # between steps every pull is gravity, zero for the static and those taken out
            pulled = np.isfinite(bodies.mass[order]) & ~np.isnan(fields["shell"][:, 3])
            fields["pull"] = np.where(pulled[:, None], env.gravity[None, :], 0.0)
        if fields["wraps"] is None:  # (saved before forces: none counted yet)
            fields["wraps"] = np.zeros((0, env.dim))
        if fields["log_normal"] is None:  # (saved before the log kept normals)
            fields["log_normal"] = np.zeros((fields["log_time"].shape[0], 3))
        if fields["sums"].shape[0] < N_SUMS:  # (saved before the work done was kept)
            fields["sums"] = np.concatenate(
                (fields["sums"], np.zeros(N_SUMS - fields["sums"].shape[0]))
            )
        state = State(**fields)
        capacity, cell_capacity = (int(c) for c in arrays["capacity"])
        engine = cls(
            bodies,
            env,
            settings,
            float(state.clock[0]),
            state=state,
            order=order,
            capacity=capacity,
            cell_capacity=cell_capacity,
        )
        bodies.lend(engine)  # the table's motion: the engine's, at its clock
        return engine


_NO_SPINS = (
    "this world's spheres do not spin (smooth contacts, none spinning or turned at the "
    "start), so the event-driven engine keeps no spins: give them friction (a rough contact "
    "law) or a spin at the start"
)

#: the state's fields a checkpoint may lack: acc and support are None without gravity, the
#: spins and orientations when no body spins (and then not written)
GRAVITY_FIELDS = ("acc", "support")
SPIN_FIELDS = ("w", "orient", "orient_t")
OPTIONAL = (*GRAVITY_FIELDS, *SPIN_FIELDS, "log_normal", "pull", "wraps")


def spinning(bodies: Bodies, env: Environment) -> bool:
    """Whether a body may ever spin or is turned: some pair law is not smooth (walls and
    planes are), or some body has a spin or an orientation other than the identity (compared
    bit for bit: a spin of -0.0 counts, so that frames give it back as it was)."""
    # (the table stores spins and orientations only when some are not +0.0 and the identity)
    return bool(np.any(env.pairs.law != LAW_SMOOTH)) or not (bodies.still and bodies.unrotated)


def with_capacities(state: State, dim: int, capacity: int, cell_capacity: int) -> State:
    """``state`` of bodies in ``dim`` dimensions with empty neighbour lists of ``capacity``
    and cell rows of ``cell_capacity`` (and scratch to match), to be filled again
    (``build_all``, which zeroes each list's row as it first writes it)."""
    return state._replace(
        nbr=aligned_rows(state.kin.shape[0], capacity, np.int32),
        cell_body=np.zeros((state.cell_count.shape[0], cell_capacity), np.int32),
        **scratch(dim, capacity, cell_capacity),
    )


def _build_lists(model: Model, state: State) -> int:
    """Every neighbour list and cell row of ``state`` built afresh from its shells
    (:func:`carom.engines.edmd.neighbours.build_all`): ``FITS``, ``LIST_FULL`` or
    ``CELL_FULL``."""
    return build_all(
        state.shell,
        model.mobile,
        state.nbr,
        state.nbr_count,
        state.cell_count,
        state.cell_body,
        state.slot,
        state.cell,
        model.box,
        model.periodic,
        model.shell_thickness,
        model.cell_size,
        model.ncell,
    )


def _fit_lists(
    model: Model, state: State, capacity: int, cell_capacity: int
) -> tuple[State, int, int]:
    """Build every list of ``state`` (made with room for ``capacity`` neighbours and
    ``cell_capacity`` bodies a cell), doubling the room that runs out and building again
    until all fit: the state and the two capacities it was built with."""
    while True:
        status = _build_lists(model, state)
        if status == FITS:
            return state, capacity, cell_capacity
        if status == LIST_FULL:
            capacity *= 2
        else:
            cell_capacity *= 2
        state = with_capacities(state, model.dim, capacity, cell_capacity)


def _calendar(s: State) -> Calendar:
    """The event calendar's arrays of state ``s``, as ``predict.calendar_of`` gives them to
    the kernels."""
    cal_next, cal_prev, cal_loc, cur_where = calendar_views(s.cal_body)
    return (
        s.cal_head, cal_next, cal_prev, cal_loc, s.cur_heap, s.cur_key, cur_where, s.cal_f,
        s.cal_i,
    )  # fmt: skip
