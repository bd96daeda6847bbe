"""RigidEngine: the time-stepped rigid-body engine behind a World, in 2D.

The stages of a step are the shared driver's (:mod:`carom.engines.stepped.driver`); this
module names the 2D kernels: the pieces placed (:mod:`.motion`), their swept boxes
(:mod:`.broadphase`), the manifolds (:mod:`.contacts`), the exact impacts (:mod:`.impacts`),
free flight (:mod:`.motion`) and the soft step (:mod:`.solver`).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom.engines.rigid import broadphase, contacts, impacts, joints, motion, queries, solver
from carom.engines.rigid.model import RigidModel, RigidState
from carom.engines.stepped.driver import Isolated, SteppedEngine
from carom.engines.stepped.joints import rod_rows
from carom.engines.stepped.settings import RigidSettings
from carom.laws.kinds import KIND_DYNAMIC, KIND_KINEMATIC, KIND_STATIC
from carom.limits import LARGEST

__all__ = ["RigidEngine"]

FloatArray = NDArray[np.float64]


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
    engine.events.on = True  # (a game loop's steps gather contact events)
    engine.use_joints(*rod_rows(4, (1.0, 0.6), 0.5, joints))  # the circle on a rod
    for _ in range(40):
        engine.step()
    engine.deepest_overlap()
    _WARM = True


class RigidEngine(SteppedEngine):
    """The time-stepped engine for 2D rigid bodies with rotation: the shared driver
    (:class:`carom.engines.stepped.driver.SteppedEngine`, its parameters and energy ledger)
    with the 2D kernels."""

    DIMS = 2
    JOINT_FLOATS = joints.JOINT_FLOATS
    ROWS = contacts
    IMPACTS = impacts
    SPIN = "omega"
    TURN = "angle"

    model: RigidModel
    state: RigidState

    _warm_kernels = staticmethod(warm_up)

    def _setup(self) -> None:
        m, s = self.model, self.state
        self._g = float(np.hypot(*m.gravity))
        #: the most corners a piece has (a ray kernel's room for one placed piece)
        self._ray_room = (max(1, int(m.piece_count.max(initial=1))), 0)
        #: room for one manifold (the narrow phase's, a leaf kernel's: it allocates nothing)
        self._manifold = (np.empty(8), np.empty(2, np.int64))
        # place everything once: static pieces never move again
        motion.place_pieces(
            s.x, s.angle, np.ones(m.kind.shape[0], np.bool_), m.body_pieces, m.piece_start,
            m.piece_count, m.local_vertices, m.local_normals, s.vertices, s.normals,
        )  # fmt: skip

    def _rest_boxes(self) -> None:
        self._piece_boxes(np.zeros(self.model.kind.shape[0], np.bool_), 0.0)

    def _piece_boxes(self, moving: NDArray[np.bool_], dt: float) -> None:
        m, s = self.model, self.state
        broadphase.piece_boxes(
            s.vertices, m.piece_start, m.piece_count, m.piece_radius, m.piece_reach,
            m.piece_body, s.v, s.omega, moving, self._dynamic, float(m.gravity[0]),
            float(m.gravity[1]), self._pull, dt, 4.0 * self.settings.linear_slop, self._boxes,
        )  # fmt: skip

    @staticmethod
    def _state_from(arrays: Mapping[str, NDArray[Any]]) -> RigidState:
        return RigidState(*(np.array(arrays[name]) for name in RigidState._fields))

    def sample(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        s, n = self.state, self.n_bodies
        w = np.zeros((n, 3))
        w[:, 2] = s.omega[:n]
        return s.x[:n].copy(), s.v[:n].copy(), s.angle[:n].reshape(-1, 1).copy(), w

    # -- the stages of a step that are the dimension's own --------------------------------

    def _pairs(self) -> int:
        m, s = self.model, self.state
        moving = (self._dynamic & self.memory.awake) | self._kinematic
        motion.place_pieces(
            s.x, s.angle, moving, m.body_pieces, m.piece_start, m.piece_count,
            m.local_vertices, m.local_normals, s.vertices, s.normals,
        )  # fmt: skip
        self._piece_boxes(moving, self.dt)
        return self._kept.update(self._boxes, m.piece_reach, m.piece_body, moving, self._dynamic)

    def _narrow(self, n_pairs: int) -> int:
        m, s, st, mem = self.model, self.state, self.settings, self.memory
        return int(
            contacts.narrow_phase(
                self._now, n_pairs, s.vertices, s.normals, m.piece_start,
                m.piece_count, m.piece_radius, m.piece_reach, m.piece_body, m.material,
                m.e_table, m.mu_table, s.x, s.v, s.omega, self._dynamic, self._g, self._pull,
                self.dt, 4.0 * st.linear_slop, st.linear_slop, mem.cache_keys, mem.cache_ids,
                mem.cache_impulses, int(mem.cache_count[0]), self._cf, self._ci,
                self._manifold,
            )
        )  # fmt: skip

    def _impact_kernel(self, todo: Isolated) -> tuple[FloatArray, int]:
        m, s, st = self.model, self.state, self.settings
        log, logged = impacts.exact_impacts(
            (todo.rows, todo.first, todo.n, self._island_of), self._now, self._n_pairs,
            self._boxes, self._reach, self._ci, s.x, s.angle, s.v, s.omega, self._accel,
            m.kind, m.inv_mass, m.inv_inertia, m.mass, m.inertia, m.material, m.e_table,
            m.mu_table, m.body_pieces, m.piece_body, m.piece_start, m.piece_count,
            m.piece_radius, m.piece_reach, m.local_vertices, m.local_normals, s.vertices,
            s.normals, self.dt, 1e-3 * st.linear_slop, 4.0 * st.linear_slop,
            self._closing_fast,
        )  # fmt: skip
        return log, int(logged)

    def _fly(self, free: NDArray[np.int64]) -> None:
        s, a, dt = self.state, self._accel, self.dt
        motion.fly_all(free, dt, s.x, s.angle, s.v, s.omega, a)
        if self._loads.on:  # a torque's constant angular acceleration, exactly
            alpha = self._spin_load[free]
            s.angle[free] += 0.5 * alpha * dt * dt
            s.omega[free] += alpha * dt

    def _cast(
        self, rays: tuple[FloatArray, ...], movers: tuple[Any, ...], mask: int, hits: Any
    ) -> None:
        m, s = self.model, self.state
        queries.cast_rays(
            rays[0], rays[1], rays[2], self._reach[0], self._reach[1], movers, s.x, s.angle,
            m.piece_body, m.piece_start, m.piece_count, m.piece_radius, m.local_vertices,
            m.local_normals, self.filters[:, 0], mask, self._ray_room, hits[0], hits[1],
            hits[2],
        )  # fmt: skip

    def _cast_shape(
        self, cast: tuple[Any, ...], pose: FloatArray, move: FloatArray,
        candidates: NDArray[np.int64], mask: int, hit: FloatArray,
    ) -> int:  # fmt: skip
        m, s = self.model, self.state
        return int(
            queries.cast_shape(
                cast, pose, move, candidates, s.x, s.angle, m.piece_body, m.piece_start,
                m.piece_count, m.piece_radius, m.piece_reach, m.local_vertices,
                m.local_normals, self.filters[:, 0], mask, self._ray_room[0], hit,
            )
        )  # fmt: skip

    def _overlap(
        self, candidates: NDArray[np.int64], low: FloatArray, high: FloatArray, point: bool,
        mask: int, hit: NDArray[np.bool_],
    ) -> None:  # fmt: skip
        m, s = self.model, self.state
        queries.overlap_pieces(
            candidates, low, high, point, s.x, s.angle, m.piece_body, m.piece_start,
            m.piece_count, m.piece_radius, m.local_vertices, m.local_normals,
            self.filters[:, 0], mask, self._ray_room[0], hit,
        )  # fmt: skip

    def _sensed(self) -> NDArray[np.int64]:
        m, s = self.model, self.state
        keys: NDArray[np.int64] = queries.sensed(
            self._kept.pairs, self._n_found, self.sensors.mask, self.sensors.filters,
            self.callers, s.x, s.angle, m.piece_body, m.piece_start, m.piece_count,
            m.piece_radius, m.local_vertices, m.local_normals, s.vertices, s.normals,
        )  # fmt: skip
        return keys

    def _spin_of(self, torque: FloatArray) -> FloatArray:
        spin: FloatArray = torque * self.model.inv_inertia
        return spin

    def _solve(self, nc: int, bodies: NDArray[np.int64], work: FloatArray) -> None:
        m, s = self.model, self.state
        active, jointed = self._joints_now()
        solver.solve_step(
            self._cf, self._ci, nc, bodies, m.inv_mass, m.inv_inertia, self._accel,
            self._spin_load, s.x, s.angle, s.v, s.omega, self._knobs(), work,
            self.joint_floats, self.joint_ints, active, jointed, self._closing_fast,
        )  # fmt: skip

    def _poses(self) -> tuple[FloatArray, FloatArray]:
        return self.state.x.copy(), self.state.angle.copy()

    def _continuous(
        self,
        nc: int,
        closest: FloatArray,
        bodies: NDArray[np.int64],
        poses: tuple[FloatArray, FloatArray],
    ) -> None:
        m, s, slop = self.model, self.state, self.settings.linear_slop
        impacts.continuous(
            bodies, poses[0], poses[1], s.x, s.angle, s.v, s.omega, self._ci, nc, closest,
            self._reach, self._dynamic, m.reach, m.body_pieces, m.piece_body, m.piece_start,
            m.piece_count, m.piece_radius, m.piece_reach, m.local_vertices, m.local_normals,
            s.vertices, s.normals, self.dt, 4.0 * slop, slop,
        )  # fmt: skip

    def _fastest(self) -> FloatArray:
        s = self.state
        fastest: FloatArray = np.sqrt(s.v[:, 0] ** 2 + s.v[:, 1] ** 2) + np.abs(s.omega) * (
            self.model.reach
        )
        return fastest

    def _stop(self, asleep: NDArray[np.int64]) -> float:
        m, s = self.model, self.state
        taken = 0.0
        for i in asleep.tolist():
            vx, vy, w = float(s.v[i, 0]), float(s.v[i, 1]), float(s.omega[i])
            taken += 0.5 * (m.mass[i] * (vx * vx + vy * vy) + m.inertia[i] * (w * w))
            s.v[i] = 0.0
            s.omega[i] = 0.0
        return taken

    def _kick(
        self, ids: NDArray[np.int64], impulses: FloatArray, points: FloatArray,
        alive: NDArray[np.bool_],
    ) -> tuple[bool, float]:  # fmt: skip
        m, s, mem = self.model, self.state, self.memory
        done, work = motion.kick(
            ids, impulses, points, s.x, s.v, s.omega, m.inv_mass, m.inv_inertia, m.mass,
            m.inertia, (alive, self._dynamic, LARGEST), (mem.awake, mem.clock),
        )  # fmt: skip
        return bool(done), float(work)

    def _energy(self, rows: NDArray[np.int64]) -> float:
        m, s = self.model, self.state
        gx, gy = float(m.gravity[0]), float(m.gravity[1])
        return float(
            motion.mechanical_energy(
                rows, self._dynamic, m.mass, m.inertia, s.x, s.v, s.omega, gx, gy
            )
        )
