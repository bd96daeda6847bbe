"""RigidEngine3D: the time-stepped engine for 3D rigid bodies with rotation.

One step (``dt = 1/rate``) runs the 2D engine's stages (:mod:`carom.engines.rigid.driver`):

1. **place**: the moving bodies' pieces in the world;
2. **broad phase**: pairs of pieces whose swept boxes overlap (:mod:`.broadphase`);
3. **narrow phase**: their manifolds, warm-started from the last step (:mod:`.contacts`);
   an awake body touching a sleeping island wakes it, and the phases run again;
4. **islands**: each body's role: free flight, an isolated impact, or the solver
   (:mod:`carom.engines.stepped.islands`, shared with 2D);
5. **exact impacts**: isolated pairs advanced through the step with their impacts solved at
   the time of impact (:mod:`.impacts`);
6. **free flight**: bodies with no contact (:func:`.motion.fly`);
7. **solve**: the soft step over the remaining contacts (:mod:`.solver`); kinematic bodies
   then move on at their own velocities;
8. **store** the impulses for the next step, and **sleep** the islands at rest (their bodies
   stop, as in Box2D; the kinetic energy they kept goes to the ledger as lost).

The settings are the 2D engine's (:class:`carom.engines.stepped.settings.RigidSettings`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom.engines.base import COLLISION_DTYPE, Partners, Sink
from carom.engines.rigid3d import broadphase, contacts, impacts, motion, solver
from carom.engines.rigid3d.model import Model3D, State3D, empty_manifolds
from carom.engines.stepped import islands
from carom.engines.stepped.driver import SteppedEngine
from carom.engines.stepped.rows import I_BODY_A, I_BODY_B, I_COUNT
from carom.engines.stepped.settings import RigidSettings
from carom.geometry.rotation import turn
from carom.laws.kinds import KIND_DYNAMIC, KIND_STATIC

__all__ = ["RigidEngine3D", "grid_cell"]

FloatArray = NDArray[np.float64]

#: a touching pair whose every point separates faster than this fraction of the restitution
#: threshold has just bounced: it flies apart on the exact path (free flight keeps its angular
#: momentum exactly), not through the solver. Resting contacts never separate that fast.
LEAVING = 0.1


def grid_cell(model: Model3D) -> float:
    """The broad phase's cell side [m]: four times the median reach of the dynamic pieces (a
    typical piece then sits in one to eight cells)."""
    finite = np.isfinite(model.piece_reach)
    dynamic = (model.kind[model.piece_body] == KIND_DYNAMIC) & finite
    reach = model.piece_reach[dynamic] if dynamic.any() else model.piece_reach[finite]
    if reach.size == 0:
        return 1.0
    cell = 4.0 * float(np.median(reach))
    return cell if cell > 0.0 and math.isfinite(cell) else 1.0


class RigidEngine3D(SteppedEngine):
    """The time-stepped engine for 3D rigid bodies.

    Parameters
    ----------
    model : Model3D
        The constants.
    state : State3D
        The state at ``time``; the engine advances it in place.
    settings : RigidSettings
    time : float
        The clock at ``state`` [s].
    partners : Partners, optional
        What each body is to a collision record (default: all bodies are the caller's).

    Notes
    -----
    The counters keep the energy ledger as the 2D engine's: ``E0 + work_done = E +
    energy_lost - energy_given``.
    """

    name = "rigid"

    @staticmethod
    def _warm_kernels() -> None:
        warm_up()

    def __init__(
        self,
        model: Model3D,
        state: State3D,
        settings: RigidSettings,
        time: float = 0.0,
        partners: Partners | None = None,
    ) -> None:
        shape = (3, contacts.CONTACT_FLOATS, contacts.CONTACT_INTS)
        self._begin(model, state, settings, time, partners, shape, grid_cell(model),
                    broadphase.find_pairs)  # fmt: skip
        n = model.kind.shape[0]
        self._made = _room(self._ci.shape[0])  # this step's manifolds, kept once it is taken
        self._made_count = 0
        self._movers = np.flatnonzero(self._kinematic)
        self._g = float(np.linalg.norm(model.gravity))
        self._ints = (
            model.piece_body, model.piece_kind, model.piece_vstart, model.piece_vcount,
            model.piece_fstart, model.piece_fcount, model.piece_cstart, model.piece_ccount,
            model.piece_estart, model.piece_ecount,
        )  # fmt: skip
        everyone = np.ones(n, np.bool_)
        self._place(everyone)
        still = np.zeros((n, 3))
        self._box(everyone, still, still, 0.0)

    # -- the Engine protocol --------------------------------------------------------------

    def sample(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Positions (n, 3), velocities (n, 3), quaternions (n, 4), angular velocities (n, 3)
        of the caller's bodies."""
        s, n = self.state, self.n_bodies
        return s.x[:n].copy(), s.v[:n].copy(), s.q[:n].copy(), s.w[:n].copy()

    @classmethod
    def restore(
        cls,
        model: Model3D,
        settings: RigidSettings,
        partners: Partners,
        arrays: Mapping[str, NDArray[Any]],
    ) -> RigidEngine3D:
        """The engine that wrote ``arrays`` (:meth:`arrays`), to continue bit for bit."""
        kept = empty_manifolds(0)  # a checkpoint written before manifolds were kept
        state = State3D(
            *(np.array(arrays[name] if name in arrays else kept[name]) for name in State3D._fields)
        )
        engine = cls(model, state, settings, float(arrays["start"][0]), partners)
        engine._restore_totals(arrays)
        return engine

    def deepest_overlap(self) -> tuple[int, int, float]:
        """The two bodies that overlap most now, with at least one of them dynamic, and the
        depth [m] (positive; ``(-1, -1, 0.0)`` when nothing overlaps)."""
        nc = self._contacts()
        ci, cf = self._ci[:nc], self._cf[:nc]
        a, b = ci[:, I_BODY_A], ci[:, I_BODY_B]
        columns = [contacts.point_offset(j) + contacts.P_SEP for j in range(4)]
        depth = -cf[:, columns]
        depth[np.arange(4)[None, :] >= ci[:, I_COUNT][:, None]] = -np.inf
        depth[~(self._dynamic[a] | self._dynamic[b])] = -np.inf
        if nc == 0 or float(depth.max()) <= 0.0:
            return (-1, -1, 0.0)
        row = int(np.argmax(depth.max(axis=1)))
        return (int(a[row]), int(b[row]), float(depth[row].max()))

    def energy(self) -> float:
        """Kinetic and gravitational potential energy of the dynamic bodies [J]."""
        return self._energy(np.arange(self.model.kind.shape[0]))

    # -- one step -------------------------------------------------------------------------

    def _place(self, which: NDArray[np.bool_]) -> None:
        m, s = self.model, self.state
        motion.place_pieces(
            s.x, s.q, which, m.body_pieces, m.piece_vstart, m.piece_vcount, m.piece_fstart,
            m.piece_fcount, m.local_vertices, m.local_normals, s.vertices, s.normals,
        )  # fmt: skip

    def _box(self, which: NDArray[np.bool_], v: FloatArray, w: FloatArray, dt: float) -> None:
        m, s = self.model, self.state
        broadphase.piece_boxes(
            s.vertices, s.normals, m.piece_kind, m.piece_vstart, m.piece_vcount,
            m.piece_fstart, m.piece_radius, m.piece_reach, m.piece_body, v, w, which,
            self._dynamic, m.gravity, dt, 4.0 * self.settings.linear_slop, self._boxes,
        )  # fmt: skip

    def _contacts(self) -> int:
        """Stages 1 to 3: the contacts at the start of the step."""
        m, s, st = self.model, self.state, self.settings
        moving = (self._dynamic & s.awake) | self._kinematic
        self._place(moving)
        self._box(moving, s.v, s.w, self.dt)
        # the pairs of swept boxes that overlap (kept through fat boxes, as in 2D)
        n_pairs = self._kept.update(self._boxes, m.piece_reach, m.piece_body, moving, self._dynamic)
        speculative = 4.0 * st.linear_slop
        kept = (s.manifold_keys, s.manifold_ints, s.manifold_floats, int(s.manifold_count[0]))
        while True:
            nc = contacts.narrow_phase(
                self._kept.pairs, n_pairs, self._ints, m.piece_radius, m.piece_reach,
                s.vertices, s.normals, m.face_first, m.face_size, m.corners, m.edges,
                m.material, m.e_table, m.mu_table, m.rolling_table, s.x, s.q, s.v, s.w,
                self._dynamic, self._g, self.dt, speculative, st.linear_slop,
                st.manifold_reuse * st.linear_slop, s.cache_keys, s.cache_ids,
                s.cache_impulses, int(s.cache_count[0]), kept, self._made, self._cf, self._ci,
            )  # fmt: skip
            if nc >= 0:
                self._made_count = n_pairs
                return int(nc)
            size = 2 * -nc
            self._cf = np.zeros((size, contacts.CONTACT_FLOATS))
            self._ci = np.zeros((size, contacts.CONTACT_INTS), np.int64)
            self._made = _room(size)

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
            self._ci, nc, closest, closing, m.kind, s.awake, st.exact_impacts,
            0.1 * st.linear_slop, st.restitution_threshold, LEAVING * st.restitution_threshold,
            self._parent, self._role, isolated,
        )  # fmt: skip
        if n_iso:
            rows = isolated[:n_iso]
            ba = m.material[self._ci[rows, I_BODY_A]]
            bb = m.material[self._ci[rows, I_BODY_B]]
            log = np.zeros((n_iso * impacts.MAX_IMPACTS, impacts.IMPACT_FIELDS))
            logged = impacts.exact_impacts(
                isolated, n_iso, closing, self._ci, s.x, s.q, s.v, s.w, self._accel,
                self._dynamic,
                m.inv_mass, m.inertia, m.inv_inertia, m.min_moment, m.e_table[ba, bb],
                m.mu_table[ba, bb], self._ints, m.piece_radius, m.piece_reach,
                m.local_vertices, m.local_normals, m.face_first, m.face_size, m.corners,
                m.edges, s.vertices, s.normals, dt, st.substeps, 1e-3 * st.linear_slop, log,
            )  # fmt: skip
            if logged:
                self._book(log[:logged], sink)
        g = m.gravity
        for i in np.flatnonzero(self._role == islands.ROLE_FREE).tolist():
            motion.fly(
                i, dt, st.substeps, s.x, s.q, s.v, s.w, g[0], g[1], g[2], m.inertia,
                m.inv_inertia,
            )  # fmt: skip
        bodies = np.flatnonzero((self._role == islands.ROLE_SOLVER) & self._dynamic)
        before = self._energy(bodies)
        work = np.zeros(1)
        solver.solve_step(
            self._cf, self._ci, nc, bodies, m.inv_mass, m.inertia, m.inv_inertia,
            self._dynamic, self._movers, s.x, s.q, s.v, s.w, m.gravity, dt, st.substeps,
            st.contact_hertz, st.damping_ratio, st.push_speed, st.restitution_threshold, work,
        )  # fmt: skip
        for i in self._movers.tolist():  # kinematic bodies: their own steady motion
            s.x[i] += dt * s.v[i]
            turn(s.q, i, s.w[i, 0], s.w[i, 1], s.w[i, 2], dt, 3)
        self._work_done += work[0]
        change = self._energy(bodies) - before - work[0]
        if change < 0.0:
            self._energy_lost -= change
        else:
            self._energy_given += change
        if s.cache_keys.shape[0] < nc:
            size = max(nc, 2 * s.cache_keys.shape[0])
            self.state = s = s._replace(
                cache_keys=np.zeros(size, np.int64),
                cache_ids=np.zeros((size, 4), np.int64),
                cache_impulses=np.zeros((size, 4, 4)),
            )
        s.cache_count[0] = contacts.store_impulses(
            self._cf, self._ci, nc, m.piece_body.shape[0], s.cache_keys, s.cache_ids,
            s.cache_impulses,
        )  # fmt: skip
        # keep this step's manifolds for the next; the last step's rows take the next ones
        keys, ints, floats = self._made
        self._made = (s.manifold_keys, s.manifold_ints, s.manifold_floats)
        self.state = s = s._replace(manifold_keys=keys, manifold_ints=ints, manifold_floats=floats)
        s.manifold_count[0] = self._made_count
        if st.sleep:
            self._settle(nc)
        self.n_contacts = nc
        self.steps += 1

    def _moving(self) -> NDArray[np.bool_]:
        """Kinematic bodies in motion (N,)."""
        s = self.state
        moving: NDArray[np.bool_] = self._kinematic & (
            np.any(s.v != 0.0, axis=1) | np.any(s.w != 0.0, axis=1)
        )
        return moving

    def _settle(self, nc: int) -> None:
        """Stage 8: sleep the islands at rest (:func:`carom.engines.stepped.islands.settle`);
        their bodies stop and the kinetic energy they kept goes to the ledger as lost."""
        m, s, st = self.model, self.state, self.settings
        before = s.awake.copy()
        fastest = np.zeros(m.kind.shape[0])  # static pieces reach far (a plane: inf)
        dyn = self._dynamic
        spin = np.linalg.norm(s.w[dyn], axis=1)
        fastest[dyn] = np.linalg.norm(s.v[dyn], axis=1) + spin * m.reach[dyn]
        islands.settle(
            self._ci, nc, m.kind, self._parent, s.awake, fastest, self._moving(), s.clock,
            s.island, self.dt, st.sleep_speed, st.sleep_time,
        )  # fmt: skip
        asleep = np.flatnonzero(before & ~s.awake)
        if asleep.size:
            self._energy_lost += self._energy(asleep) - self._potential(asleep)
            s.v[asleep] = 0.0
            s.w[asleep] = 0.0

    def _potential(self, rows: NDArray[np.int64]) -> float:
        """Gravitational potential energy ``-m g . x`` of the bodies ``rows`` [J]."""
        m, s = self.model, self.state
        return float(-np.sum(m.mass[rows] * (s.x[rows] @ m.gravity)))

    def _book(self, log: FloatArray, sink: Sink | None) -> None:
        """Count the exact impacts and hand them to ``sink`` as collision records."""
        partner = log[:, 2].astype(np.int64)
        against = self._count(partner, float(np.sum(log[:, 11])), 0.0)
        if sink is None:
            return
        records = np.zeros(log.shape[0], COLLISION_DTYPE)
        records["time"] = self.time + log[:, 0]
        records["body"] = log[:, 1].astype(np.int64)
        records["kind"] = against
        records["partner"] = self.partners.number[partner]
        records["impulse"] = log[:, 3:6]
        records["un_before"] = log[:, 6]
        records["un_after"] = log[:, 7]
        records["point"] = log[:, 8:11]
        sink(records)

    def _energy(self, rows: NDArray[np.int64]) -> float:
        m, s = self.model, self.state
        g = m.gravity
        return float(
            motion.mechanical_energy(
                rows, self._dynamic, m.mass, m.inertia, s.x, s.v, s.q, s.w, g[0], g[1], g[2]
            )
        )


