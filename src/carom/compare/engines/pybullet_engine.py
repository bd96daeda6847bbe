"""pybullet (Bullet 3) in a comparison, set up as the PyBullet Quickstart Guide recommends.

* ``p.DIRECT`` (no GUI), the default step ``1/240`` s ("best to keep it at 240 Hz").
* Spheres (``GEOM_SPHERE``); walls are static ``GEOM_PLANE`` shapes, one per box face. A 2D
  scene runs in the plane z = 0 with no walls across z: nothing pushes a body out of it.
* ``changeDynamics``: ``restitution`` per body and wall so that Bullet's product rule
  (combined restitution = product of the two) gives carom's; ``lateralFriction``,
  ``rollingFriction`` and ``spinningFriction`` 0; ``linearDamping`` and ``angularDamping`` 0
  (their defaults, 0.04, would slow every body).
* ``restitutionVelocityThreshold`` (below it restitution is ignored) set to 0 when there is
  no gravity, so slow collisions keep their restitution; with gravity Bullet's default stays,
  since it is what lets a bouncing body come to rest.
* CCD off (``ccdSweptSphereRadius`` 0): the docs reserve it for bodies that move more than
  their size per step; the largest step per radius is reported.
"""

from __future__ import annotations

import os
import sys
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any

import numpy as np

from carom.compare.spec import PeerScene, factor_restitution
from carom.errors import CaromError
from carom.laws.kinds import KIND_DYNAMIC, KIND_KINEMATIC

__all__ = ["start", "start_rigid"]


@contextmanager
def _quiet_stderr() -> Iterator[None]:
    """Bullet writes its build time to standard error when imported; keep it off ours."""
    sys.stderr.flush()
    saved = os.dup(2)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 2)
            yield
    finally:
        os.dup2(saved, 2)
        os.close(saved)


with _quiet_stderr():
    import pybullet as p

DT = 1.0 / 240.0
#: the fields of p.getDynamicsInfo, as the Quickstart Guide names them
_DYNAMICS_INFO = (
    "mass",
    "lateral_friction",
    "local_inertia_diagonal",
    "local_inertial_pos",
    "local_inertial_orn",
    "restitution",
    "rolling_friction",
    "spinning_friction",
    "contact_damping",
    "contact_stiffness",
    "body_type",
    "collision_margin",
)


class PybulletSimulation:
    def __init__(self, scene: PeerScene) -> None:
        body_e, wall_e, notes, walls_exact = factor_restitution(scene, "pybullet")
        if not walls_exact:
            notes.append("pybullet has no per-pair restitution: those wall contacts are plastic")
        self.client = client = p.connect(p.DIRECT)
        self.dim = dim = scene.dim

        def three(v: np.ndarray) -> list[float]:
            return [float(c) for c in v] + [0.0] * (3 - dim)

        still = not np.any(scene.gravity)
        p.setGravity(*three(scene.gravity), physicsClientId=client)
        p.setTimeStep(DT, physicsClientId=client)
        if still:
            p.setPhysicsEngineParameter(restitutionVelocityThreshold=0.0, physicsClientId=client)
        no_friction = {
            "lateralFriction": 0.0,
            "rollingFriction": 0.0,
            "spinningFriction": 0.0,
            "physicsClientId": client,
        }
        self.ids: list[int] = []
        shapes: dict[float, int] = {}
        for i in range(scene.n):
            r = float(scene.radius[i])
            if r not in shapes:
                shapes[r] = p.createCollisionShape(p.GEOM_SPHERE, radius=r, physicsClientId=client)
            body = p.createMultiBody(
                baseMass=float(scene.mass[i]),
                baseCollisionShapeIndex=shapes[r],
                basePosition=three(scene.positions[i]),
                physicsClientId=client,
            )
            p.changeDynamics(
                body,
                -1,
                restitution=float(body_e[i]),
                linearDamping=0.0,
                angularDamping=0.0,
                **no_friction,
            )
            p.resetBaseVelocity(
                body, linearVelocity=three(scene.velocities[i]), physicsClientId=client
            )
            self.ids.append(body)
        for face in range(2 * dim):
            axis, upper = divmod(face, 2)
            normal = [0.0, 0.0, 0.0]
            normal[axis] = -1.0 if upper else 1.0
            point = [0.0, 0.0, 0.0]
            point[axis] = float(scene.box[axis]) if upper else 0.0
            plane = p.createCollisionShape(p.GEOM_PLANE, planeNormal=normal, physicsClientId=client)
            wall = p.createMultiBody(0.0, plane, basePosition=point, physicsClientId=client)
            p.changeDynamics(wall, -1, restitution=float(wall_e[face]), **no_friction)
        info = p.getDynamicsInfo(self.ids[0], -1, physicsClientId=client)
        self.dt = DT
        self.settings: dict[str, Any] = {
            "dt_s": DT,
            **p.getPhysicsEngineParameters(physicsClientId=client),
            "restitutionVelocityThreshold_m_s": 0.0 if still else "default",
            "shape": "GEOM_SPHERE",
            "walls": "static GEOM_PLANE per box face",
            "body_restitution": sorted(set(body_e.tolist())),
            "wall_restitution": wall_e.tolist(),
            "restitution_combine": "product",
            "lateral_rolling_spinning_friction": 0.0,
            "linear_angular_damping": 0.0,
            "first_body_dynamics_info": dict(zip(_DYNAMICS_INFO, info, strict=False)),
            "ccdSweptSphereRadius": 0.0,
        }
        self.notes = [
            *notes,
            "dt = 1/240 s, Bullet's default and the Quickstart Guide's advice",
            "damping set from 0.04 (default) to 0 and friction to 0: the scene has neither",
            "restitutionVelocityThreshold = 0 without gravity (restitution at every speed); "
            "Bullet's default with gravity, so bodies can come to rest",
        ]

    def step(self) -> None:
        p.stepSimulation(physicsClientId=self.client)

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        n, dim, client = len(self.ids), self.dim, self.client
        x = np.empty((n, dim))
        v = np.empty((n, dim))
        for k, body in enumerate(self.ids):
            x[k] = p.getBasePositionAndOrientation(body, physicsClientId=client)[0][:dim]
            v[k] = p.getBaseVelocity(body, physicsClientId=client)[0][:dim]
        return x, v

    def close(self) -> None:
        p.disconnect(physicsClientId=self.client)


