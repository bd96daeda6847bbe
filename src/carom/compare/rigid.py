"""Rigid bodies in ``carom compare``: the scene as plain data, the closed form, the yardstick.

A :class:`RigidScene` is what carom's rigid-body engine starts from
(:func:`carom.engines.rigid.assemble.world_parts`):
every body's convex pieces in its own frame, mass, inertia, kind, pose and velocities, and the
restitution and friction of every pair of materials; the box's walls and the planes are static
slabs, as carom sees them. Each peer builds the same bodies from it.

:func:`impact_expectation` gives the closed form of one body landing on flat ground (a rod
dropped at an angle, a box landing flat): the time of impact from free fall, and Newton's
restitution at the contact point with the body's inertia (Hecker's formula,
:func:`carom.laws.point_impulse.impulse`). :class:`RigidMonitor` measures every engine from its
poses and velocities alone: energy, overlap (carom's exact geometry on the poses each engine
reports), bodies whose centre passed through a static body, the top body's drift and the
largest rotation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom.compare.yardstick import (
    FLIGHT_STEP,
    LEVEL,
    ImpactBase,
    RigidSceneBase,
    Yardstick,
    check_time,
    next_contact,
)
from carom.engines.rigid.assemble import assemble
from carom.engines.rigid.driver import RigidEngine
from carom.engines.rigid.model import RigidModel, RigidState, new_state
from carom.engines.stepped.assemble import world_parts
from carom.engines.stepped.settings import RigidSettings
from carom.errors import CaromError
from carom.laws.kinds import KIND_DYNAMIC, KIND_KINEMATIC, KIND_STATIC
from carom.laws.point_impulse import impulse
from carom.shapes import ConvexPiece
from carom.world import World

__all__ = ["ImpactCheck", "RigidMonitor", "RigidScene", "impact_expectation"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class RigidScene(RigidSceneBase):
    """A 2D scene of rigid bodies as plain data, every body as carom's rigid engine sees it
    (:class:`carom.compare.yardstick.RigidSceneBase`: name, title, n, settings, until,
    model, start, world).

    Attributes
    ----------
    pieces : tuple of tuple of ConvexPiece
        Each body's convex pieces in its frame (centre of mass at the origin) [m]: one corner
        is a circle, two a capsule or segment, three or more a (rounded) polygon.

    ``model`` and ``start`` are a :class:`RigidModel` and :class:`RigidState`: ``inertia``
    (B,) [kg m^2], ``gravity`` (2,), ``position`` and ``velocity`` (B, 2), ``angle`` and
    ``omega`` (B,) [rad], [rad/s].
    """

    pieces: tuple[tuple[ConvexPiece, ...], ...]

    dim = 2

    @classmethod
    def _parts(cls, world: World) -> tuple[RigidModel, RigidState]:
        model, state, _ = world_parts(world, assemble)
        if not isinstance(model, RigidModel) or not isinstance(state, RigidState):
            raise CaromError("carom compare's rigid scenes are 2D; 3D comparisons come later")
        return model, state

    @staticmethod
    def _pieces(model: RigidModel) -> tuple[tuple[ConvexPiece, ...], ...]:
        rows = model.body_pieces
        pieces = []
        for body in range(model.kind.shape[0]):
            own = []
            for p in range(int(rows[body]), int(rows[body + 1])):
                start, count = int(model.piece_start[p]), int(model.piece_count[p])
                corners = model.local_vertices[start : start + count].copy()
                own.append(ConvexPiece(corners, float(model.piece_radius[p])))
            pieces.append(tuple(own))
        return tuple(pieces)

    angle = property(lambda self: self.start.angle)
    omega = property(lambda self: self.start.omega)

    def energy(self, x: FloatArray, v: FloatArray, omega: FloatArray) -> tuple[float, float, float]:
        """Translational and rotational kinetic energy and potential energy [J] of the
        dynamic bodies among the first ``n`` (centres (n, 2), velocities (n, 2), omega (n,))."""
        dyn = self.kind[: self.n] == KIND_DYNAMIC
        m, inertia = self.mass[: self.n][dyn], self.inertia[: self.n][dyn]
        translation = 0.5 * float(np.sum(m * np.sum(v[dyn] ** 2, axis=1)))
        rotation = 0.5 * float(np.sum(inertia * omega[dyn] ** 2))
        potential = -float(np.sum(m * (x[dyn] @ self.gravity)))
        return translation, rotation, potential


@dataclass(frozen=True)
class ImpactCheck(ImpactBase):
    """The closed form of one body landing on flat ground, in 2D
    (:class:`carom.compare.yardstick.ImpactBase`): ``velocity`` (2,) [m/s], ``omega`` a
    float [rad/s] about z."""


def _corners(scene: RigidScene, body: int, angle: float) -> tuple[FloatArray, FloatArray]:
    """The body's core corners turned by ``angle`` (relative to its centre) and their
    rounding radii."""
    turned = [piece.moved(np.zeros(2), angle) for piece in scene.pieces[body]]
    radii = [np.full(p.vertices.shape[0], p.radius) for p in turned]
    return np.concatenate([p.vertices for p in turned]), np.concatenate(radii)


def _placed(scene: RigidScene, body: int) -> list[ConvexPiece]:
    """The body's pieces where it starts, in world coordinates."""
    where, angle = scene.position[body], float(scene.angle[body])
    return [piece.moved(where, angle) for piece in scene.pieces[body]]


