"""3D rigid bodies in ``carom compare``: the scene as plain data, the closed form, the yardstick.

A :class:`RigidScene3D` is what carom's 3D rigid-body engine starts from
(:func:`carom.engines.rigid3d.assemble.world_parts`): every body's pieces in its own frame
(centre of mass at the origin), mass, inertia tensor, kind, pose and velocities, and the
restitution and friction of every pair of materials. :func:`primitives` names each body's
pieces as the peers' shapes (sphere, capsule, box, convex hull, triangle mesh, plane), so every
peer builds the same bodies.

:func:`impact_expectation3d` gives the closed form of one body landing on level ground (a box
on an edge or a corner, a rod on its end, a spinning ball): the time of impact from free
fall, then Newton's restitution at the touching points with the full inertia tensor
(Hecker's impulse with Coulomb friction for one point, :func:`carom.laws.rigid_impact.
point_impulse`; the exact frictionless normal impulses for two to four), then torque-free
flight with the angular momentum kept. :class:`RigidMonitor3D` measures every engine from its
poses and velocities alone: energies, angular momentum, overlap (carom's exact geometry on
the poses each engine reports), bodies whose centre passed through a static body, the top
body's drift and the largest rotation.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from carom.compare import yardstick
from carom.compare.yardstick import ImpactBase, RigidSceneBase, Yardstick
from carom.engines.rigid3d.assemble import world_parts
from carom.engines.rigid3d.driver import RigidEngine3D
from carom.engines.rigid3d.impacts import normal_lcp
from carom.engines.rigid3d.model import (
    PIECE_PLANE,
    PIECE_ROUND,
    Model3D,
    Piece3D,
    State3D,
    new_state,
)
from carom.engines.rigid3d.motion import free_turn
from carom.engines.stepped.settings import RigidSettings
from carom.errors import CaromError
from carom.geometry.rotation import matrix_quaternion, rotation_matrices, turn, turned_angle
from carom.laws.kinds import KIND_DYNAMIC, KIND_KINEMATIC, KIND_STATIC
from carom.laws.rigid_impact import collision_matrix, point_impulse
from carom.world import World

__all__ = [
    "ImpactCheck3D",
    "Primitive",
    "RigidMonitor3D",
    "RigidScene3D",
    "impact_expectation3d",
    "path_enters",
    "primitives",
    "principal_frame",
    "world_momentum",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: a box's corners lie on two planes per axis to within this [m]
BOX_TOLERANCE = 1e-12


@dataclass(frozen=True)
class RigidScene3D(RigidSceneBase):
    """Plain data of a 3D rigid scene as carom's 3D engine starts it: the fields of
    :class:`carom.compare.yardstick.RigidSceneBase` and each body's ``pieces`` (tuples of
    :class:`Piece3D` in the body's frame, centre of mass at the origin [m]).

    Its ``model`` (a :class:`Model3D`) and ``start`` (a :class:`State3D`) give ``inertia``
    (B, 3, 3) [kg m^2], ``gravity`` (3,), ``position`` and ``velocity`` (B, 3),
    ``orientation`` (B, 4) unit quaternions ``(w, x, y, z)`` and ``omega`` (B, 3) [rad/s] in
    the world frame.
    """

    pieces: tuple[tuple[Piece3D, ...], ...]

    dim = 3

    @classmethod
    def _parts(cls, world: World) -> tuple[Model3D, State3D]:
        model, state, _ = world_parts(world)
        if not isinstance(model, Model3D) or not isinstance(state, State3D):
            raise CaromError("RigidScene3D takes a 3D world; a 2D one is a RigidScene")
        return model, state

    @staticmethod
    def _pieces(model: Model3D) -> tuple[tuple[Piece3D, ...], ...]:
        m = model
        pieces = []
        for body in range(m.kind.shape[0]):
            own = []
            for p in range(int(m.body_pieces[body]), int(m.body_pieces[body + 1])):
                vs, vc = int(m.piece_vstart[p]), int(m.piece_vcount[p])
                fs, fc = int(m.piece_fstart[p]), int(m.piece_fcount[p])
                cs, cc = int(m.piece_cstart[p]), int(m.piece_ccount[p])
                es, ec = int(m.piece_estart[p]), int(m.piece_ecount[p])
                own.append(
                    Piece3D(
                        int(m.piece_kind[p]),
                        m.local_vertices[vs : vs + vc].copy(),
                        float(m.piece_radius[p]),
                        m.local_normals[fs : fs + fc].copy(),
                        m.face_first[fs : fs + fc].copy(),
                        m.face_size[fs : fs + fc].copy(),
                        m.corners[cs : cs + cc].copy(),
                        m.edges[es : es + ec].copy(),
                    )
                )
            pieces.append(tuple(own))
        return tuple(pieces)

    rolling = property(lambda self: self.model.rolling_table)
    orientation = property(lambda self: self.start.q)
    omega = property(lambda self: self.start.w)

    def energy(
        self, x: FloatArray, v: FloatArray, q: FloatArray, w: FloatArray
    ) -> tuple[float, float, float]:
        """Translational and rotational kinetic energy and potential energy [J] of the
        dynamic bodies among the first ``n`` (centres and velocities (n, 3), quaternions
        (n, 4), angular velocities (n, 3) in the world frame)."""
        dyn = self.kind[: self.n] == KIND_DYNAMIC
        m = self.mass[: self.n][dyn]
        translation = 0.5 * float(np.sum(m * np.sum(v[dyn] ** 2, axis=1)))
        spin = world_momentum(self.inertia[: self.n][dyn], q[dyn], w[dyn])
        rotation = 0.5 * float(np.sum(spin * w[dyn]))
        potential = -float(np.sum(m * (x[dyn] @ self.gravity)))
        return translation, rotation, potential

    @property
    def kinematic(self) -> IntArray:
        """The rows of the kinematic bodies (moved at constant velocities)."""
        return np.nonzero(self.kind == KIND_KINEMATIC)[0]

    def kinematic_pose(self, body: int, time: float) -> tuple[FloatArray, FloatArray]:
        """Where a kinematic body is at ``time`` [s]: its centre (3,) [m], moved at its
        constant velocity, and its orientation (4,), turned at its constant angular velocity
        (world frame) about its centre."""
        x = self.position[body] + self.velocity[body] * time
        q = self.orientation[body : body + 1].copy()
        w = self.omega[body]
        turn(q, 0, w[0], w[1], w[2], time, 3)  # as the engine turns it
        return x, q[0]


def world_momentum(inertia: FloatArray, q: FloatArray, w: FloatArray) -> FloatArray:
    """Spin angular momentum ``R I R^T w`` (n, 3) [kg m^2/s] of bodies with body-frame
    tensors (n, 3, 3), orientations (n, 4) and world angular velocities (n, 3)."""
    r = rotation_matrices(q)
    body = np.einsum("nji,nj->ni", r, w)
    return np.asarray(np.einsum("nij,nj->ni", r, np.einsum("nij,nj->ni", inertia, body)), float)


@dataclass(frozen=True)
class Primitive:
    """One piece of a body as the peers' shapes name it, in the body's frame.

    Attributes
    ----------
    shape : {"sphere", "capsule", "box", "hull", "mesh", "plane"}
    centre : (3,) float64
        A sphere's or box's centre [m] (a box's faces are parallel to the body's axes).
    half : (3,) float64
        A box's half sides [m].
    radius : float
        A sphere's or capsule's radius; a rounded hull's rounding [m].
    ends : (2, 3) float64
        A capsule's segment [m].
    vertices : (k, 3) float64
        A hull's corners or a mesh's vertices [m].
    triangles : (t, 3) int64
        A mesh's triangles, counter-clockwise from outside.
    normal : (3,) float64
        A plane's outward normal (solid below ``normal . x = offset``).
    offset : float
        A plane's offset [m].
    """

    shape: str
    centre: FloatArray = field(default_factory=lambda: np.zeros(3))
    half: FloatArray = field(default_factory=lambda: np.zeros(3))
    radius: float = 0.0
    ends: FloatArray = field(default_factory=lambda: np.zeros((2, 3)))
    vertices: FloatArray = field(default_factory=lambda: np.zeros((0, 3)))
    triangles: IntArray = field(default_factory=lambda: np.zeros((0, 3), np.int64))
    normal: FloatArray = field(default_factory=lambda: np.zeros(3))
    offset: float = 0.0


def _box(v: FloatArray) -> Primitive | None:
    """The box whose corners are ``v`` (8, 3), if they are an axis-aligned box's."""
    if v.shape[0] != 8:
        return None
    low, high = v.min(axis=0), v.max(axis=0)
    on_face = (np.abs(v - low) <= BOX_TOLERANCE) | (np.abs(v - high) <= BOX_TOLERANCE)
    if not np.all(on_face):
        return None
    corners = {tuple(row) for row in (np.abs(v - high) <= BOX_TOLERANCE).tolist()}
    if len(corners) != 8:
        return None
    return Primitive("box", centre=0.5 * (low + high), half=0.5 * (high - low))


