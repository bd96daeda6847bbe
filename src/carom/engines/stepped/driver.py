"""SteppedEngine: the time-stepped rigid engine's driver, one for 2D and 3D.

One step (``dt = 1/rate``) runs these stages, in this order (docs/rigid.md); each dimension
names its kernels for the stages that differ (:class:`carom.engines.rigid.driver.RigidEngine`,
:class:`carom.engines.rigid3d.driver.RigidEngine3D`):

1. **place**: the moving bodies' pieces in the world;
2. **broad phase**: pairs of pieces whose swept boxes overlap
   (:mod:`carom.engines.stepped.broadphase`);
3. **narrow phase**: their manifolds, warm-started from the last step; an awake body touching
   a sleeping island wakes it, and the phases run again;
4. **islands**: each body's role: free flight, an island solved exactly, or the solver
   (:mod:`carom.engines.stepped.islands`); in 3D a ball on a level cloth has its cloth left
   out (:mod:`carom.engines.rigid3d.cloth`);
5. **exact impacts**: the islands solved exactly advanced through the step, their impacts
   taken in the order they happen, each at its time of impact
   (:mod:`carom.engines.stepped.impacts`; balls on the cloth roll in closed form between);
6. **free flight**: bodies with no contact; in 3D, balls alone on a level cloth roll in
   closed form;
7. **solve**: the soft step over the remaining contacts; a solved body that moved far is swept
   against the static geometry its contacts did not hold, and put back at the first touch;
8. **store** the impulses for the next step, and **sleep** the islands at rest (their bodies
   stop, as in Box2D; the kinetic energy they kept goes to the ledger as lost).

Beside the step: the clock (whole steps, and a shorter one to end on a time asked between two),
advancing to a time or through frames, warming up, and the running totals that ``counters``
reports and a checkpoint keeps.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from time import perf_counter
from typing import Any, NamedTuple, Self

import numpy as np
from numpy.typing import NDArray

from carom.engines.base import COLLISION_DTYPE, PARTNER_BODY, Counters, FrameArrays, Partners, Sink
from carom.engines.stepped import islands
from carom.engines.stepped.broadphase import KeptPairs, find_pairs, grid_cell, repair_pairs
from carom.engines.stepped.contacts import extremes, store_points
from carom.engines.stepped.events import ContactEvents
from carom.engines.stepped.filters import default_filters, filter_pairs
from carom.engines.stepped.joints import (
    JOINT_INTS,
    joined_keys,
    joints_now,
    links,
)
from carom.engines.stepped.loads import Loaded, Loads
from carom.engines.stepped.memory import (
    Laws,
    Remembered,
    StepMemory,
    carried,
    new_memory,
    rekeyed,
    remembered,
    renumbering,
)
from carom.engines.stepped.rows import I_BODY_A, I_BODY_B, I_COUNT, point_layout
from carom.engines.stepped.sensors import Sensors
from carom.engines.stepped.settings import RigidSettings
from carom.geometry.bvh import build_bvh, empty_bvh
from carom.laws.kinds import KIND_DYNAMIC, KIND_KINEMATIC

__all__ = ["STAGES", "STOP_CHECK_STEPS", "Isolated", "SteppedEngine"]

FloatArray = NDArray[np.float64]

#: the stages of a step as :attr:`SteppedEngine.stage_seconds` times them (module docstring:
#: 1-3, 4, 5, 6, 7, 8)
STAGES = ("contacts", "islands", "exact impacts", "free flight", "solver", "store and sleep")
#: steps between looks at a run's stop request
STOP_CHECK_STEPS = 64


class Isolated(NamedTuple):
    """The islands a step solves exactly: their contact ``rows``, island k's
    ``rows[first[k]:first[k + 1]]``, ``n`` islands
    (:func:`carom.engines.stepped.islands.plan`)."""

    rows: NDArray[np.int64]
    first: NDArray[np.int64]
    n: int


class SteppedEngine:
    """A time-stepped rigid engine, the same for 2D and 3D: the stages of a step (module
    docstring), the clock (whole steps, a shorter one to end on a time), advancing to a time or
    through frames, and the running totals (collisions with bodies and with walls or planes,
    the energy ledger) that :meth:`counters` reports and a checkpoint keeps.

    Parameters
    ----------
    model : RigidModel or Model3D
        The constants.
    state : RigidState or State3D
        The state at ``time``; the engine advances it in place.
    settings : RigidSettings
    time : float
        The clock at ``state`` [s].
    partners : Partners, optional
        What each body is to a collision record; the caller's bodies are those of kind
        ``PARTNER_BODY`` (the first ones), walls and planes follow. Default: all bodies are the
        caller's.
    memory : StepMemory, optional
        Sleep and the warm-start cache at ``time``; default every dynamic body awake, no
        contact cached.

    Notes
    -----
    A dimension's engine is a subclass naming its kernels: ``DIMS``; its contact rows' module
    ``ROWS`` (the float columns ``CONTACT_FLOATS``, ``POINT0``, ``POINT_FLOATS``, ``P_SEP``,
    ``P_VREL``, ``P_JN``; ``CONTACT_INTS``, ``MAX_POINTS``, ``point_offset``, the shape of a
    cached contact's impulses ``CACHE_IMPULSES`` and ``store_tangents``); its impacts' module
    ``IMPACTS`` (``IMPACT_FIELDS``); the state's ``SPIN`` field; and the stages that differ by
    dimension:
    :meth:`_setup`, :meth:`_pairs`, :meth:`_narrow`, :meth:`_impact_kernel`, :meth:`_fly`,
    :meth:`_solve`, :meth:`_fastest`, :meth:`_stop`, :meth:`_energy`, :meth:`sample`,
    :meth:`_state_from` and :meth:`_warm_kernels`.

    The counters keep the energy ledger: ``work_done`` is what kinematic bodies put in (each
    impulse on a body times the kinematic body's velocity at the contact point, summed as the
    solver and the exact impacts apply them), ``energy_lost`` what the impacts solved exactly
    and the solver took out of the bodies' kinetic and potential energy beyond that work,
    ``energy_given`` what the solver put in (pushing overlaps apart), step by step, so that
    ``E0 + work_done = E + energy_lost - energy_given``.
    """

    name = "rigid"
    DIMS: int
    #: the float columns of a joint row (the dimension's joints module)
    JOINT_FLOATS: int
    ROWS: Any
    IMPACTS: Any
    #: the state's fields of the bodies' turn and spin
    TURN: str
    SPIN: str
    #: the model's contact tables over the materials, which sleep depends on
    LAW_TABLES: tuple[str, ...] = ("e_table", "mu_table")
    #: a touching pair whose every point separates faster than this fraction of the
    #: restitution threshold has just bounced: it flies apart on the exact path (free flight
    #: keeps its energy and angular momentum exactly), not through the solver, whose soft
    #: contact would take energy from a bounce ended just before the step. Resting contacts
    #: never separate that fast. (inf: never)
    LEAVING: float = 0.1

    start: float
    steps: int
    dt: float
    n_bodies: int
    partners: Partners

    def __init__(
        self,
        model: Any,
        state: Any,
        settings: RigidSettings,
        time: float = 0.0,
        partners: Partners | None = None,
        memory: StepMemory | None = None,
    ) -> None:
        self.model = model
        self.state = state
        self.settings = settings
        self._start_totals(time)
        #: the step [s]: the settings' own, another during a step of another length
        self.dt = settings.dt
        n = model.kind.shape[0]
        if partners is None:
            partners = Partners(np.zeros(n, np.int8), np.arange(n, dtype=np.int64))
        self.partners = partners
        #: the caller's bodies: the first ``n_bodies``
        self.n_bodies = int(np.count_nonzero(partners.kind == PARTNER_BODY))
        #: each row's body number for the caller (-1: a wall or plane of the scenery)
        self.callers = np.where(partners.kind == PARTNER_BODY, partners.number, -1)
        #: the contact events of the last step (:mod:`.events`)
        self.events = ContactEvents(self.DIMS, self.callers, point_layout(self.DIMS))
        self.sensors = Sensors(self.callers, model.piece_body.shape[0])
        self.cell = grid_cell(model.kind, model.piece_body, model.piece_reach)
        rows, dims = self.ROWS, self.DIMS
        self._cf = np.zeros((max(64, 2 * n), rows.CONTACT_FLOATS))
        self._ci = np.zeros((max(64, 2 * n), rows.CONTACT_INTS), np.int64)
        pieces = model.piece_body.shape[0]
        self._boxes = np.zeros((pieces, 2 * dims))
        self._parent = np.zeros(n, np.int64)
        self._no_joints = np.zeros(0, np.int64)  # (the joints and bodies of no joint)
        self._none_jointed = np.zeros(n, np.bool_)
        self._role = np.zeros(n, np.int64)
        self._island_of = np.zeros(n, np.int64)
        self._dynamic = model.kind == KIND_DYNAMIC
        self._kinematic = model.kind == KIND_KINEMATIC
        #: the kinematic bodies (indices)
        self._movers = np.flatnonzero(self._kinematic)
        self._accel = np.zeros((n, dims))
        self._accel[self._dynamic] = model.gravity
        #: each piece's collision filter (:func:`.filters.piece_filters`: its body's, none for
        #: a sensor's piece), and whether any is not the default
        self.filters = default_filters(model.piece_body.shape[0])
        self.filtered = False
        #: the joints (:mod:`.joints`): integer and float rows (the world's own arrays,
        #: shared: the solver writes their impulses and reactions in place), the bodies they
        #: join (-1: the world) and the pairs they keep from touching
        self.joint_ints = np.zeros((0, JOINT_INTS), np.int64)
        self.joint_floats = np.zeros((0, self.JOINT_FLOATS))
        self._links = np.zeros((0, 2), np.int64)
        self._joined = np.zeros(0, np.int64)
        #: the forces and torques given for the next step; during a step, the most they
        #: accelerate each body's points [m/s^2] and each body's angular acceleration
        #: [rad/s^2] in 2D, the torque [N m] in 3D (zeros without loads)
        self._loads = loads = Loads(n, dims)
        self._pull = loads.no_pull
        self._spin_load = np.zeros_like(loads.torque)
        self._no_impacts = np.zeros((0, self.IMPACTS.IMPACT_FIELDS))
        self._nowhere = np.zeros((0, dims))  # no points: impulses at the centres
        self._g = float(np.linalg.norm(model.gravity))
        self.n_contacts = 0
        #: the wall time [s] the last step spent in each of :data:`STAGES`
        self.stage_seconds = (0.0,) * len(STAGES)
        self._n_pairs = 0  # the broad phase's pairs at the last step, the filters' kept
        self._n_found = 0  # (and all it found: sensors look through them)
        # what every step reads the same way: the rows' columns the shared kernels take, a
        # cached contact's values per point, the leaving speed (inf: never)
        self._extremes_layout = (rows.POINT0, rows.POINT_FLOATS, rows.P_SEP, rows.P_VREL)
        self._store_layout = (rows.POINT0, rows.POINT_FLOATS, rows.P_JN)
        self._per_point = math.prod(rows.CACHE_IMPULSES) // rows.MAX_POINTS
        threshold = settings.restitution_threshold
        self._leaving = math.inf if math.isinf(self.LEAVING) else self.LEAVING * threshold
        #: a touching contact closing faster than this [m/s] is an impact, not a resting
        #: contact: the restitution threshold, or twice what gravity adds in a step if less
        #: (a resting contact starts a step hardly closing: the solver's last pass left it at
        #: rest; a box rocking onto a corner at 0.8 m/s is an impact, solved exactly)
        self._closing_fast = min(threshold, 2.0 * self._g * self.dt) if self._g > 0 else threshold
        if memory is None:
            memory = new_memory(model.kind, rows.MAX_POINTS, rows.CACHE_IMPULSES)
        #: sleep and the warm-start cache
        self.memory = memory
        self._setup()
        self._settle_statics()

    def _settle_statics(self) -> None:
        """The broad phase's pairs kept from step to step, the static bodies' pieces (their
        boxes finite: a plane's is not) in a tree built once (:func:`find_pairs`)."""
        model = self.model
        pieces = model.piece_body.shape[0]
        self._kept = KeptPairs(pieces, self.DIMS, model.kind.shape[0], self._find, self._repair)
        static = ~(self._dynamic | self._kinematic)
        self._rest_boxes()
        bounded = np.all(np.isfinite(self._boxes), axis=1)
        still = np.flatnonzero(static[model.piece_body] & bounded)
        self._kept.settle(self._boxes, still)
        self._tree = tree = build_bvh(self._kept.fat, still)
        #: what an island solved exactly looks through when a body turns where its broad
        #: phase did not look: the static tree (and its items' boxes), the static pieces it
        #: does not hold, the pieces of bodies that are not static
        self._reach = (
            (tree.box, tree.left, tree.first, tree.count, tree.order, self._kept.fat),
            np.flatnonzero(static[model.piece_body] & ~bounded).astype(np.int64),
            np.flatnonzero(~static[model.piece_body]).astype(np.int64),
            self.filters,
        )
        self._now = self._kept.pairs  # the pairs this step (filtered: a copy)

    def _find(self, boxes: NDArray[np.float64], active: NDArray[np.bool_], out: Any) -> int:
        tree = self._tree
        return int(
            find_pairs(
                boxes, self.model.piece_body, active, self._dynamic, self.cell, self._kept.loose,
                tree.box, tree.left, tree.first, tree.count, tree.order, out,
            )
        )  # fmt: skip

    def _repair(
        self, fat: NDArray[np.float64], active: NDArray[np.bool_], moved: NDArray[np.int64],
        n_moved: int, old: NDArray[np.int64], n_old: int, out: NDArray[np.int64],
    ) -> int:  # fmt: skip
        tree = self._tree
        return int(
            repair_pairs(
                fat, moved, n_moved, self.model.piece_body, active, self._dynamic,
                self._kept.loose, (tree.box, tree.left, tree.first, tree.count, tree.order),
                old, n_old, out,
            )
        )  # fmt: skip

    def _setup(self) -> None:
        """The dimension's own set-up, after the shared one."""

    def _rest_boxes(self) -> None:
        """Every piece's box as it stands, not swept, into ``_boxes`` (after :meth:`_setup`:
        the pieces placed)."""
        raise NotImplementedError

    @classmethod
    def restore(
        cls,
        model: Any,
        settings: RigidSettings,
        partners: Partners,
        arrays: Mapping[str, NDArray[Any]],
    ) -> Self:
        """The engine that wrote ``arrays`` (:meth:`arrays`), to continue bit for bit."""
        memory = StepMemory(*(np.array(arrays[name]) for name in StepMemory._fields))
        engine = cls(
            model, cls._state_from(arrays), settings, float(arrays["start"][0]), partners, memory
        )
        engine._restore_totals(arrays)
        return engine

    @staticmethod
    def _state_from(arrays: Mapping[str, NDArray[Any]]) -> Any:
        """The state kept in a checkpoint's ``arrays``."""
        raise NotImplementedError

    def arrays(self) -> dict[str, NDArray[Any]]:
        """The state's arrays and the clock and totals, for a checkpoint."""
        kept = self.state._asdict() | self.memory._asdict()
        return {name: np.array(value) for name, value in kept.items()} | self._totals()

    def _start_totals(self, time: float) -> None:
        self.start = float(time)
        self.steps = 0
        #: the steps taken when the clock was at ``start`` (a shorter step, to reach a time
        #: between two steps, moves the clock's origin there)
        self.base = 0
        self._collisions = 0
        self._wall_collisions = 0
        self._energy_lost = 0.0
        self._energy_given = 0.0
        self._work_done = 0.0

    # -- one step -------------------------------------------------------------------------

    def step(self, sink: Sink | None = None) -> None:
        """Advance one step of ``dt`` [s]: stages 1 to 8 (module docstring)."""
        m, mem, st = self.model, self.memory, self.settings
        rows = self.ROWS
        t0 = perf_counter()
        loaded = self._load() if self._loads.on else None
        nc = self._contacts()
        if st.sleep and islands.wake(
            self._ci, nc, m.kind, mem.awake, self._moving(), mem.clock, mem.island, self._links
        ):
            nc = self._contacts()
        t1 = perf_counter()
        n = m.kind.shape[0]
        isolated = np.zeros(max(nc, 1), np.int64)
        island_first = np.zeros(n + 1, np.int64)
        closest, closing = extremes(self._cf, self._ci, nc, self._extremes_layout)
        skip = self._on_cloth(nc, closest, closing, loaded)
        n_iso = islands.plan(
            self._ci, nc, closest, closing, skip, m.kind, mem.awake, st.exact_impacts,
            0.1 * st.linear_slop, self._closing_fast, self._leaving,
            self._loads.none_torqued if loaded is None else loaded.torqued, self._links,
            self._parent,
            self._role, isolated, island_first, self._island_of,
        )  # fmt: skip
        t2 = perf_counter()
        met = self._no_impacts
        if n_iso:
            todo = Isolated(isolated, island_first, n_iso)
            log, logged = self._impact_kernel(todo)
            # the islands it handed back (island -1) are the solver's, the whole step
            self._role[(self._role == islands.ROLE_EXACT) & (self._island_of < 0)] = (
                islands.ROLE_SOLVER
            )
            if logged:
                met = log[:logged]
                self._book(met, sink)
        t3 = perf_counter()
        self._roll_cloth()
        free = np.flatnonzero(self._role == islands.ROLE_FREE)
        if loaded is None:
            self._fly(free)
        else:  # a free body's load does all the work on it
            pushed = free[loaded.on[free]]
            before = self._energy(pushed)
            self._fly(free)
            self._work_done += self._energy(pushed) - before
        t4 = perf_counter()
        bodies = self._solver_bodies()
        before = self._energy(bodies)
        work = np.zeros(1)  # by kinematic bodies on the others, this step [J]
        poses = self._poses() if bodies.size else None
        self._solve(nc, bodies, work)
        if poses is not None:
            self._continuous(nc, closest, bodies, poses)
        if loaded is not None:
            work[0] += self._load_work(bodies, loaded)
        self._work_done += work[0]
        change = self._energy(bodies) - before - work[0]  # the solver's own part
        if change < 0.0:
            self._energy_lost -= change
        else:
            self._energy_given += change
        t5 = perf_counter()
        if mem.cache_keys.shape[0] < nc:
            size = max(nc, 2 * mem.cache_keys.shape[0])
            self.memory = mem = mem._replace(
                cache_keys=np.zeros(size, np.int64),
                cache_ids=np.zeros((size, *mem.cache_ids.shape[1:]), np.int64),
                cache_impulses=np.zeros((size, *mem.cache_impulses.shape[1:])),
            )
        # the cache as (K, points, values): a view (2D keeps (K, 4), 3D (K, 4, 4))
        size = mem.cache_keys.shape[0]
        cache = mem.cache_impulses.reshape(size, rows.MAX_POINTS, self._per_point)
        mem.cache_count[0] = store_points(
            self._cf, self._ci, nc, m.piece_body.shape[0], self._store_layout, mem.cache_keys,
            mem.cache_ids, cache,
        )  # fmt: skip
        rows.store_tangents(self._cf, self._ci, nc, cache)
        self._keep_manifolds()
        if self.events.on:
            self.events.update(
                (self._cf, self._ci, nc), (rows.POINT0, rows.POINT_FLOATS, rows.I_FLAGS),
                st.linear_slop, met, self.time, self._dynamic & mem.awake,
            )  # fmt: skip
            if self.sensors.on:
                self.sensors.update(self._sensed(), self._dynamic & mem.awake)
        if loaded is not None:
            self._work_done += self._load_work(
                np.flatnonzero(self._role == islands.ROLE_EXACT), loaded
            )
            self._unload()
        if st.sleep:
            self._settle(nc)
        self.n_contacts = nc
        self.steps += 1
        t6 = perf_counter()
        self.stage_seconds = (t1 - t0, t2 - t1, t3 - t2, t4 - t3, t5 - t4, t6 - t5)

    # -- what a debug drawing shows (carom play) ---------------------------------------------

    def awake_islands(self) -> int:
        """The awake islands at the last step: dynamic bodies joined by contacts or joints,
        one island each group (a lone awake body is one)."""
        awake = self._dynamic & self.memory.awake
        return int(np.unique(self._parent[awake]).size)

    def contact_points(self) -> FloatArray:
        """Every contact point of the last step (C, 2 d + 1): the point [m], the unit normal
        (from B to A) and the normal impulse it took over the step [N s]."""
        rows, d, nc = self.ROWS, self.DIMS, self.n_contacts
        at, total = point_layout(d).at, point_layout(d).total
        cf, count = self._cf[:nc], self._ci[:nc, I_COUNT]
        parts = []
        for j in range(rows.MAX_POINTS):
            has = count > j
            start = rows.POINT0 + j * rows.POINT_FLOATS
            parts.append(
                np.hstack(
                    (
                        cf[has, start + at : start + at + d],
                        cf[has, rows.F_NX : rows.F_NX + d],
                        cf[has, start + total : start + total + 1],
                    )
                )
            )
        return np.concatenate(parts) if parts else np.zeros((0, 2 * d + 1))

    def fat_boxes(self) -> FloatArray:
        """The broad phase's boxes (P, 2 d) [m], one a piece: lower corner, upper corner (each
        grown around the piece's swept box, as Box2D's enlarged boxes)."""
        return np.array(self._kept.fat, dtype=float)

    def _load(self) -> Loaded:
        """Take the loads given for this step (:mod:`.loads`): each dynamic body's acceleration
        gains ``F / m``, its points' reach the load's pull, its spin the torque; return the
        bodies loaded, their positions now, those torqued, and their orientations now (2D:
        the angles; 3D: none kept), for :meth:`_load_work`."""
        m, loads = self.model, self._loads
        on = loads.loaded()
        dynamic = self._dynamic
        self._accel[dynamic] += loads.force[dynamic] * m.inv_mass[dynamic, None]
        self._pull = loads.pull(m.inv_mass, m.inv_inertia, m.reach)
        self._spin_load = self._spin_of(loads.torque)
        turn = self.state.angle.copy() if self.DIMS == 2 else np.zeros(0)
        return Loaded(on, self.state.x.copy(), loads.torqued(), turn)

    def _spin_of(self, torque: FloatArray) -> FloatArray:
        """What the solver and free flight take of the torques (N,) or (N, 3) [N m]: 2D, the
        angular accelerations [rad/s^2]; 3D, the torques themselves."""
        return torque

    def _load_work(self, rows: NDArray[np.int64], loaded: Loaded) -> float:
        """The work [J] the loads did on the bodies ``rows`` over the step: ``F . dx`` (exact
        for a force constant through the step), and in 2D ``T dtheta`` (3D: the solver books
        its torques' work, and the torques' islands are never solved exactly)."""
        on, x0, _, turn0 = loaded
        rows = rows[on[rows]]
        if rows.size == 0:
            return 0.0
        loads, s = self._loads, self.state
        work = float(np.sum(loads.force[rows] * (s.x[rows] - x0[rows])))
        if self.DIMS == 2:
            work += float(np.sum(loads.torque[rows] * (s.angle[rows] - turn0[rows])))
        return work

    def _unload(self) -> None:
        """After the step: the loads cleared, each dynamic body's acceleration gravity again."""
        self._accel[self._dynamic] = self.model.gravity
        self._pull = self._loads.no_pull
        self._spin_load = np.zeros_like(self._loads.torque)
        self._loads.clear()

    def _contacts(self) -> int:
        """Stages 1 to 3: the contacts at the start of the step, into rows ``_cf``, ``_ci``;
        return how many."""
        n_pairs = self._n_found = self._pairs()
        self._now = self._kept.pairs
        if self.filtered or self._joined.size:
            # the pairs the filters and joints keep, into a copy (the kept ones stay whole)
            self._now = np.empty_like(self._kept.pairs)
            n_pairs = filter_pairs(
                self._kept.pairs,
                n_pairs,
                self.model.piece_body,
                self.filters,
                self._joined,
                self.model.kind.shape[0],
                self._now,
            )
        self._n_pairs = n_pairs
        while True:
            nc = self._narrow(n_pairs)
            if nc >= 0:
                return nc
            self._grow(2 * -nc)

    def _pairs(self) -> int:
        """Stages 1 and 2: place the moving bodies' pieces and find the pairs of swept boxes
        that overlap, into ``_kept.pairs``; return how many."""
        raise NotImplementedError

    def _narrow(self, n_pairs: int) -> int:
        """Stage 3: the manifolds of the pairs into the contact rows; return how many, or
        minus the rows needed when they do not fit."""
        raise NotImplementedError

    def _grow(self, size: int) -> None:
        """Room for ``size`` contact rows."""
        self._cf = np.zeros((size, self.ROWS.CONTACT_FLOATS))
        self._ci = np.zeros((size, self.ROWS.CONTACT_INTS), np.int64)

    def _impact_kernel(self, todo: Isolated) -> tuple[FloatArray, int]:
        """Stage 5: advance the islands solved exactly (``todo``) through the step, their
        impacts solved at their times of impact; return the impacts' log and how many rows
        of it are written (rows of the dimension's ``IMPACT_FIELDS``)."""
        raise NotImplementedError

    def _fly(self, free: NDArray[np.int64]) -> None:
        """Stage 6: the bodies ``free`` in free flight through the step."""
        raise NotImplementedError

    def _on_cloth(
        self, nc: int, closest: FloatArray, closing: FloatArray, loaded: Loaded | None
    ) -> NDArray[np.bool_]:
        """The contacts (nc,) that islands leave out: the cloth under each ball on a level
        cloth this step (the 3D engine: :func:`carom.engines.rigid3d.cloth.candidates`;
        none in 2D)."""
        return np.zeros(max(nc, 1), np.bool_)

    def _roll_cloth(self) -> None:
        """Stage 6: move the balls alone on a level cloth in closed form, their energy lost
        booked (the 3D engine: :mod:`carom.engines.rigid3d.cloth`; none in 2D)."""

    def _solver_bodies(self) -> NDArray[np.int64]:
        """The bodies stage 7 solves."""
        return np.flatnonzero(self._role == islands.ROLE_SOLVER)

    def _joints_now(self) -> tuple[NDArray[np.int64], NDArray[np.bool_]]:
        """The joints stage 7 solves (those of a body it solves), and the bodies of their
        islands (N,) bool (their contacts take their impacts first)."""
        if self._links.shape[0] == 0:
            return self._no_joints, self._none_jointed
        return joints_now(
            self.joint_ints, self._role, islands.ROLE_SOLVER, self._dynamic, self._parent
        )

    def use_joints(self, ints: NDArray[np.int64], floats: FloatArray, wake: bool = True) -> None:
        """The joints' rows (:mod:`.joints`), taken as they are (the solver writes their
        impulses and reactions into ``floats``); the bodies of every joint wake if
        ``wake`` (not when an engine is built or restored: it goes on as it was)."""
        self.joint_ints = ints
        self.joint_floats = floats
        self._links = links(ints)
        self._joined = joined_keys(ints, self.model.kind.shape[0])
        if wake:
            ends = self._links.ravel()
            self._wake_bodies(np.unique(ends[ends >= 0]))

    def _solve(self, nc: int, bodies: NDArray[np.int64], work: FloatArray) -> None:
        """Stage 7: the soft step over the contacts left to the solver; the work of kinematic
        bodies [J] is added to ``work[0]``."""
        raise NotImplementedError

    def _poses(self) -> tuple[FloatArray, FloatArray]:
        """The bodies' positions and orientations now (copies), for :meth:`_continuous`."""
        raise NotImplementedError

    def _continuous(
        self,
        nc: int,
        closest: FloatArray,
        bodies: NDArray[np.int64],
        poses: tuple[FloatArray, FloatArray],
    ) -> None:
        """Stage 7, after the solve: continuous collision of the solver's ``bodies`` that
        moved far, from ``poses`` (:meth:`_poses` before the solve), against static geometry
        other than what they touched at the start (the step's ``nc`` contacts, each one's
        least separation ``closest`` [m]): at the first touch a body is put back, its
        velocity kept (no body runs through a wall, as in Box2D)."""
        raise NotImplementedError

    def _knobs(self) -> tuple[float, int, float, float, float, float]:
        """The solver's settings for a step: ``dt`` [s], substeps, contact stiffness [Hz],
        damping ratio, push speed [m/s] and restitution threshold [m/s]."""
        st = self.settings
        return (
            self.dt, st.substeps, st.contact_hertz, st.damping_ratio, st.push_speed,
            st.restitution_threshold,
        )  # fmt: skip

    def _keep_manifolds(self) -> None:
        """Keep this step's manifolds for the next (an engine that reuses them)."""

    def _energy(self, rows: NDArray[np.int64]) -> float:
        """Kinetic and gravitational potential energy of the dynamic bodies among ``rows``
        [J]."""
        raise NotImplementedError

    def energy(self) -> float:
        """Kinetic and gravitational potential energy of the dynamic bodies [J]."""
        return self._energy(np.arange(self.model.kind.shape[0]))

    def energy_of(self, rows: NDArray[np.int64]) -> float:
        """:meth:`energy` of the dynamic bodies among ``rows`` (k,) [J]."""
        return self._energy(rows)

    def book_work(self, work: float) -> None:
        """Book ``work`` [J] done on the bodies from outside the engine (their kinds
        switched: the energy that entered or left the count)."""
        self._work_done += work

    def _moving(self) -> NDArray[np.bool_]:
        """Kinematic bodies in motion (N,)."""
        moving = np.zeros(self._kinematic.shape[0], np.bool_)
        movers = self._movers
        if movers.size:
            s = self.state
            spin = getattr(s, self.SPIN)[movers]  # (K,) in 2D, (K, 3) in 3D
            turning = np.any(spin.reshape(movers.size, -1) != 0.0, axis=1)
            moving[movers] = np.any(s.v[movers] != 0.0, axis=1) | turning
        return moving

    def _fastest(self) -> FloatArray:
        """Each body's fastest point [m/s], (N,), for sleep."""
        raise NotImplementedError

    def _stop(self, asleep: NDArray[np.int64]) -> float:
        """Stop the bodies ``asleep``; return the kinetic energy they had [J]."""
        raise NotImplementedError

    def _settle(self, nc: int) -> None:
        """Stage 8: sleep the islands at rest (:func:`.islands.settle`); their bodies stop and
        the kinetic energy they kept goes to the ledger as lost."""
        m, mem, st = self.model, self.memory, self.settings
        before = mem.awake.copy()
        islands.settle(
            self._ci, nc, m.kind, self._parent, mem.awake, self._fastest(), self._moving(),
            mem.clock, mem.island, self.dt, st.sleep_speed, st.sleep_time,
        )  # fmt: skip
        asleep = np.flatnonzero(before & ~mem.awake)
        if asleep.size:
            self._energy_lost += self._stop(asleep)

    def deepest_overlap(self, asleep: bool = False) -> tuple[int, int, float]:
        """The two bodies that overlap most now, with at least one of them dynamic and
        awake (``asleep``: or asleep), and the depth [m] (positive; ``(-1, -1, 0.0)`` when
        nothing overlaps)."""
        rows = self.ROWS
        if asleep:  # (every dynamic body looked at as if awake, then as it was)
            awake = self.memory.awake.copy()
            self.memory.awake[self._dynamic] = True
            try:
                nc = self._contacts()
            finally:
                self.memory.awake[:] = awake
        else:
            nc = self._contacts()
        ci, cf = self._ci[:nc], self._cf[:nc]
        a, b = ci[:, I_BODY_A], ci[:, I_BODY_B]
        points = rows.MAX_POINTS
        columns = [rows.point_offset(j) + rows.P_SEP for j in range(points)]
        depth = -cf[:, columns]  # (nc, points); the points a contact has count
        depth[np.arange(points)[None, :] >= ci[:, I_COUNT][:, None]] = -np.inf
        depth[~(self._dynamic[a] | self._dynamic[b])] = -np.inf
        if nc == 0 or float(depth.max()) <= 0.0:
            return (-1, -1, 0.0)
        row = int(np.argmax(depth.max(axis=1)))
        return (int(a[row]), int(b[row]), float(depth[row].max()))

    def _book(self, log: FloatArray, sink: Sink | None) -> None:
        """Count the exact impacts and hand them to ``sink`` as collision records.

        A row of ``log``: time into the step, body A, body B, the impulse on A (d), normal
        speeds before and after, the point (d), the energy lost and, if there is a column
        more, the work done by a kinematic partner."""
        d = self.DIMS
        partner = log[:, 2].astype(np.int64)
        lost = float(log[:, 5 + 2 * d].sum())
        work = float(log[:, 6 + 2 * d].sum()) if log.shape[1] > 6 + 2 * d else 0.0
        against = self._count(partner, lost, work)
        if sink is None:
            return
        records = np.zeros(log.shape[0], COLLISION_DTYPE)
        records["time"] = self.time + log[:, 0]
        records["body"] = log[:, 1].astype(np.int64)
        records["kind"] = against
        records["partner"] = self.partners.number[partner]
        records["impulse"][:, :d] = log[:, 3 : 3 + d]
        records["un_before"] = log[:, 3 + d]
        records["un_after"] = log[:, 4 + d]
        records["point"][:, :d] = log[:, 5 + d : 5 + 2 * d]
        sink(records)

    @staticmethod
    def _warm_kernels() -> None:
        """Load every kernel a step of this engine's dimension can call (a module's
        ``warm_up``)."""
        raise NotImplementedError

    def warm_up(self) -> None:
        """Load (or compile) every kernel a run may call: a step's, including those called
        only on a first impact or sleep, and the sampler's. Changes nothing."""
        self.advance(self.time, 0, None)  # no step is taken
        self._warm_kernels()
        self.sample()

    @property
    def time(self) -> float:
        """The clock [s]: its origin plus whole steps since."""
        return self.start + self._since * self.settings.dt

    def advance(
        self,
        until: float,
        max_events: int,
        sink: Sink | None,
        stop: Callable[[], bool] | None = None,
    ) -> bool:
        """Step until the clock reaches ``until`` [s] exactly: whole steps of ``dt``, then,
        when ``until`` falls between two steps (by more than a millionth of a step), one
        shorter step that ends on it (the clock's origin moves there, and later steps are
        whole steps from it). ``max_events`` bounds the steps; then, or when ``stop`` says
        so, the clock stays short of ``until`` and False is returned. Impacts solved exactly
        go to ``sink``."""
        span = (until - self.start) / self.dt + 1e-6  # (inf: max_events steps, as events)
        wanted = max_events if math.isinf(span) else max(math.floor(span) - self._since, 0)
        todo = min(wanted, max_events)
        for k in range(todo):
            self.step(sink)
            if stop is not None and (k + 1) % STOP_CHECK_STEPS == 0 and stop():
                return False
        rest = until - self.time
        short = rest > 1e-6 * self.dt  # (until between two steps, or infinite)
        if todo < wanted or (short and todo == max_events):
            return False  # the steps allowed are spent short of until
        if short:
            self._step_short(rest, until, sink)
        return True

    # -- reaching a body between steps (issue 43) --------------------------------------------

    def apply_impulses(
        self, ids: NDArray[np.int64], impulses: FloatArray, points: FloatArray | None,
        alive: NDArray[np.bool_] | None = None,
    ) -> bool:  # fmt: skip
        """Impulses ``impulses`` (k, d) or (1, d) (one for all) [N s] on the dynamic bodies
        ``ids`` (k,), each at the world point ``points[j]`` (k, d) or (1, d) [m] (None: at the
        centre of mass), in order: the velocity changes by ``J / m`` and the spin by
        ``I^-1 (r x J)`` at once, an impulse's exact effect. The bodies wake; the kinetic
        energy they gain or lose is booked as work done on them
        (:attr:`Counters.work_done`). Checked first in the same compiled call (every id
        ``alive`` (n,) (None: every body) and dynamic, every number finite and within
        carom's limits): False, and nothing done, when a check fails."""
        at = self._nowhere if points is None else points
        everyone = np.ones(self.n_bodies, np.bool_) if alive is None else alive
        done, work = self._kick(ids, impulses, at, everyone)
        self._work_done += work
        return done

    def apply_forces(
        self, ids: NDArray[np.int64], forces: FloatArray, points: FloatArray | None
    ) -> None:
        """Forces ``forces`` (k, d) [N] on the dynamic bodies ``ids`` (k,) through the next step,
        each at the world point ``points[j]`` (k, d) [m] (None: at the centre of mass), then
        cleared (:mod:`.loads`). The bodies wake."""
        arms = None if points is None else points - self.state.x[ids]
        self._loads.add_forces(ids, forces, arms)
        self._wake_bodies(np.unique(ids))

    def apply_torques(self, ids: NDArray[np.int64], torques: FloatArray) -> None:
        """Torques (k,) in 2D, (k, 3) in 3D [N m] on the dynamic bodies ``ids`` (k,) through
        the next step, then cleared. The bodies wake."""
        self._loads.add_torques(ids, torques)
        self._wake_bodies(np.unique(ids))

    def loads_now(self) -> tuple[FloatArray, FloatArray] | None:
        """The forces (n, d) [N] and torques [N m] given for the next step (copies), None when
        none are."""
        loads = self._loads
        return (loads.force.copy(), loads.torque.copy()) if loads.on else None

    def take_loads(self, kept: tuple[FloatArray, FloatArray]) -> None:
        """The loads :meth:`loads_now` gave (another engine's, over the first bodies of this
        one), on the bodies still dynamic, for the next step."""
        force, torque = kept
        rows = np.flatnonzero(self._dynamic[: force.shape[0]])
        if rows.size:
            self._loads.add_forces(rows, force[rows], None)
            self._loads.add_torques(rows, torque[rows])

    def remembered(self) -> Remembered:
        """What this engine hands the engine a world builds in its place (bodies added,
        kinds switched, gravity or materials set): its sleep and warm starts, and what they
        are of (:func:`.memory.carried`)."""
        m = self.model
        return remembered(
            self.memory, self.partners, m.body_pieces, m.kind.astype(np.int64), m.material,
            self.sample(), self._laws(), self._keyed(),
        )  # fmt: skip

    def take_memory(self, kept: Remembered) -> None:
        """Start from the sleep and warm starts another engine of this world had
        (:meth:`remembered`), as far as they hold for this one (:func:`.memory.carried`)."""
        m = self.model
        where = renumbering(kept, self.partners, m.body_pieces)
        self.memory = carried(
            kept, where, m.kind.astype(np.int64), m.material, self.sample(), self._laws(),
            self.memory,
        )  # fmt: skip
        if kept.keyed:
            rows, keys = rekeyed(where, kept.keyed[0])
            self._take_keyed(keys, tuple(table[rows] for table in kept.keyed[1:]))

    def _keyed(self) -> tuple[NDArray[Any], ...]:
        """The dimension's own rows kept from step to step keyed by piece pairs (the used
        ones): the keys, then each table's rows; none by default."""
        return ()

    def _take_keyed(self, keys: NDArray[np.int64], tables: tuple[NDArray[Any], ...]) -> None:
        """Take the rows :meth:`_keyed` gave, renumbered (``keys`` sorted)."""

    def _laws(self) -> Laws:
        """Gravity, the settings and the contact tables (:attr:`LAW_TABLES`)."""
        m = self.model
        return Laws(m.gravity, self.settings, tuple(getattr(m, t) for t in self.LAW_TABLES))

    def retire(self, ids: NDArray[np.int64]) -> None:
        """Take bodies ``ids`` (k,) out of the world for good, their indices kept: they stop
        (the kinetic energy they had leaves the ledger as work done on them) and never move
        again; with their filters zeroed (:meth:`use_filters`) nothing touches or sees them."""
        rows = np.unique(ids)
        before = self._energy(rows)
        self.state.v[rows] = 0.0
        getattr(self.state, self.SPIN)[rows] = 0.0
        self.memory.awake[rows] = False
        self._work_done += self._energy(rows) - before
        self._movers = self._movers[~np.isin(self._movers, rows)]
        gone = self.callers[rows]
        self.events.forget(gone)
        self.sensors.forget(gone)

    def use_filters(
        self, table: NDArray[np.int64], changed: NDArray[np.int64] | None = None
    ) -> None:
        """The caller's bodies' filters, ``table`` (n, 3): category, mask, group each
        (:mod:`.filters`). The bodies ``changed`` (k,) wake: a pair they may now touch is
        found at the next step."""
        full = self.sensors.filters.copy()
        full[: table.shape[0]] = table
        self.filters[:] = self.sensors.solid(full, self.model.piece_body)
        self.filtered = bool(np.any(self.filters != default_filters(1)))
        if changed is not None:
            self._wake_bodies(np.unique(changed))

    def use_sensors(
        self, sensor: NDArray[np.bool_], changed: NDArray[np.int64],
        pieces: NDArray[np.int64] | None = None,
    ) -> None:  # fmt: skip
        """Which of the caller's bodies are sensors, ``sensor`` (n,), and which pieces of
        others, ``pieces`` (k, 2) rows (body, its piece) (:mod:`.sensors`): they touch nothing
        and report the bodies overlapping them after each step that gathers events. The
        bodies ``changed`` (k,) wake."""
        m = self.model
        marked = np.zeros(m.piece_body.shape[0], np.bool_)
        whole = np.zeros(m.kind.shape[0], np.bool_)  # (the world's walls and planes: none)
        whole[: sensor.shape[0]] = sensor
        marked |= whole[m.piece_body]
        if pieces is not None and len(pieces):
            marked[m.body_pieces[pieces[:, 0]] + pieces[:, 1]] = True
        self.sensors.mask[:] = marked
        self.use_filters(self.sensors.filters, changed)

    def _sensed(self) -> NDArray[np.int64]:
        """The sensor pairs overlapping now, as keys (:mod:`.sensors`)."""
        raise NotImplementedError

    def cast_rays(
        self, origins: FloatArray, directions: FloatArray, lengths: FloatArray, mask: int = -1
    ) -> tuple[FloatArray, NDArray[np.int64], FloatArray]:
        """Rays from ``origins`` (R, d) [m] along unit ``directions`` (R, d) up to ``lengths``
        (R,) [m] against every body now whose category holds a bit of ``mask`` (signed 64-bit:
        -1 is every bit) (:mod:`carom.geometry.rays`): each one's distance [m] (inf: no hit),
        the caller's number of the body hit (:attr:`callers`; -2: none) and the outward normal
        there (R, d)."""
        m = self.model
        rays = origins.shape[0]
        distance = np.empty(rays)
        piece = np.empty(rays, np.int64)
        normal = np.zeros((rays, self.DIMS))
        movers = self._reach[2]
        # the moving bodies' pieces, one box each: a tree over them for many rays, one by one
        # for a few
        boxes = self._mover_boxes()
        tree = build_bvh(boxes) if rays >= 8 and movers.size else empty_bvh(self.DIMS)
        trees = (tree.box, tree.left, tree.first, tree.count, tree.order, boxes, movers)
        self._cast((origins, directions, lengths), trees, mask, (distance, piece, normal))
        body = np.where(piece >= 0, self.callers[m.piece_body[np.maximum(piece, 0)]], -2)
        return distance, body, normal

    def _mover_boxes(self) -> FloatArray:
        """The boxes (k, 2 d) of the moving bodies' pieces (``_reach[2]``), each within its
        reach of its body's centre now, for the queries."""
        m, movers = self.model, self._reach[2]
        centre = self.state.x[m.piece_body[movers]]
        reach = (m.piece_reach[movers] + m.piece_radius[movers])[:, None]
        boxes: FloatArray = np.hstack((centre - reach, centre + reach))
        return boxes

    def _cast(
        self, rays: tuple[FloatArray, ...], movers: tuple[Any, ...], mask: int, hits: Any
    ) -> None:
        """The dimension's ray kernel (:meth:`cast_rays`)."""
        raise NotImplementedError

    def overlaps(
        self, low: FloatArray, high: FloatArray, point: bool, mask: int = -1
    ) -> NDArray[np.int64]:
        """The caller's numbers of the bodies (sorted, each once; -1 for a wall or plane)
        that hold the point ``low`` (``point``) or meet the box ``[low, high]`` (d,) [m] now,
        exactly (:mod:`carom.geometry.overlaps`), among those whose category holds a bit of
        ``mask``. Candidates are the pieces whose boxes meet the query's (:meth:`_near`)."""
        m = self.model
        candidates = self._near(low, high)
        hit = np.zeros(candidates.shape[0], np.bool_)
        self._overlap(candidates, low, high, point, mask, hit)
        return np.unique(self.callers[m.piece_body[candidates[hit]]])

    def _near(self, low: FloatArray, high: FloatArray) -> NDArray[np.int64]:
        """The pieces whose boxes meet the box ``[low, high]`` (d,) [m]: the static pieces'
        boxes of the broad phase, the moving bodies' pieces within their reach of their
        centres now, and every unbounded static piece (a plane)."""
        fat, open_statics, movers = self._reach[0][5], self._reach[1], self._reach[2]
        boxes = fat.copy()
        boxes[movers] = self._mover_boxes()
        d = self.DIMS
        near = np.all(boxes[:, :d] <= high, axis=1) & np.all(boxes[:, d:] >= low, axis=1)
        near[open_statics] = True
        return np.flatnonzero(near).astype(np.int64)

    def cast_shape(
        self, cast: tuple[FloatArray | NDArray[np.int64], ...], pose: FloatArray,
        move: FloatArray, swept: tuple[FloatArray, FloatArray], mask: int = -1,
    ) -> tuple[int, FloatArray]:  # fmt: skip
        """The first body a shape moved from ``pose`` along ``move`` (d,) [m] would touch:
        the caller's number of the body (-1: a wall or plane; -2: none) and the hit (the
        fraction of ``move``, the point (d,), the body's outward normal there (d,)).
        ``cast``: the shape's pieces (the dimension's arrays); ``swept`` the box (low, high)
        the shape sweeps, where the candidates lie; ``mask`` as :meth:`cast_rays`'."""
        candidates = self._near(*swept)
        hit = np.full(1 + 2 * self.DIMS, np.nan)
        piece = self._cast_shape(cast, pose, move, candidates, mask, hit)
        if piece < 0:
            return -2, hit
        return int(self.callers[self.model.piece_body[piece]]), hit

    def _cast_shape(
        self, cast: tuple[Any, ...], pose: FloatArray, move: FloatArray,
        candidates: NDArray[np.int64], mask: int, hit: FloatArray,
    ) -> int:  # fmt: skip
        """The dimension's shape-cast kernel (:meth:`cast_shape`): the piece hit or -1."""
        raise NotImplementedError

    def _overlap(
        self, candidates: NDArray[np.int64], low: FloatArray, high: FloatArray, point: bool,
        mask: int, hit: NDArray[np.bool_],
    ) -> None:  # fmt: skip
        """The dimension's overlap kernel (:meth:`overlaps`)."""
        raise NotImplementedError

    def set_motion(self, ids: NDArray[np.int64], field: str, values: FloatArray) -> None:
        """Set the state column ``field`` ("x", "v", the dimension's orientation or spin) of
        bodies ``ids`` (k,) to ``values`` (k, ...); they wake, and the change of energy is
        booked as work done on them."""
        rows = np.unique(ids)
        before = self._energy(rows)
        getattr(self.state, field)[ids] = values
        self._wake_bodies(rows)
        self._work_done += self._energy(rows) - before

    def _kick(
        self, ids: NDArray[np.int64], impulses: FloatArray, points: FloatArray,
        alive: NDArray[np.bool_],
    ) -> tuple[bool, float]:  # fmt: skip
        """The dimension's kernel of :meth:`apply_impulses` (``points`` with no rows: at the
        centres); returns whether it passed its checks and the kinetic energy given [J]."""
        raise NotImplementedError

    def _wake_bodies(self, rows: NDArray[np.int64]) -> None:
        """Wake the dynamic bodies among ``rows`` (their islands wake through their
        contacts at the next step, whose broad phase finds their pieces where they are)."""
        dynamic = rows[self._dynamic[rows]]
        self.memory.awake[dynamic] = True
        self.memory.clock[dynamic] = 0.0

    def step_of(self, dt: float, sink: Sink | None = None) -> None:
        """One step of ``dt`` [s]: :meth:`step` when ``dt`` is the engine's own, else one step
        of that length in every stage (longer or shorter), after which the clock's origin is
        where it ended and later steps are whole ones from there."""
        if dt == self.dt:
            self.step(sink)
        else:
            self._step_short(dt, self.time + dt, sink)

    @property
    def _since(self) -> int:
        """Whole steps since the clock's origin (:attr:`start`)."""
        return self.steps - self.base

    def _step_short(self, dt: float, until: float, sink: Sink | None) -> None:
        """One step of ``dt`` [s] (other than a whole one: shorter to end on a time, or any
        length :meth:`step_of` is given) that ends at ``until`` [s]: every stage takes ``dt``
        for this step; the clock's origin moves to ``until``."""
        full = self.dt
        self.dt = dt
        try:
            self.step(sink)
        finally:
            self.dt = full
        self.start, self.base = float(until), self.steps

    def sample(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        raise NotImplementedError

    def sample_motion(self) -> tuple[FloatArray, FloatArray]:
        """:meth:`sample`'s positions and velocities, copies."""
        s, n = self.state, self.n_bodies
        return s.x[:n].copy(), s.v[:n].copy()

    def sample_positions(self) -> FloatArray:
        """The caller's bodies' centres of mass now, (n, d) [m]; a copy."""
        x: FloatArray = self.state.x[: self.n_bodies].copy()
        return x

    def sample_turns(self) -> FloatArray:
        """The caller's bodies' orientations now: (n,) angles [rad] in 2D, (n, 4) unit
        quaternions in 3D; a copy."""
        turns: FloatArray = getattr(self.state, self.TURN)[: self.n_bodies].copy()
        return turns

    def advance_frames(
        self,
        times: FloatArray,
        sink: Sink | None,
        stop: Callable[[], bool] | None,
        out: FrameArrays,
    ) -> int:
        """Step to each of ``times`` and sample there: a call from Python a frame, which
        costs little beside a step. Returns the frames written (fewer if ``stop`` said so)."""
        for f in range(len(times)):
            if not self.advance(float(times[f]), np.iinfo(np.int64).max, sink, stop):
                return f
            x, v, orient, w = self.sample()
            out.times[f] = self.time
            out.positions[f] = x
            out.velocities[f] = v
            out.orientations[f] = orient.reshape(len(orient), -1)
            out.angular_velocities[f] = w
        return len(times)

    def counters(self) -> Counters:
        return Counters(
            self.steps,
            self._collisions,
            self._wall_collisions,
            0,
            0,
            0.0,
            self._energy_lost,
            0,
            self._energy_given,
            self._work_done,
        )

    def resting(self) -> NDArray[np.int64]:
        return np.full(self.n_bodies, -1, np.int64)

    def _totals(self) -> dict[str, NDArray[Any]]:
        """The clock and the running totals, for :meth:`arrays`."""
        return {
            "steps": np.array([self.steps]),
            "start": np.array([self.start]),
            "base": np.array([self.base]),
            "totals": np.array(
                [
                    self._collisions,
                    self._wall_collisions,
                    self._energy_lost,
                    self._energy_given,
                    self._work_done,
                ]
            ),
        }

    def _restore_totals(self, arrays: Mapping[str, NDArray[Any]]) -> None:
        """Take the clock and totals back from :meth:`_totals`' arrays."""
        self.steps = int(arrays["steps"][0])
        # (a checkpoint written before shorter steps: the clock's origin at step 0)
        self.base = int(arrays["base"][0]) if "base" in arrays else 0
        collisions, walls, lost, given, work = (float(t) for t in arrays["totals"])
        self._collisions, self._wall_collisions = int(collisions), int(walls)
        self._energy_lost, self._energy_given, self._work_done = lost, given, work

    def _count(self, partner: NDArray[np.int64], lost: float, work: float) -> NDArray[np.int8]:
        """Count exact impacts against ``partner`` rows and add their ledger; return what
        each partner is (PARTNER_BODY, PARTNER_WALL, PARTNER_PLANE)."""
        against = self.partners.kind[partner]
        bodies = int(np.count_nonzero(against == PARTNER_BODY))
        self._collisions += bodies
        self._wall_collisions += against.shape[0] - bodies
        self._energy_lost += lost
        self._work_done += work
        return against
