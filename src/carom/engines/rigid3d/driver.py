"""RigidEngine3D: the time-stepped engine for 3D rigid bodies with rotation.

The stages of a step are the shared driver's (:mod:`carom.engines.stepped.driver`); this
module names the 3D kernels: the pieces placed (:mod:`.motion`), their swept boxes
(:mod:`.broadphase`), the manifolds, kept from step to step (:mod:`.contacts`), the exact
impacts (:mod:`.impacts`), free flight (:func:`.motion.fly`) and the soft step
(:mod:`.solver`), after which kinematic bodies move on at their own velocities. The settings
are the 2D engine's (:class:`carom.engines.stepped.settings.RigidSettings`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom.engines.rigid3d import (
    broadphase,
    cloth,
    contacts,
    impacts,
    joints,
    motion,
    queries,
    solver,
)
from carom.engines.rigid3d.model import Model3D, State3D, empty_manifolds
from carom.engines.stepped import islands
from carom.engines.stepped.driver import Isolated, SteppedEngine
from carom.engines.stepped.joints import rod_rows
from carom.engines.stepped.loads import Loaded
from carom.engines.stepped.settings import RigidSettings
from carom.geometry.rotation import turn
from carom.laws.kinds import KIND_DYNAMIC, KIND_STATIC
from carom.limits import LARGEST

__all__ = ["RigidEngine3D"]

FloatArray = NDArray[np.float64]

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
    engine.events.on = True  # (a game loop's steps gather contact events)
    engine.use_joints(*rod_rows(0, (0.0, 0.0, 0.6), 0.5, joints))  # the ball on a rod
    for _ in range(30):
        engine.step()
    engine.deepest_overlap()
    _WARM = True


class RigidEngine3D(SteppedEngine):
    """The time-stepped engine for 3D rigid bodies with rotation: the shared driver
    (:class:`carom.engines.stepped.driver.SteppedEngine`, its parameters and energy ledger)
    with the 3D kernels. Kinematic bodies move on at their own velocities after the solver;
    each step's manifolds are kept for the next (:mod:`.contacts`)."""

    DIMS = 3
    JOINT_FLOATS = joints.JOINT_FLOATS
    ROWS = contacts
    IMPACTS = impacts
    SPIN = "w"
    TURN = "q"
    LAW_TABLES = ("e_table", "mu_table", "rolling_table")

    model: Model3D
    state: State3D

    _warm_kernels = staticmethod(warm_up)

    def _setup(self) -> None:
        m, n = self.model, self.model.kind.shape[0]
        #: the most corners and faces a piece has (a ray kernel's room for one placed piece)
        self._ray_room = (
            int(m.piece_vcount.max(initial=1)),
            max(1, int(m.piece_fcount.max(initial=1))),
        )
        #: the bodies that could roll on a cloth (:mod:`.cloth`): none, and no step looks
        self._ball_shaped = cloth.ball_shaped(
            m.kind, m.body_pieces, m.piece_kind, m.piece_vcount, m.inertia
        )
        #: this step's balls on a cloth: each body's (contact row, cloth piece) or -1, and
        #: its cloth (:func:`.cloth.candidates`)
        self._held = np.full((n, 2), -1, np.int64)
        self._support = np.zeros((n, cloth.SUPPORT))
        self._n_held = 0
        self._made = _room(self._ci.shape[0])  # this step's manifolds, kept once it is taken
        self._made_count = 0
        self._ints = (
            m.piece_body, m.piece_kind, m.piece_vstart, m.piece_vcount, m.piece_fstart,
            m.piece_fcount, m.piece_cstart, m.piece_ccount, m.piece_estart, m.piece_ecount,
        )  # fmt: skip
        self._place(np.ones(n, np.bool_))

    def _rest_boxes(self) -> None:
        n = self.model.kind.shape[0]
        still = np.zeros((n, 3))
        self._box(np.ones(n, np.bool_), still, still, 0.0)

    @staticmethod
    def _state_from(arrays: Mapping[str, NDArray[Any]]) -> State3D:
        kept = empty_manifolds(0)  # a checkpoint written before manifolds were kept
        return State3D(
            *(np.array(arrays[name] if name in arrays else kept[name]) for name in State3D._fields)
        )

    def sample(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Positions (n, 3), velocities (n, 3), quaternions (n, 4), angular velocities (n, 3)
        of the caller's bodies."""
        s, n = self.state, self.n_bodies
        return s.x[:n].copy(), s.v[:n].copy(), s.q[:n].copy(), s.w[:n].copy()

    # -- the stages of a step that are the dimension's own --------------------------------

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
            self._dynamic, m.gravity, self._pull, dt, 4.0 * self.settings.linear_slop,
            m.body_pieces,
            self._boxes,
        )  # fmt: skip

    def _pairs(self) -> int:
        m, s = self.model, self.state
        moving = (self._dynamic & self.memory.awake) | self._kinematic
        self._place(moving)
        self._box(moving, s.v, s.w, self.dt)
        return self._kept.update(self._boxes, m.piece_reach, m.piece_body, moving, self._dynamic)

    def _narrow(self, n_pairs: int) -> int:
        m, s, st, mem = self.model, self.state, self.settings, self.memory
        kept = (s.manifold_keys, s.manifold_ints, s.manifold_floats, int(s.manifold_count[0]))
        nc = int(
            contacts.narrow_phase(
                self._now, n_pairs, self._ints, m.piece_radius, m.piece_reach,
                s.vertices, s.normals, m.face_first, m.face_size, m.corners, m.edges,
                m.material, m.e_table, m.mu_table, m.rolling_table, s.x, s.q, s.v, s.w,
                self._dynamic, self._g, self._pull, self.dt, 4.0 * st.linear_slop,
                st.linear_slop,
                st.manifold_reuse * st.linear_slop, mem.cache_keys, mem.cache_ids,
                mem.cache_impulses, int(mem.cache_count[0]), kept, self._made, self._cf, self._ci,
            )
        )  # fmt: skip
        if nc >= 0:
            self._made_count = n_pairs
        return nc

    def _grow(self, size: int) -> None:
        super()._grow(size)
        self._made = _room(size)

    def _impact_kernel(self, todo: Isolated) -> tuple[FloatArray, int]:
        m, s, st = self.model, self.state, self.settings
        rolled = np.empty(0, np.int64)
        if self._n_held:
            rolled = np.flatnonzero((self._held[:, 0] >= 0) & (self._role == islands.ROLE_EXACT))
        before = self._energy(rolled) if rolled.size else 0.0
        log, logged = impacts.exact_impacts(
            (todo.rows, todo.first, todo.n, self._island_of), self._now, self._n_pairs,
            self._boxes, self._reach, self._ci, s.x, s.q, s.v, s.w, self._accel, m.kind,
            self._dynamic, m.inv_mass, m.inertia, m.inv_inertia, m.min_moment,
            (m.material, m.e_table, m.mu_table), m.body_pieces, self._ints, m.piece_radius,
            m.piece_reach, m.local_vertices, m.local_normals, m.face_first, m.face_size,
            m.corners, m.edges, s.vertices, s.normals, self.dt, st.substeps,
            1e-3 * st.linear_slop, 4.0 * st.linear_slop,
            self._closing_fast, (self._support, self._held), m.mass,
        )  # fmt: skip
        if rolled.size:
            # the balls that rolled between their impacts (an island handed back to the
            # solver is as it was): the cloth's friction and the velocity across it that an
            # impact gave took what the impacts' own losses do not account for
            rolled = rolled[self._island_of[rolled] >= 0]
            cloth.loaded(rolled, self._held, self._support, self._ci, self._cf, self.dt, m.mass)
            met = log[:logged]
            theirs = np.isin(met[:, 1].astype(np.int64), rolled) | np.isin(
                met[:, 2].astype(np.int64), rolled
            )
            self._book_cloth(self._energy(rolled) - before + float(met[theirs, 11].sum()))
        return log, int(logged)

    def _poses(self) -> tuple[FloatArray, FloatArray]:
        return self.state.x.copy(), self.state.q.copy()

    def _continuous(
        self,
        nc: int,
        closest: FloatArray,
        bodies: NDArray[np.int64],
        poses: tuple[FloatArray, FloatArray],
    ) -> None:
        m, s, st = self.model, self.state, self.settings
        impacts.continuous(
            bodies, poses[0], s.x, s.q, s.v, s.w, self._ci, nc, closest, self._reach,
            self._dynamic, m.inertia, m.inv_inertia, m.body_pieces, self._ints,
            m.piece_radius, m.piece_reach, m.local_vertices, m.local_normals, m.face_first,
            m.face_size, m.corners, m.edges, s.vertices, s.normals, self.dt,
            4.0 * st.linear_slop, st.linear_slop,
        )  # fmt: skip

    def _fly(self, free: NDArray[np.int64]) -> None:
        m, s, a, t = self.model, self.state, self._accel, self._spin_load
        motion.fly_all(
            free, self.dt, self.settings.substeps, s.x, s.q, s.v, s.w, a, m.inertia,
            m.inv_inertia, t,
        )  # fmt: skip

    def _cast(
        self, rays: tuple[FloatArray, ...], movers: tuple[Any, ...], mask: int, hits: Any
    ) -> None:
        m, s = self.model, self.state
        queries.cast_rays(
            rays[0], rays[1], rays[2], self._reach[0], self._reach[1], movers, s.x, s.q,
            (m.piece_body, m.piece_kind, m.piece_vstart, m.piece_vcount, m.piece_fstart,
             m.piece_fcount, m.piece_cstart), m.piece_radius, m.local_vertices,
            m.local_normals, m.face_first, m.face_size, m.corners, self.filters[:, 0],
            mask, self._ray_room, hits[0], hits[1], hits[2],
        )  # fmt: skip

    def _cast_shape(
        self, cast: tuple[Any, ...], pose: FloatArray, move: FloatArray,
        candidates: NDArray[np.int64], mask: int, hit: FloatArray,
    ) -> int:  # fmt: skip
        # the shape as one more body (its model ``cast[0]``, pieces in its origin's frame)
        # after the world's, its pieces' starts moved past the world's rows; every body still
        m, s, c = self.model, self.state, cast[0]
        n, pieces = m.kind.shape[0], m.piece_body.shape[0]
        shift = (0, 0, m.local_vertices.shape[0], 0, m.local_normals.shape[0], 0,
                 m.corners.shape[0], 0, m.edges.shape[0], 0)  # fmt: skip
        theirs = (np.full(c.piece_body.shape[0], n), c.piece_kind, c.piece_vstart,
                  c.piece_vcount, c.piece_fstart, c.piece_fcount, c.piece_cstart,
                  c.piece_ccount, c.piece_estart, c.piece_ecount)  # fmt: skip
        ints: Any = tuple(
            np.concatenate((mine, other + k)).astype(np.int64)
            for mine, other, k in zip(self._ints, theirs, shift, strict=True)
        )

        def both(name: str) -> NDArray[Any]:
            return np.concatenate((getattr(m, name), getattr(c, name)))

        v = np.zeros((n + 1, 3))
        v[n] = move
        still = np.zeros((n + 1, 3))
        corners, faces = both("local_vertices"), both("local_normals")
        return int(
            impacts.cast_shape(
                candidates, np.arange(pieces, pieces + c.piece_body.shape[0]),
                np.vstack((s.x, pose[:3])), np.vstack((s.q, pose[3:])), v, still, still,
                both("inertia"), both("inv_inertia"), ints, both("piece_radius"),
                both("piece_reach"), corners, faces, both("face_first"), both("face_size"),
                both("corners"), both("edges"), np.empty_like(corners), np.empty_like(faces),
                self.filters[:, 0], mask, hit,
            )
        )  # fmt: skip

    def _sensed(self) -> NDArray[np.int64]:
        m, s = self.model, self.state
        keys: NDArray[np.int64] = queries.sensed(
            self._kept.pairs, self._n_found, self.sensors.mask, self.sensors.filters,
            self.callers, s.x, s.q, self._ints, m.piece_radius, m.local_vertices,
            m.local_normals, m.face_first, m.face_size, m.corners, m.edges, s.vertices,
            s.normals,
        )  # fmt: skip
        return keys

    def _overlap(
        self, candidates: NDArray[np.int64], low: FloatArray, high: FloatArray, point: bool,
        mask: int, hit: NDArray[np.bool_],
    ) -> None:  # fmt: skip
        m, s = self.model, self.state
        queries.overlap_pieces(
            candidates, low, high, point, s.x, s.q,
            (m.piece_body, m.piece_kind, m.piece_vstart, m.piece_vcount, m.piece_fstart,
             m.piece_fcount, m.piece_cstart, m.piece_estart, m.piece_ecount), m.piece_radius,
            m.local_vertices, m.local_normals, m.face_first, m.corners, m.edges,
            self.filters[:, 0], mask, self._ray_room, hit,
        )  # fmt: skip

    def _on_cloth(
        self, nc: int, closest: FloatArray, closing: FloatArray, loaded: Loaded | None
    ) -> NDArray[np.bool_]:
        skip = np.zeros(max(nc, 1), np.bool_)
        self._n_held = 0
        if not self._ball_shaped.any():
            return skip
        m, s, st = self.model, self.state, self.settings
        pushed = self._loads.none_torqued if loaded is None else loaded.on
        placed = (
            s.vertices, s.normals, m.piece_vstart, m.piece_fstart, m.piece_fcount,
            m.piece_cstart, m.face_first, m.face_size, m.corners,
        )  # fmt: skip
        limits = (
            0.1 * st.linear_slop, self._closing_fast, self._leaving, self.dt,
            4.0 * st.linear_slop,
        )  # fmt: skip
        self._n_held = cloth.candidates(
            self._ci, self._cf, nc, closest, closing, m.kind, self.memory.awake,
            self._ball_shaped, m.body_pieces, m.piece_kind, m.piece_radius, m.mass, m.inertia,
            self._accel, pushed, self._links, limits, s.x, s.v, placed, skip, self._held,
            self._support,
        )  # fmt: skip
        return skip

    def _roll_cloth(self) -> None:
        if not self._n_held:
            return
        m, s, st = self.model, self.state, self.settings
        balls = np.flatnonzero((self._held[:, 0] >= 0) & (self._role == islands.ROLE_FREE))
        if not balls.size:
            return
        self._role[balls] = islands.ROLE_CLOTH
        before = self._energy(balls)
        cloth.roll_all(
            balls, self._held, self._support, self._ci, self._cf, self.dt, st.substeps, s.x,
            s.q, s.v, s.w, m.mass, m.inertia, m.inv_inertia,
        )  # fmt: skip
        self._book_cloth(self._energy(balls) - before)

    def _book_cloth(self, change: float) -> None:
        """Book the energy ``change`` [J] of balls on the cloth that no impact accounts for:
        friction's, and the dropped velocity across the cloth's."""
        if change < 0.0:
            self._energy_lost -= change
        else:
            self._energy_given += change

    def _solver_bodies(self) -> NDArray[np.int64]:
        return np.flatnonzero((self._role == islands.ROLE_SOLVER) & self._dynamic)

    def _solve(self, nc: int, bodies: NDArray[np.int64], work: FloatArray) -> None:
        m, s, dt = self.model, self.state, self.dt
        active, _ = self._joints_now()
        solver.solve_step(
            self._cf, self._ci, nc, bodies, m.inv_mass, m.inertia, m.inv_inertia,
            self._accel, self._spin_load, self._movers, s.x, s.q, s.v, s.w, self._knobs(),
            work, self.joint_floats, self.joint_ints, active,
        )  # fmt: skip
        for i in self._movers.tolist():  # kinematic bodies: their own steady motion
            s.x[i] += dt * s.v[i]
            turn(s.q, i, s.w[i, 0], s.w[i, 1], s.w[i, 2], dt, 3)

    def _keep_manifolds(self) -> None:
        # this step's manifolds for the next; the last step's rows take the next ones
        s = self.state
        keys, ints, floats = self._made
        self._made = (s.manifold_keys, s.manifold_ints, s.manifold_floats)
        self.state = s = s._replace(manifold_keys=keys, manifold_ints=ints, manifold_floats=floats)
        s.manifold_count[0] = self._made_count

    def _keyed(self) -> tuple[NDArray[Any], ...]:
        s = self.state
        used = int(s.manifold_count[0])
        return (s.manifold_keys[:used], s.manifold_ints[:used], s.manifold_floats[:used])

    def _take_keyed(self, keys: NDArray[np.int64], tables: tuple[NDArray[Any], ...]) -> None:
        # the manifolds another engine of this world kept, for this one's next step
        ints, floats = tables
        rows = max(len(keys), self._ci.shape[0])
        kept = empty_manifolds(rows)
        kept["manifold_keys"][: len(keys)] = keys
        kept["manifold_ints"][: len(keys)] = ints
        kept["manifold_floats"][: len(keys)] = floats
        kept["manifold_count"][0] = len(keys)
        self.state = self.state._replace(**kept)

    def _fastest(self) -> FloatArray:
        m, s = self.model, self.state
        fastest = np.zeros(m.kind.shape[0])  # static pieces reach far (a plane: inf)
        dyn = self._dynamic
        spin = np.linalg.norm(s.w[dyn], axis=1)
        fastest[dyn] = np.linalg.norm(s.v[dyn], axis=1) + spin * m.reach[dyn]
        return fastest

    def _stop(self, asleep: NDArray[np.int64]) -> float:
        s = self.state
        taken = self._energy(asleep) - self._potential(asleep)
        s.v[asleep] = 0.0
        s.w[asleep] = 0.0
        return taken

    def _potential(self, rows: NDArray[np.int64]) -> float:
        """Gravitational potential energy ``-m g . x`` of the bodies ``rows`` [J]."""
        m, s = self.model, self.state
        return float(-np.sum(m.mass[rows] * (s.x[rows] @ m.gravity)))

    def _kick(
        self, ids: NDArray[np.int64], impulses: FloatArray, points: FloatArray,
        alive: NDArray[np.bool_],
    ) -> tuple[bool, float]:  # fmt: skip
        m, s, mem = self.model, self.state, self.memory
        done, work = motion.kick(
            ids, impulses, points, s.x, s.v, s.q, s.w, m.inv_mass, m.inv_inertia, m.mass,
            m.inertia, (alive, self._dynamic, LARGEST), (mem.awake, mem.clock),
        )  # fmt: skip
        return bool(done), float(work)

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
