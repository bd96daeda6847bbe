"""Rapier (``rapier3d`` on PyPI, the 3D engine in f32) in a comparison, set up as its user
guide sets up rigid bodies.

* One ``PhysicsWorld`` at Rapier's default ``IntegrationParameters`` (1/60 s, its solver
  iterations), on one thread.
* Each body a ``RigidBody.dynamic()`` or ``fixed()`` at carom's pose and velocities, its
  pieces as colliders: ``cuboid``, ``ball``, ``capsule_from_endpoints``, ``convex_hull``,
  ``trimesh`` (a static mesh) and ``halfspace``. carom's mass and inertia tensor are given
  as the first collider's ``MassProperties`` (principal moments and frame); the others have
  no density.
* A kinematic body is ``kinematic_velocity_based()`` at its constant velocities.
* Rapier combines two colliders' coefficients by a rule; ``MULTIPLY`` is chosen for both
  friction and restitution, and per-material coefficients reproduce the scene's pairs
  (:func:`carom.compare.rigid.shape_coefficients`). No damping. Sleeping as in the scene
  (``can_sleep``). CCD off: Rapier's default.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import rapier3d as r

from carom.compare.rigid3d import RigidScene3D, primitives, principal_frame
from carom.compare.yardstick import shape_coefficients
from carom.errors import CaromError
from carom.laws.kinds import KIND_DYNAMIC, KIND_KINEMATIC

__all__ = ["RIGID_DT", "start_rigid"]

#: Rapier's default step [s] (IntegrationParameters.dt)
RIGID_DT = float(r.IntegrationParameters().dt)


def _xyzw(q: np.ndarray) -> tuple[float, float, float, float]:
    return (float(q[1]), float(q[2]), float(q[3]), float(q[0]))


def _vector(v: np.ndarray) -> tuple[float, float, float]:
    return (float(v[0]), float(v[1]), float(v[2]))


class RapierSimulation:
    def __init__(self, scene: RigidScene3D) -> None:
        e, notes = shape_coefficients(
            scene, scene.restitution, "product", "rapier3d", "restitution"
        )
        mu, mu_notes = shape_coefficients(scene, scene.friction, "product", "rapier3d", "friction")
        self.world = world = r.PhysicsWorld(gravity=_vector(scene.gravity))
        world.set_num_threads(1)
        self.n = scene.n
        self.handles = []
        rule = r.CoefficientCombineRule.MULTIPLY
        for i in range(scene.bodies):
            dynamic = bool(scene.kind[i] == KIND_DYNAMIC)
            m = int(scene.material[i])
            colliders = []
            for k, part in enumerate(primitives(scene, i)):
                builder = self._collider(scene, part, i)
                builder = (
                    builder.friction(float(mu[m]))
                    .restitution(float(e[m]))
                    .friction_combine_rule(rule)
                    .restitution_combine_rule(rule)
                )
                if dynamic:
                    if k == 0:
                        moments, frame = principal_frame(scene.inertia[i])
                        builder = builder.mass_properties(
                            r.MassProperties(
                                local_com=(0.0, 0.0, 0.0),
                                mass=float(scene.mass[i]),
                                principal_inertia=_vector(moments),
                                principal_inertia_local_frame=_xyzw(frame),
                            )
                        )
                    else:
                        builder = builder.density(0.0)
                colliders.append(builder)
            moved = bool(scene.kind[i] == KIND_KINEMATIC)
            if dynamic:
                body = r.RigidBody.dynamic()
            elif moved:
                body = r.RigidBody.kinematic_velocity_based()
            else:
                body = r.RigidBody.fixed()
            body = body.position((_vector(scene.position[i]), _xyzw(scene.orientation[i])))
            if moved:
                body = body.linvel(_vector(scene.velocity[i])).angvel(_vector(scene.omega[i]))
            if dynamic:
                body = body.linvel(_vector(scene.velocity[i])).angvel(_vector(scene.omega[i]))
                body = body.linear_damping(0.0).angular_damping(0.0)
                body = body.can_sleep(bool(scene.settings.sleep))
            self.handles.append(world.add_body(body, colliders))
        params = world.integration_parameters
        self.dt = float(params.dt)
        self.settings: dict[str, Any] = {
            "dt_s": self.dt,
            "num_solver_iterations": int(params.num_solver_iterations),
            "num_internal_pgs_iterations": int(params.num_internal_pgs_iterations),
            "num_internal_stabilization_iterations": int(
                params.num_internal_stabilization_iterations
            ),
            "prediction_distance_m": float(params.prediction_distance()),
            "allowed_linear_error_m": float(params.allowed_linear_error()),
            "combine": "MULTIPLY for friction and restitution",
            "restitution_per_material": e.tolist(),
            "friction_per_material": mu.tolist(),
            "ccd": "off (Rapier's default)",
            "sleep": bool(scene.settings.sleep),
            "threads": 1,
            "precision": "f32",
        }
        self.notes = [
            *notes,
            *mu_notes,
            "Rapier's default integration parameters (dt 1/60 s); one thread; f32 arithmetic",
            "carom's mass and inertia tensor on each body's first collider",
        ]
        if np.any(scene.rolling > 0.0):
            self.notes.append("the scene's rolling resistance is not given to Rapier")

    @staticmethod
    def _collider(scene: RigidScene3D, part: Any, body: int) -> Any:
        if part.shape == "box":
            hx, hy, hz = (float(c) for c in part.half)
            return r.Collider.cuboid(hx, hy, hz).translation(_vector(part.centre))
        if part.shape == "sphere":
            return r.Collider.ball(float(part.radius)).translation(_vector(part.centre))
        if part.shape == "capsule":
            a, b = part.ends
            return r.Collider.capsule_from_endpoints(_vector(a), _vector(b), float(part.radius))
        if part.shape == "hull":
            builder = r.Collider.convex_hull(np.asarray(part.vertices, float))
            if builder is None:
                raise CaromError(
                    f"rapier3d: body {body} of scene {scene.name!r}: Rapier could not build "
                    f"the convex hull of its piece"
                )
            return builder
        if part.shape == "mesh":
            return r.Collider.trimesh(
                np.asarray(part.vertices, float), np.asarray(part.triangles, np.uint32)
            )
        return r.Collider.halfspace(_vector(part.normal)).translation(
            _vector(part.normal * part.offset)
        )

    def step(self) -> None:
        self.world.step()

    def state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        n = self.n
        x, v, w = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3))
        q = np.empty((n, 4))
        bodies = self.world.rigid_bodies
        for k in range(n):
            b = bodies[self.handles[k]]
            x[k] = tuple(b.translation)
            v[k] = tuple(b.linvel)
            w[k] = tuple(b.angvel)
            qx, qy, qz, qw = b.rotation.to_tuple()
            q[k] = (qw, qx, qy, qz)
        return x, v, q, w

    def close(self) -> None:
        pass


def start_rigid(scene: RigidScene3D) -> RapierSimulation:
    return RapierSimulation(scene)