def primitives(scene: RigidScene3D, body: int) -> list[Primitive]:
    """Body ``body``'s pieces as the peers' shapes, in its frame: round pieces as spheres and
    capsules, axis-aligned boxes as boxes, other polytopes as convex hulls, a static body's
    triangles as one mesh, planes as planes."""
    out: list[Primitive] = []
    mesh_v: list[FloatArray] = []
    for piece in scene.pieces[body]:
        v = piece.vertices
        if piece.kind == PIECE_PLANE:
            normal = piece.normals[0]
            out.append(Primitive("plane", normal=normal.copy(), offset=float(v[0] @ normal)))
        elif piece.kind == PIECE_ROUND:
            if v.shape[0] == 1:
                out.append(Primitive("sphere", centre=v[0].copy(), radius=piece.radius))
            else:
                out.append(Primitive("capsule", ends=v[:2].copy(), radius=piece.radius))
        elif v.shape[0] == 3 and piece.normals.shape[0] == 2:  # a mesh's flat triangle
            mesh_v.append(v)
        else:
            box = _box(v) if piece.radius == 0.0 else None
            out.append(box or Primitive("hull", vertices=v.copy(), radius=piece.radius))
    if mesh_v:
        triangles = np.arange(3 * len(mesh_v), dtype=np.int64).reshape(-1, 3)
        out.append(Primitive("mesh", vertices=np.concatenate(mesh_v), triangles=triangles))
    return out