def impact_expectation(scene: RigidScene, step: float) -> ImpactCheck | None:
    """The closed form when one dynamic body, not spinning, falls onto flat ground.

    The ground is the static piece whose top is a level face under the body. The body's
    lowest point reaches it at the free-fall time; Newton's restitution acts there
    (Hecker's impulse with the body's inertia; a level face landing is struck under its
    centre of mass). Friction is left out, so the closed form holds only when the contact
    point does not slide (mu = 0, or no tangential velocity or lever arm). None when the
    scene is not of this kind, or when no engine step fits between the impact and the
    body's next contact.

    Parameters
    ----------
    scene : RigidScene
    step : float
        The largest step of the engines compared [s]: the check waits two of them.
    """
    dyn = np.nonzero(scene.kind == KIND_DYNAMIC)[0]
    if dyn.shape[0] != 1 or scene.omega[dyn[0]] != 0.0 or scene.gravity[0] != 0.0:
        return None
    if np.any(scene.kind == KIND_KINEMATIC) or scene.gravity[1] >= 0.0:
        return None
    body = int(dyn[0])
    g = -float(scene.gravity[1])
    x0, v0 = scene.position[body], scene.velocity[body]
    corners, radii = _corners(scene, body, float(scene.angle[body]))
    bottom = corners[:, 1] - radii
    low = float(bottom.min())
    touching = corners[bottom <= low + LEVEL]  # the lowest corner, or a level face's
    lowest_x = touching[:, 0] + x0[0]
    # the ground: the highest level top face below the body that spans its lowest point
    ground, top = -1, -math.inf
    for other in np.nonzero(scene.kind == KIND_STATIC)[0]:
        for piece in _placed(scene, int(other)):
            world = piece.vertices
            height = float(world[:, 1].max())
            level = world[np.abs(world[:, 1] - height) <= LEVEL * max(1.0, abs(height))]
            if level.shape[0] < 2:
                continue
            inside = np.all((lowest_x >= level[:, 0].min()) & (lowest_x <= level[:, 0].max()))
            if inside and top < height + piece.radius <= x0[1] + low:
                ground, top = int(other), height + piece.radius
    if ground < 0:
        return None
    a, b = int(scene.material[body]), int(scene.material[ground])
    e, mu = float(scene.restitution[a, b]), float(scene.friction[a, b])
    # free fall of the lowest point: y0 + low + vy t - g t^2 / 2 = top
    drop = x0[1] + low - top
    vy = float(v0[1])
    t_hit = (vy + math.sqrt(vy * vy + 2.0 * g * drop)) / g
    v_hit = v0 + scene.gravity * t_hit
    span = touching[:, 0]
    # a level face is struck under the centre of mass when it spans it, else at its end
    r_x = float(np.clip(0.0, span.min(), span.max()))
    r = np.array([r_x, low])
    lever = abs(r_x) > 0.0
    if mu > 0.0 and (lever or v_hit[0] != 0.0):
        return None  # friction acts: not this closed form
    normal = np.array([0.0, 1.0])
    mass, inertia = float(scene.mass[body]), float(scene.inertia[body])
    j = float(impulse(v_hit, normal, mass, math.inf, e=e, r_a=r, inertia_a=inertia))
    v_after = v_hit + j * normal / mass
    w_after = (r[0] * j * normal[1] - r[1] * j * normal[0]) / inertia

    # the flight after the impact, until a corner reaches the ground again
    def lands(t: float) -> bool:
        tau = t - t_hit
        y = x0[1] + vy * t_hit - 0.5 * g * t_hit**2 + v_after[1] * tau - 0.5 * g * tau**2
        turned, rad = _corners(scene, body, float(scene.angle[body]) + w_after * tau)
        return bool(float(np.min(turned[:, 1] - rad)) + y <= top)

    t_next = next_contact(t_hit, scene.until, FLIGHT_STEP, lands)
    check = check_time(t_hit, t_next, step)
    if check is None:
        return None
    velocity = v_after + scene.gravity * (check - t_hit)
    reach = max(piece.reach for piece in scene.pieces[body])
    speed = abs(float(v_hit[1]))  # the contact point's approach speed (no spin before)
    return ImpactCheck(
        body=body,
        impact_time=t_hit,
        time=check,
        velocity=velocity,
        omega=float(w_after),
        speed=max(speed, 1e-300),
        reach=reach,
        source=(
            f"free fall onto level ground, then Newton's restitution e = {e:g} at the "
            f"contact point with the body's inertia (Hecker's formula)"
        ),
    )