def _room(rows: int) -> tuple[NDArray[np.int64], NDArray[np.int64], FloatArray]:
    """Room for ``rows`` manifolds as the narrow phase makes them: keys, ints and floats
    (:func:`.model.empty_manifolds`)."""
    made = empty_manifolds(rows)
    return made["manifold_keys"], made["manifold_ints"], made["manifold_floats"]


_WARM = False


def warm_up() -> None:
    """Load (or compile) every kernel a step can call, once per process: a small scene with
    every pair of piece kinds (ball, capsule, box, a mesh triangle, a plane) runs 30 steps,
    so a scene's first contact of a new kind is not paid for inside a timed run."""
    global _WARM
    if _WARM:
        return
    from carom.engines.rigid3d.model import (
        build_model,
        engine_pieces,
        new_state,
        plane_piece,
        triangle_piece,
    )
    from carom.shapes3d import Box, Capsule, Sphere

    inf = math.inf
    shapes = [Sphere(0.1), Capsule(0.2, 0.05), Box([0.2, 0.2, 0.2]), Box([0.1, 0.3, 0.1])]
    pieces = [engine_pieces(shape.pieces(), 0.0) for shape in shapes]
    pieces.append([plane_piece(np.array([0.0, 0.0, 1.0]), 0.0)])
    pieces.append([triangle_piece(np.array([[0.5, -1.0, 0.0], [2.0, -1.0, 0.0], [0.5, 1.0, 0.0]]))])
    props = [shape.mass_properties(mass=1.0) for shape in shapes]
    n = len(pieces)
    kind = np.array([KIND_DYNAMIC] * 4 + [KIND_STATIC] * 2)
    model = build_model(
        pieces,
        kind,
        np.array([1.0] * 4 + [inf, inf]),
        np.array([p.inertia for p in props] + [np.eye(3)] * 2),
        np.zeros(n, np.int64),
        np.array([[0.5]]),
        np.array([[0.5]]),
        np.array([[1e-3]]),
        np.array([0.0, 0.0, -10.0]),
    )
    x = np.array([[0.0, 0.0, 0.1], [0.0, 0.3, 0.3], [0.0, 0.0, 0.35], [0.9, 0.0, 0.1],
                  [0.0, 0.0, 0.0], [0.0, 0.0, 0.0]])  # fmt: skip
    q = np.zeros((n, 4))
    q[:, 0] = 1.0
    w = np.zeros((n, 3))
    w[1] = (1.0, 2.0, 3.0)
    state = new_state(model, x, np.zeros((n, 3)), q, w)
    engine = RigidEngine3D(model, state, RigidSettings())
    for _ in range(30):
        engine.step()
    engine.deepest_overlap()
    _WARM = True