def principal_frame(inertia: FloatArray) -> tuple[FloatArray, FloatArray]:
    """Principal moments (3,) [kg m^2] and the quaternion ``(w, x, y, z)`` that turns the
    principal axes into the body's frame, of a body-frame tensor (3, 3); identity when the
    tensor is already diagonal."""
    if np.all(inertia == np.diag(np.diag(inertia))):
        return np.diag(inertia).copy(), np.array([1.0, 0.0, 0.0, 0.0])
    moments, axes = np.linalg.eigh(inertia)
    if np.linalg.det(axes) < 0.0:
        axes[:, 2] = -axes[:, 2]
    return moments, matrix_quaternion(axes)


@dataclass(frozen=True)
class ImpactCheck3D(ImpactBase):
    """The closed form of one body landing on level ground, in 3D
    (:class:`carom.compare.yardstick.ImpactBase`): ``velocity`` (3,) [m/s], ``omega`` (3,)
    [rad/s] in the world frame (torque-free flight after the impact keeps the angular
    momentum).

    Attributes
    ----------
    points : int
        Points that touch at the impact (1 a corner or a ball, 2 an edge, 3-4 a face).
    """

    points: int


def _lowest(
    scene: RigidScene3D, body: int, q: FloatArray, up: FloatArray
) -> tuple[FloatArray, float]:
    """The body's lowest points (k, 3) relative to its centre, turned by ``q`` (4,), and
    their height along ``up`` relative to the centre [m]."""
    r = rotation_matrices(q[None, :])[0]
    points: list[FloatArray] = []
    for piece in scene.pieces[body]:
        points.append(piece.vertices @ r.T - piece.radius * up)
    every = np.concatenate(points)
    height = every @ up
    low = float(height.min())
    return every[height <= low + yardstick.LEVEL], low