class RigidMonitor(Yardstick):
    """The same yardstick for every engine, fed the poses and velocities after each step
    (:class:`Yardstick`; angles and angular velocities about z).

    Parameters
    ----------
    scene : RigidScene
    expected : ImpactCheck or None
    dt : float
        The engine's step [s].
    """

    scene: RigidScene
    expected: ImpactCheck | None

    def _setup(self, dyn: IntArray) -> int:
        scene = self.scene
        self._angle0 = scene.angle[dyn].copy()
        # the static pieces in world coordinates (they never move)
        self._walls = [
            piece
            for body in np.nonzero(scene.kind == KIND_STATIC)[0]
            for piece in _placed(scene, int(body))
        ]
        # a copy of carom's engine, only to measure overlaps of the poses it is given
        settings = RigidSettings(rate=scene.settings.rate, sleep=False, exact_impacts=False)
        m = scene.model
        self._probe = RigidEngine(
            m, new_state(m, scene.position, scene.velocity, scene.angle, scene.omega), settings
        )
        return int(dyn[np.argmax(scene.position[dyn, 1])]) if dyn.shape[0] else -1

    def _energy(
        self, x: FloatArray, v: FloatArray, turn: FloatArray, spin: FloatArray
    ) -> tuple[float, float, float]:
        return self.scene.energy(x, v, spin)

    def _turns(self, turn: FloatArray) -> FloatArray:
        return np.asarray(np.abs(turn[self._dynamic] - self._angle0), float)

    def _momentum(self, x: FloatArray, v: FloatArray, turn: FloatArray, spin: FloatArray) -> float:
        scene, dyn = self.scene, self._dynamic
        m = scene.mass[: scene.n][dyn]
        own = scene.inertia[: scene.n][dyn] * spin[dyn]
        orbit = m * (x[dyn, 0] * v[dyn, 1] - x[dyn, 1] * v[dyn, 0])
        return float(np.sum(own + orbit))

    def _overlap(self, x: FloatArray, turn: FloatArray) -> float:
        state = self._probe.state
        n = self.scene.n
        state.x[:n] = x
        state.angle[:n] = turn
        self._probe.memory.awake[:] = True
        return self._probe.deepest_overlap()[2]

    def _passed(self, before: FloatArray, after: FloatArray, rows: IntArray) -> None:
        for piece in self._walls:
            hit = _segments_cross(before, after, piece.vertices)
            self.through.update(int(i) for i in rows[hit])


def _segments_cross(before: FloatArray, after: FloatArray, corners: FloatArray) -> NDArray[Any]:
    """Which paths ``before[i] -> after[i]`` (n, 2) enter a convex core: a polygon's inside
    (three or more corners, counter-clockwise) or a segment's line between its ends (two);
    a point (one corner) is never crossed by a centre."""
    d = after - before
    k = corners.shape[0]
    if k == 1:
        return np.zeros(before.shape[0], bool)
    if k == 2:
        a, b = corners
        e = b - a
        denom = d[:, 0] * e[1] - d[:, 1] * e[0]
        w = a - before
        with np.errstate(divide="ignore", invalid="ignore"):
            s = (w[:, 0] * e[1] - w[:, 1] * e[0]) / denom
            u = (w[:, 0] * d[:, 1] - w[:, 1] * d[:, 0]) / denom
        return np.asarray((denom != 0.0) & (s >= 0.0) & (s <= 1.0) & (u > 0.0) & (u < 1.0))
    # clip the path to each edge's inner half-plane (Cyrus-Beck)
    low = np.zeros(before.shape[0])
    high = np.ones(before.shape[0])
    for j in range(k):
        a, b = corners[j], corners[(j + 1) % k]
        outward = np.array([b[1] - a[1], a[0] - b[0]])
        start = (before - a) @ outward  # > 0: outside this edge
        rate = d @ outward
        with np.errstate(divide="ignore", invalid="ignore"):
            t = -start / rate
        entering = rate < 0.0
        leaving = rate > 0.0
        low = np.where(entering, np.maximum(low, t), low)
        high = np.where(leaving, np.minimum(high, t), high)
        parallel_out = (rate == 0.0) & (start > 0.0)
        high = np.where(parallel_out, -1.0, high)
    return np.asarray(low < high)