def start(scene: PeerScene) -> PybulletSimulation:
    return PybulletSimulation(scene)


# --- 3D rigid bodies --------------------------------------------------------------------

#: the step on rigid scenes [s]: the Quickstart Guide's "best to keep it at 240 Hz"
RIGID_DT = DT


def _xyzw(q: np.ndarray) -> list[float]:
    """A carom quaternion ``(w, x, y, z)`` in Bullet's order ``(x, y, z, w)``."""
    return [float(q[1]), float(q[2]), float(q[3]), float(q[0])]


class PybulletRigidSimulation:
    """A 3D rigid scene in Bullet, built as the Quickstart Guide builds bodies.

    * Each body a ``createMultiBody`` of its shapes: ``GEOM_BOX``, ``GEOM_SPHERE``,
      ``GEOM_CAPSULE``, ``GEOM_MESH`` from vertices (a convex hull; a static triangle mesh
      with ``GEOM_FORCE_CONCAVE_TRIMESH``), ``GEOM_PLANE``; several shapes through
      ``createCollisionShapeArray``.
    * carom's mass and inertia tensor: the inertial frame at the centre of mass along the
      principal axes (``baseInertialFrameOrientation``), ``localInertiaDiagonal`` the
      principal moments.
    * Bullet multiplies the two surfaces' restitution and friction: per-body coefficients
      reproduce the scene's pairs (:func:`carom.compare.rigid.shape_coefficients`);
      rolling and spinning friction 0, damping 0 (its default 0.04 would slow every body).
    * A kinematic body is a body of mass 0 with its velocities (``resetBaseVelocity``), which
      Bullet moves without simulating; it is set to its exact pose where each step starts
      (``resetBasePositionAndOrientation``).
    * Sleeping as in the scene (``activationState``). Everything else at Bullet's defaults:
      240 Hz, its solver iterations, contact margins, CCD off.
    """

    def __init__(self, scene: Any) -> None:
        from carom.compare.rigid3d import primitives, principal_frame
        from carom.compare.yardstick import shape_coefficients
        from carom.geometry.rotation import quaternion_product

        e, notes = shape_coefficients(
            scene, scene.restitution, "product", "pybullet", "restitution"
        )
        mu, mu_notes = shape_coefficients(scene, scene.friction, "product", "pybullet", "friction")
        self.client = client = p.connect(p.DIRECT)
        p.setGravity(*[float(g) for g in scene.gravity], physicsClientId=client)
        p.setTimeStep(RIGID_DT, physicsClientId=client)
        still = not np.any(scene.gravity)
        if still:
            p.setPhysicsEngineParameter(restitutionVelocityThreshold=0.0, physicsClientId=client)
        self.n = scene.n
        self.scene = scene
        self.time = 0.0
        self.ids: list[int] = []
        self._principal: list[np.ndarray] = []
        for i in range(scene.bodies):
            shape = self._shape(scene, primitives(scene, i), i)
            dynamic = bool(scene.kind[i] == KIND_DYNAMIC)
            moments, frame = principal_frame(scene.inertia[i]) if dynamic else (None, None)
            body = p.createMultiBody(
                baseMass=float(scene.mass[i]) if dynamic else 0.0,
                baseCollisionShapeIndex=shape,
                basePosition=[float(c) for c in scene.position[i]],
                baseOrientation=_xyzw(scene.orientation[i]),
                baseInertialFramePosition=[0.0, 0.0, 0.0],
                baseInertialFrameOrientation=_xyzw(frame)
                if frame is not None
                else [0.0, 0.0, 0.0, 1.0],
                physicsClientId=client,
            )
            m = int(scene.material[i])
            extra: dict[str, Any] = {}
            if moments is not None:
                extra["localInertiaDiagonal"] = [float(c) for c in moments]
            if dynamic:
                extra["activationState"] = (
                    p.ACTIVATION_STATE_ENABLE_SLEEPING
                    if scene.settings.sleep
                    else p.ACTIVATION_STATE_DISABLE_SLEEPING
                )
            p.changeDynamics(
                body,
                -1,
                restitution=float(e[m]),
                lateralFriction=float(mu[m]),
                rollingFriction=0.0,
                spinningFriction=0.0,
                linearDamping=0.0,
                angularDamping=0.0,
                physicsClientId=client,
                **extra,
            )
            if dynamic or scene.kind[i] == KIND_KINEMATIC:
                p.resetBaseVelocity(
                    body,
                    linearVelocity=[float(c) for c in scene.velocity[i]],
                    angularVelocity=[float(c) for c in scene.omega[i]],
                    physicsClientId=client,
                )
            self.ids.append(body)
            # the body frame from the inertial frame Bullet reports: q_body = q_inertial f*
            turn = frame if frame is not None else np.array([1.0, 0.0, 0.0, 0.0])
            self._principal.append(turn * np.array([1.0, -1.0, -1.0, -1.0]))
        self._product = quaternion_product
        self.dt = RIGID_DT
        self.settings: dict[str, Any] = {
            "dt_s": RIGID_DT,
            **p.getPhysicsEngineParameters(physicsClientId=client),
            "restitutionVelocityThreshold_m_s": 0.0 if still else "default",
            "restitution_per_material": e.tolist(),
            "friction_per_material": mu.tolist(),
            "combine": "product (Bullet's rule)",
            "rolling_spinning_friction": 0.0,
            "linear_angular_damping": 0.0,
            "ccd": "off (Bullet's default)",
            "sleep": bool(scene.settings.sleep),
        }
        self.notes = [
            *notes,
            *mu_notes,
            "dt = 1/240 s, Bullet's default and the Quickstart Guide's advice",
            "carom's mass and full inertia tensor (principal moments and axes) for each body",
            "damping set from 0.04 (default) to 0; everything else at Bullet's defaults, CCD off",
        ]
        if np.any(scene.rolling > 0.0):
            self.notes.append("the scene's rolling resistance is not given to Bullet")

    def _shape(self, scene: Any, parts: list[Any], body: int) -> int:
        """One collision shape of a body's primitives."""
        client = self.client
        if len(parts) == 1:
            return self._one(parts[0], client)
        kinds, radii, halves, lengths, where, turns = [], [], [], [], [], []
        for part in parts:
            if part.shape not in ("box", "sphere", "capsule"):
                raise CaromError(
                    f"pybullet: body {body} of scene {scene.name!r} is a compound with a "
                    f"{part.shape} piece, which carom compare builds only from boxes, spheres "
                    f"and capsules; compare a scene of single convex bodies"
                )
            centre, turn, length = _frame_of(part)
            kinds.append(
                {"box": p.GEOM_BOX, "sphere": p.GEOM_SPHERE, "capsule": p.GEOM_CAPSULE}[part.shape]
            )
            radii.append(float(part.radius))
            halves.append([float(c) for c in part.half])
            lengths.append(length)
            where.append(centre)
            turns.append(turn)
        return int(
            p.createCollisionShapeArray(
                shapeTypes=kinds,
                radii=radii,
                halfExtents=halves,
                lengths=lengths,
                collisionFramePositions=where,
                collisionFrameOrientations=turns,
                physicsClientId=client,
            )
        )

    @staticmethod
    def _one(part: Any, client: int) -> int:
        centre, turn, length = _frame_of(part)
        frame = {"collisionFramePosition": centre, "collisionFrameOrientation": turn}
        if part.shape == "box":
            return int(
                p.createCollisionShape(
                    p.GEOM_BOX,
                    halfExtents=[float(c) for c in part.half],
                    physicsClientId=client,
                    **frame,
                )
            )
        if part.shape == "sphere":
            return int(
                p.createCollisionShape(
                    p.GEOM_SPHERE, radius=float(part.radius), physicsClientId=client, **frame
                )
            )
        if part.shape == "capsule":
            return int(
                p.createCollisionShape(
                    p.GEOM_CAPSULE,
                    radius=float(part.radius),
                    height=length,
                    physicsClientId=client,
                    **frame,
                )
            )
        if part.shape == "hull":
            return int(
                p.createCollisionShape(
                    p.GEOM_MESH, vertices=part.vertices.tolist(), physicsClientId=client
                )
            )
        if part.shape == "mesh":
            return int(
                p.createCollisionShape(
                    p.GEOM_MESH,
                    vertices=part.vertices.tolist(),
                    indices=part.triangles.ravel().tolist(),
                    flags=p.GEOM_FORCE_CONCAVE_TRIMESH,
                    physicsClientId=client,
                )
            )
        return int(
            p.createCollisionShape(
                p.GEOM_PLANE,
                planeNormal=[float(c) for c in part.normal],
                collisionFramePosition=[float(c) for c in part.normal * part.offset],
                physicsClientId=client,
            )
        )

    def step(self) -> None:
        # Bullet moves a body of mass 0 by its velocity in the step: set it where the step
        # starts, so that no error accumulates
        for row in self.scene.kinematic:
            x, q = self.scene.kinematic_pose(int(row), self.time)
            p.resetBasePositionAndOrientation(
                self.ids[row], [float(c) for c in x], _xyzw(q), physicsClientId=self.client
            )
            p.resetBaseVelocity(
                self.ids[row],
                linearVelocity=[float(c) for c in self.scene.velocity[row]],
                angularVelocity=[float(c) for c in self.scene.omega[row]],
                physicsClientId=self.client,
            )
        p.stepSimulation(physicsClientId=self.client)
        self.time += self.dt

    def state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        n, client = self.n, self.client
        x, v, w = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
        q = np.empty((n, 4))
        for k in range(n):
            body = self.ids[k]
            pos, orn = p.getBasePositionAndOrientation(body, physicsClientId=client)
            lin, ang = p.getBaseVelocity(body, physicsClientId=client)
            x[k], v[k], w[k] = pos, lin, ang
            q[k] = (orn[3], orn[0], orn[1], orn[2])
        q = self._product(q, np.array(self._principal[:n]))
        return x, v, q, w

    def close(self) -> None:
        p.disconnect(physicsClientId=self.client)


def _frame_of(part: Any) -> tuple[list[float], list[float], float]:
    """A primitive's frame in its body (position, Bullet quaternion) and a capsule's length
    between its caps' centres (Bullet's capsules lie along z)."""
    if part.shape != "capsule":
        return [float(c) for c in part.centre], [0.0, 0.0, 0.0, 1.0], 0.0
    a, b = part.ends
    axis = b - a
    length = float(np.linalg.norm(axis))
    z = axis / length
    # the shortest turn from z to the axis
    w = 1.0 + float(z[2])
    if w < 1e-12:
        turn = [1.0, 0.0, 0.0, 0.0]  # half a turn about x
    else:
        q = np.array([-z[1], z[0], 0.0, w])
        q /= np.linalg.norm(q)
        turn = [float(c) for c in q]
    return [float(c) for c in 0.5 * (a + b)], turn, length


def start_rigid(scene: Any) -> PybulletRigidSimulation:
    return PybulletRigidSimulation(scene)