def _ground(scene: RigidScene3D, feet: FloatArray, up: FloatArray) -> tuple[int, float]:
    """The static body whose level top lies under every point of ``feet`` (k, 3) [m]
    (world), highest first, and its height along ``up``; (-1, -inf) if none."""
    best, top = -1, -math.inf
    below = float(np.min(feet @ up))
    for other in np.nonzero(scene.kind == KIND_STATIC)[0]:
        r = rotation_matrices(scene.orientation[other][None, :])[0]
        for piece in scene.pieces[int(other)]:
            normals = piece.normals @ r.T
            corners = piece.vertices @ r.T + scene.position[other]
            if piece.kind == PIECE_PLANE:
                if abs(float(normals[0] @ up) - 1.0) > yardstick.LEVEL:
                    continue
                height = float(corners[0] @ up)
            else:
                faces = np.nonzero(np.abs(normals @ up - 1.0) <= yardstick.LEVEL)[0]
                if faces.shape[0] != 1 or piece.kind == PIECE_ROUND:
                    continue
                f = int(faces[0])
                first, size = int(piece.face_first[f]), int(piece.face_size[f])
                ring = corners[piece.corners[first : first + size]]
                height = float(ring[0] @ up) + piece.radius
                # every foot inside the face's polygon, seen from above
                for a, b in zip(ring, np.roll(ring, -1, axis=0), strict=True):
                    side = np.cross(b - a, feet - a) @ up
                    if np.any(side < -yardstick.LEVEL):
                        height = -math.inf
                        break
            if top < height <= below + yardstick.LEVEL:
                best, top = int(other), height
    return best, top


def _flight(
    scene: RigidScene3D, body: int, q: FloatArray, w: FloatArray, tau: float
) -> tuple[FloatArray, FloatArray]:
    """Orientation and angular velocity after ``tau`` [s] of torque-free flight (the world
    angular momentum kept)."""
    qq, ww = q.reshape(1, 4).copy(), w.reshape(1, 3).copy()
    inertia = scene.inertia[body][None]
    inverse = np.linalg.inv(scene.inertia[body])[None]
    if tau > 0.0:
        free_turn(0, tau, 1, qq, ww, inertia, inverse)
    return qq[0], ww[0]


