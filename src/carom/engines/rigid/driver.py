"""RigidEngine: the time-stepped rigid-body engine behind a World (2D).

One step (``dt = 1/rate``) runs these stages, in this order (docs/rigid.md):

1. **place**: the awake bodies' pieces in the world;
2. **broad phase**: pairs of pieces whose swept boxes overlap (:mod:`.broadphase`);
3. **narrow phase**: their manifolds, warm-started from the last step (:mod:`.contacts`);
   an awake body touching a sleeping island wakes it, and the two phases run again;
4. **islands**: each body's role: free flight, an isolated impact, or the solver
   (:mod:`.islands`);
5. **exact impacts**: isolated pairs advanced through the step with their impacts solved at
   the time of impact (:mod:`.impacts`);
6. **free flight**: bodies with no contact, exactly (:mod:`.motion`);
7. **solve**: the soft step over the remaining contacts (:mod:`.solver`);
8. **store** the impulses for the next step, and **sleep** the islands at rest (their bodies
   stop, as in Box2D; the kinetic energy they kept goes to the ledger as lost).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom.engines.base import (
    COLLISION_DTYPE,
    Partners,
    Sink,
)
from carom.engines.rigid import broadphase, contacts, impacts, motion, solver
from carom.engines.rigid.model import RigidModel, RigidState, grid_cell
from carom.engines.stepped import islands
from carom.engines.stepped.driver import SteppedEngine
from carom.engines.stepped.rows import I_BODY_A, I_BODY_B, I_COUNT
from carom.engines.stepped.settings import RigidSettings
from carom.laws.kinds import KIND_DYNAMIC, KIND_KINEMATIC, KIND_STATIC

__all__ = ["RigidEngine"]

FloatArray = NDArray[np.float64]


class RigidEngine(SteppedEngine):
    """The time-stepped engine for 2D rigid bodies with rotation.

    Parameters
    ----------
    model : RigidModel
        The constants.
    state : RigidState
        The state at ``time``; the engine advances it in place.
    settings : RigidSettings
    time : float
        The clock at ``state`` [s].
    partners : Partners, optional
        What each body is to a collision record; the caller's bodies are those of kind
        ``KIND_PAIR`` (the first ones), walls and planes follow. Default: all bodies are the
        caller's.

    Notes
    -----
    The counters keep the energy ledger: ``work_done`` is what kinematic bodies put in (each
    impulse on a body times the kinematic body's velocity at the contact point, summed as the
    solver and the exact impacts apply them), ``energy_lost`` what the impacts solved exactly
    and the solver took out of the bodies' kinetic and potential energy beyond that work,
    ``energy_given`` what the solver put in (pushing overlaps apart), step by step, so that
    ``E0 + work_done = E + energy_lost - energy_given``.
    """

    name = "rigid"

    @staticmethod
    def _warm_kernels() -> None:
        warm_up()

    def __init__(
        self,
        model: RigidModel,
        state: RigidState,
        settings: RigidSettings,
        time: float = 0.0,
        partners: Partners | None = None,
    ) -> None:
        shape = (2, contacts.CONTACT_FLOATS, contacts.CONTACT_INTS)
        self._begin(model, state, settings, time, partners, shape, grid_cell(model),
                    broadphase.find_pairs)  # fmt: skip
        n = model.kind.shape[0]
        self._g = float(np.hypot(*model.gravity))
        # place everything once: static pieces never move again
        motion.place_pieces(
            state.x,
            state.angle,
            np.ones(n, np.bool_),
            model.body_pieces,
            model.piece_start,
            model.piece_count,
            model.local_vertices,
            model.local_normals,
            state.vertices,
            state.normals,
        )

    # -- the Engine protocol --------------------------------------------------------------

    def sample(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        s, n = self.state, self.n_bodies
        w = np.zeros((n, 3))
        w[:, 2] = s.omega[:n]
        return s.x[:n].copy(), s.v[:n].copy(), s.angle[:n].reshape(-1, 1).copy(), w

    @classmethod
    def restore(
        cls,
        model: RigidModel,
        settings: RigidSettings,
        partners: Partners,
        arrays: Mapping[str, NDArray[Any]],
    ) -> RigidEngine:
        """The engine that wrote ``arrays`` (:meth:`arrays`), to continue bit for bit."""
        state = RigidState(*(np.array(arrays[name]) for name in RigidState._fields))
        start = float(arrays["start"][0])
        engine = cls(model, state, settings, start, partners)
        engine._restore_totals(arrays)
        return engine

    def deepest_overlap(self) -> tuple[int, int, float]:
        """The two bodies that overlap most now, with at least one of them dynamic, and
        the depth [m] (positive; ``(-1, -1, 0.0)`` when nothing overlaps)."""
        nc = self._contacts()
        ci, cf = self._ci[:nc], self._cf[:nc]
        a, b = ci[:, I_BODY_A], ci[:, I_BODY_B]
        columns = [contacts.point_offset(j) + contacts.P_SEP for j in range(2)]
        depth = -cf[:, columns]  # (nc, 2); a contact's second point counts if it has one
        depth[ci[:, I_COUNT] < 2, 1] = -np.inf
        depth[~(self._dynamic[a] | self._dynamic[b])] = -np.inf
        if nc == 0 or float(depth.max()) <= 0.0:
            return (-1, -1, 0.0)
        row = int(np.argmax(depth.max(axis=1)))
        return (int(a[row]), int(b[row]), float(depth[row].max()))

    # -- one step -------------------------------------------------------------------------

    def _contacts(self) -> int:
        """Stages 1 to 3: the contacts at the start of the step (waking what they touch)."""
        m, s, st = self.model, self.state, self.settings
        moving = (self._dynamic & s.awake) | self._kinematic
        motion.place_pieces(
            s.x,
            s.angle,
            moving,
            m.body_pieces,
            m.piece_start,
            m.piece_count,
            m.local_vertices,
            m.local_normals,
            s.vertices,
            s.normals,
        )
        speculative = 4.0 * st.linear_slop
        broadphase.piece_boxes(
            s.vertices,
            m.piece_start,
            m.piece_count,
            m.piece_radius,
            m.piece_reach,
            m.piece_body,
            s.v,
            s.omega,
            moving,
            self._dynamic,
            float(m.gravity[0]),
            float(m.gravity[1]),
            self.dt,
            speculative,
            self._boxes,
        )
        # stage 2: the pairs of swept boxes that overlap (kept through fat boxes)
        n_pairs = self._kept.update(self._boxes, m.piece_reach, m.piece_body, moving, self._dynamic)
        while True:
            nc = contacts.narrow_phase(
                self._kept.pairs,
                n_pairs,
                s.vertices,
                s.normals,
                m.piece_start,
                m.piece_count,
                m.piece_radius,
                m.piece_reach,
                m.piece_body,
                m.material,
                m.e_table,
                m.mu_table,
                s.x,
                s.v,
                s.omega,
                self._dynamic,
                self._g,
                self.dt,
                speculative,
                st.linear_slop,
                s.cache_keys,
                s.cache_ids,
                s.cache_impulses,
                int(s.cache_count[0]),
                self._cf,
                self._ci,
            )
            if nc >= 0:
                break
            size = 2 * -nc
            self._cf = np.zeros((size, contacts.CONTACT_FLOATS))
            self._ci = np.zeros((size, contacts.CONTACT_INTS), np.int64)
        return nc

    def step(self, sink: Sink | None = None) -> None:
        """Advance one step of ``dt`` [s]."""
        m, s, st = self.model, self.state, self.settings
        dt = self.dt
        nc = self._contacts()
        if st.sleep and islands.wake(
            self._ci, nc, m.kind, s.awake, self._moving(), s.clock, s.island
        ):
            nc = self._contacts()
        isolated = np.zeros(max(nc, 1), np.int64)
        closest, closing = contacts.extremes(self._cf, self._ci, nc)
        n_iso = islands.plan(
            self._ci,
            nc,
            closest,
            closing,
            m.kind,
            s.awake,
            st.exact_impacts,
            0.1 * st.linear_slop,
            st.restitution_threshold,
            np.inf,
            self._parent,
            self._role,
            isolated,
        )
        if n_iso:
            rows = isolated[:n_iso]
            ba = self._ci[rows, I_BODY_A]
            bb = self._ci[rows, I_BODY_B]
            log = np.zeros((n_iso * impacts.MAX_IMPACTS, impacts.IMPACT_FIELDS))
            logged = impacts.exact_impacts(
                isolated,
                n_iso,
                self._ci,
                s.x,
                s.angle,
                s.v,
                s.omega,
                self._accel,
                self._dynamic,
                m.inv_mass,
                m.inv_inertia,
                m.mass,
                m.inertia,
                m.e_table[m.material[ba], m.material[bb]],
                m.mu_table[m.material[ba], m.material[bb]],
                m.piece_start,
                m.piece_count,
                m.piece_radius,
                m.piece_reach,
                m.local_vertices,
                m.local_normals,
                s.vertices,
                s.normals,
                dt,
                1e-3 * st.linear_slop,
                log,
            )
            if logged:
                self._book(log[:logged], sink)
        free = np.flatnonzero(self._role == islands.ROLE_FREE)
        for i in free.tolist():
            motion.fly(i, dt, s.x, s.angle, s.v, s.omega, self._accel[i, 0], self._accel[i, 1])
        bodies = np.flatnonzero(self._role == islands.ROLE_SOLVER)
        before = self._energy(bodies)
        work = np.zeros(1)  # by kinematic bodies on the others, this step [J]
        solver.solve_step(
            self._cf,
            self._ci,
            nc,
            bodies,
            m.inv_mass,
            m.inv_inertia,
            self._dynamic,
            s.x,
            s.angle,
            s.v,
            s.omega,
            float(m.gravity[0]),
            float(m.gravity[1]),
            dt,
            st.substeps,
            st.contact_hertz,
            st.damping_ratio,
            st.push_speed,
            st.restitution_threshold,
            work,
        )
        self._work_done += work[0]
        change = self._energy(bodies) - before - work[0]  # the solver's own part
        if change < 0.0:
            self._energy_lost -= change
        else:
            self._energy_given += change
        if s.cache_keys.shape[0] < nc:
            size = max(nc, 2 * s.cache_keys.shape[0])
            self.state = s = s._replace(
                cache_keys=np.zeros(size, np.int64),
                cache_ids=np.zeros((size, 2), np.int64),
                cache_impulses=np.zeros((size, 4)),
            )
        s.cache_count[0] = contacts.store_impulses(
            self._cf,
            self._ci,
            nc,
            m.piece_start.shape[0],
            s.cache_keys,
            s.cache_ids,
            s.cache_impulses,
        )
        if st.sleep:
            self._settle(nc)
        self.n_contacts = nc
        self.steps += 1

    def _moving(self) -> NDArray[np.bool_]:
        """Kinematic bodies in motion (N,)."""
        s = self.state
        moving: NDArray[np.bool_] = self._kinematic & (
            (s.v[:, 0] != 0.0) | (s.v[:, 1] != 0.0) | (s.omega != 0.0)
        )
        return moving

    def _settle(self, nc: int) -> None:
        """Stage 8: sleep the islands at rest (:func:`.islands.settle`); their bodies stop and
        the kinetic energy they kept goes to the ledger as lost."""
        m, s, st = self.model, self.state, self.settings
        before = s.awake.copy()
        fastest = np.sqrt(s.v[:, 0] ** 2 + s.v[:, 1] ** 2) + np.abs(s.omega) * m.reach
        islands.settle(
            self._ci, nc, m.kind, self._parent, s.awake, fastest, self._moving(), s.clock,
            s.island, self.dt, st.sleep_speed, st.sleep_time,
        )  # fmt: skip
        taken = 0.0
        for i in np.flatnonzero(before & ~s.awake).tolist():
            vx, vy, w = float(s.v[i, 0]), float(s.v[i, 1]), float(s.omega[i])
            taken += 0.5 * (m.mass[i] * (vx * vx + vy * vy) + m.inertia[i] * (w * w))
            s.v[i] = 0.0
            s.omega[i] = 0.0
        self._energy_lost += taken

    def _energy(self, rows: NDArray[np.int64]) -> float:
        """Kinetic and gravitational potential energy of the dynamic bodies among ``rows``
        [J]."""
        m, s = self.model, self.state
        gx, gy = float(m.gravity[0]), float(m.gravity[1])
        return motion.mechanical_energy(
            rows, self._dynamic, m.mass, m.inertia, s.x, s.v, s.omega, gx, gy
        )

    def _book(self, log: FloatArray, sink: Sink | None) -> None:
        """Count the exact impacts and hand them to ``sink`` as collision records."""
        partner = log[:, 2].astype(np.int64)
        against = self._count(partner, float(np.sum(log[:, 9])), float(np.sum(log[:, 10])))
        if sink is None:
            return
        records = np.zeros(log.shape[0], COLLISION_DTYPE)
        records["time"] = self.time + log[:, 0]
        records["body"] = log[:, 1].astype(np.int64)
        records["kind"] = against
        records["partner"] = self.partners.number[partner]
        records["impulse"][:, :2] = log[:, 3:5]
        records["un_before"] = log[:, 5]
        records["un_after"] = log[:, 6]
        records["point"][:, :2] = log[:, 7:9]
        sink(records)


_WARM = False


def warm_up() -> None:
    """Load (or compile) every kernel a step can call, once per process: a small scene that
    exercises them all runs 40 steps (an exact impact, resting contacts that fall asleep, a
    kinematic paddle, circle, capsule and polygon pairs). Numba loads a kernel from the
    cache at its first call, so without this a scene's first impact or first sleep would
    pay for it inside a timed run."""
    global _WARM
    if _WARM:
        return
    from carom.engines.rigid.model import build_model, new_state
    from carom.shapes import Box, Capsule, Circle, Polygon

    inf = math.inf
    shapes = [
        (Box(4.0, 0.5), KIND_STATIC, inf, (0.0, -0.25), (0.0, 0.0)),
        (Box(0.2, 0.2), KIND_DYNAMIC, 1.0, (-1.0, 0.3), (0.0, 0.0)),  # falls: exact impact
        (Box(0.3, 0.3), KIND_DYNAMIC, 1.0, (0.0, 0.15), (0.0, 0.0)),  # resting stack
        (Polygon.regular(5, 0.15), KIND_DYNAMIC, 1.0, (0.0, 0.45), (0.0, 0.0)),
        (Circle(0.1), KIND_DYNAMIC, 1.0, (1.0, 0.1), (0.0, 0.0)),
        (Capsule(0.3, 0.05), KIND_DYNAMIC, 1.0, (1.5, 0.05), (0.0, 0.0)),
        (Box(0.05, 0.4), KIND_KINEMATIC, inf, (0.6, 0.2), (0.5, 0.0)),  # paddle
    ]
    props = [
        shape.mass_properties(mass=mass) if kind == KIND_DYNAMIC else None
        for shape, kind, mass, _, _ in shapes
    ]
    model = build_model(
        [shape.pieces() for shape, *_ in shapes],
        np.array([kind for _, kind, *_ in shapes]),
        np.array([p.mass if p else inf for p in props]),
        np.array([p.inertia if p else inf for p in props]),
        np.zeros(len(shapes), np.int64),
        np.array([[0.5]]),
        np.array([[0.5]]),
        np.array([0.0, -10.0]),
    )
    n = len(shapes)
    x = np.array([pos for *_, pos, _ in shapes], float)
    v = np.array([vel for *_, vel in shapes], float)
    state = new_state(model, x, v, np.zeros(n), np.zeros(n))
    settings = RigidSettings(sleep_time=0.1)
    engine = RigidEngine(model, state, settings)
    for _ in range(40):
        engine.step()
    engine.deepest_overlap()
    _WARM = True
