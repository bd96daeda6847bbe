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

__all__ = ["start"]


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