def impact_expectation3d(scene: RigidScene3D, step: float) -> ImpactCheck3D | None:
    """The closed form when one dynamic body falls onto level ground.

    The ground is the static plane, or the static polytope's level top face, under the
    body's lowest points. They reach it at the free-fall time. One point (a corner, a ball,
    a capsule's end): Hecker's impulse with the full inertia tensor and Coulomb friction
    (sticking, sliding or the cone's edge). Two to four points (an edge or a face): the
    exact normal impulses of the frictionless problem (each point's Newton restitution,
    none pulling), so only when the pair has no friction. Then torque-free flight; the
    check waits two steps of ``step`` and must come before any second contact. None when
    the scene is not of this kind; a body that spins before the impact must be a ball.
    ``step`` is the largest step of the engines compared [s], as in 2D.
    """
    dyn = np.nonzero(scene.kind == KIND_DYNAMIC)[0]
    g_norm = float(np.linalg.norm(scene.gravity))
    if dyn.shape[0] != 1 or np.any(scene.kind == KIND_KINEMATIC) or g_norm == 0.0:
        return None
    body = int(dyn[0])
    up = -scene.gravity / g_norm
    x0, v0 = scene.position[body], scene.velocity[body]
    q0, w0 = scene.orientation[body], scene.omega[body]
    ball = len(scene.pieces[body]) == 1 and scene.pieces[body][0].vertices.shape[0] == 1
    if np.any(w0 != 0.0) and not ball:
        return None  # a spinning body's lowest point changes as it falls
    feet, low = _lowest(scene, body, q0, up)
    ground, top = _ground(scene, feet + x0, up)
    if ground < 0:
        return None
    a, b = int(scene.material[body]), int(scene.material[ground])
    e, mu = float(scene.restitution[a, b]), float(scene.friction[a, b])
    drop = float(x0 @ up) + low - top
    vu = float(v0 @ up)
    t_hit = (vu + math.sqrt(vu * vu + 2.0 * g_norm * drop)) / g_norm
    v_hit = v0 + scene.gravity * t_hit
    mass = float(scene.mass[body])
    inv_inertia = np.linalg.inv(scene.inertia[body])
    r0 = rotation_matrices(q0[None, :])[0]
    iw = r0 @ inv_inertia @ r0.T  # the world inverse tensor at the impact
    u = v_hit[None, :] + np.cross(w0, feet)  # the points' velocities
    count = feet.shape[0]
    no_body = np.zeros((3, 3))
    if count == 1:
        k = collision_matrix(1.0 / mass, iw, feet[0], 0.0, no_body, np.zeros(3))
        impulses = point_impulse(u[0], up, k, e, mu)[None, :]
        law = "Hecker's impulse with Coulomb friction"
    else:
        if mu > 0.0 or count > 4:
            return None  # friction at several points: not this closed form
        kk = np.empty((count, count))
        for i in range(count):
            for j in range(count):
                # normal velocity change at point i per unit normal impulse at point j
                turn = iw @ np.cross(feet[j], up)
                kk[i, j] = 1.0 / mass + float(up @ np.cross(turn, feet[i]))
        bias = (1.0 + e) * (u @ up)
        lam = np.zeros(count)
        if not normal_lcp(kk, bias, count, lam):
            return None
        impulses = lam[:, None] * up[None, :]
        law = f"the exact frictionless impulses at {count} points"
    v_after = v_hit + impulses.sum(axis=0) / mass
    w_after = w0 + iw @ np.sum(np.cross(feet, impulses), axis=0)
    # the flight after the impact, until the body reaches the ground again
    x_hit = x0 + v0 * t_hit + 0.5 * scene.gravity * t_hit**2
    turning = [q0.copy(), w_after.copy()]  # the flight so far: asked once a step, in order

    def lands(t: float) -> bool:
        turning[:] = _flight(scene, body, turning[0], turning[1], yardstick.FLIGHT_STEP)
        tau = t - t_hit
        centre = x_hit + v_after * tau + 0.5 * scene.gravity * tau**2
        _, low_now = _lowest(scene, body, turning[0], up)
        return float(centre @ up) + low_now <= top

    t_next = yardstick.next_contact(t_hit, scene.until, yardstick.FLIGHT_STEP, lands)
    first = yardstick.check_time(t_hit, t_next, step)
    if first is None:
        return None
    _, w_check = _flight(scene, body, q0, w_after, first - t_hit)
    velocity = v_after + scene.gravity * (first - t_hit)
    reach = float(scene.model.reach[body])
    speed = float(np.max(np.abs(u @ up)))
    source = (
        f"free fall onto level ground, then Newton's restitution e = {e:g} with the full "
        f"inertia tensor ({law}, mu = {mu:g}), then torque-free flight"
    )
    return ImpactCheck3D(body, t_hit, first, velocity, w_check, max(speed, 1e-300), reach,
                         source, points=count)  # fmt: skip


class RigidMonitor3D(Yardstick):
    """The same yardstick for every engine, fed the poses and velocities after each step
    (:class:`carom.compare.rigid.Yardstick`; quaternions ``(w, x, y, z)`` and angular
    velocities in the world frame).

    Parameters
    ----------
    scene : RigidScene3D
    expected : ImpactCheck3D or None
    dt : float
        The interval between observations [s].
    """

    scene: RigidScene3D
    expected: ImpactCheck3D | None

    def _setup(self, dyn: IntArray) -> int:
        scene = self.scene
        self._q0 = scene.orientation[dyn].copy()
        # the static pieces' faces in the world (they never move): (normals, offsets)
        self._walls: list[tuple[FloatArray, FloatArray]] = []
        for body in np.nonzero(scene.kind == KIND_STATIC)[0]:
            r = rotation_matrices(scene.orientation[body][None, :])[0]
            for piece in scene.pieces[int(body)]:
                if piece.kind == PIECE_ROUND or piece.vertices.shape[0] == 3:
                    continue  # a centre never crosses a round core or a flat triangle
                normals = piece.normals @ r.T
                corners = piece.vertices @ r.T + scene.position[body]
                plane = piece.kind == PIECE_PLANE
                first = corners if plane else corners[piece.corners[piece.face_first]]
                offsets = np.sum(normals * first, axis=1)
                self._walls.append((normals, offsets))
        # a copy of carom's engine, only to measure overlaps of the poses it is given
        settings = RigidSettings(rate=scene.settings.rate, sleep=False, exact_impacts=False)
        m = scene.model
        self._probe = RigidEngine3D(
            m,
            new_state(m, scene.position, scene.velocity, scene.orientation, scene.omega),
            settings,
        )
        up = -scene.gravity / max(float(np.linalg.norm(scene.gravity)), 1e-300)
        heights = scene.position[dyn] @ up if np.any(up) else scene.position[dyn, 2]
        return int(dyn[np.argmax(heights)]) if dyn.shape[0] else -1

    def _energy(
        self, x: FloatArray, v: FloatArray, turn: FloatArray, spin: FloatArray
    ) -> tuple[float, float, float]:
        return self.scene.energy(x, v, turn, spin)

    def _turns(self, turn: FloatArray) -> FloatArray:
        return turned_angle(turn[self._dynamic], self._q0)

    def _momentum(self, x: FloatArray, v: FloatArray, turn: FloatArray, spin: FloatArray) -> float:
        scene, dyn = self.scene, self._dynamic
        m = scene.mass[: scene.n][dyn]
        own = world_momentum(scene.inertia[: scene.n][dyn], turn[dyn], spin[dyn])
        orbit = m[:, None] * np.cross(x[dyn], v[dyn])
        return float(np.linalg.norm(np.sum(own + orbit, axis=0)))

    def _overlap(self, x: FloatArray, turn: FloatArray) -> float:
        state = self._probe.state
        n = self.scene.n
        state.x[:n] = x
        state.q[:n] = turn / np.linalg.norm(turn, axis=1, keepdims=True)
        self._probe.memory.awake[:] = True
        return self._probe.deepest_overlap()[2]

    def _passed(self, before: FloatArray, after: FloatArray, rows: IntArray) -> None:
        for normals, offsets in self._walls:
            hit = path_enters(before, after, normals, offsets)
            self.through.update(int(i) for i in rows[hit])


def path_enters(
    before: FloatArray, after: FloatArray, normals: FloatArray, offsets: FloatArray
) -> NDArray[np.bool_]:
    """Which paths ``before[i] -> after[i]`` (n, 3) enter the convex region
    ``normals . x <= offsets`` (a polytope's faces, or a plane's one), clipped face by face
    (Cyrus-Beck); a path that starts inside does not count."""
    d = after - before
    low = np.zeros(before.shape[0])
    high = np.ones(before.shape[0])
    start_out = np.zeros(before.shape[0], bool)
    for normal, offset in zip(normals, offsets, strict=True):
        start = before @ normal - offset  # > 0: outside this face
        start_out |= start > 0.0
        rate = d @ normal
        with np.errstate(divide="ignore", invalid="ignore"):
            t = -start / rate
        low = np.where(rate < 0.0, np.maximum(low, t), low)
        high = np.where(rate > 0.0, np.minimum(high, t), high)
        high = np.where((rate == 0.0) & (start > 0.0), -1.0, high)
    return np.asarray(start_out & (low < high))
