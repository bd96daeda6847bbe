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
* Joints as Rapier's impulse joints (:func:`_add_joints`): spherical, revolute, prismatic and
  fixed joints, with limits and velocity motors, their frames set so that each joint is at
  rest where the scene starts; the world's end a fixed body at the origin.
"""

from __future__ import annotations

from typing import Any

import numpy as np
import rapier3d as r

from carom.compare.rigid3d import RigidScene3D, primitives, principal_frame
from carom.compare.yardstick import shape_coefficients
from carom.errors import CaromError
from carom.geometry.rotation import matrix_quaternion, rotation_matrices
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
        joint_notes = _add_joints(world, self.handles, scene)
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
            *joint_notes,
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


def _add_joints(world: Any, handles: list[Any], scene: RigidScene3D) -> list[str]:
    """The scene's joints as Rapier's impulse joints; the notes on how they were built.

    Each joint's frame on each body is the joint's world frame at the start seen from that
    body (anchor and axis turned into the body's frame), so every joint starts at rest and
    its angle or travel counts from the start, as carom's limits do. A motor is Rapier's
    velocity motor (``motor_velocity(speed, factor)``, its damping factor large, so it pushes
    at its most until at the speed) clamped at the motor's largest force or torque. Springs
    and distance joints are refused (carom compare gives Rapier the 3D rope's joints).
    """
    specs = scene.joints
    if not specs:
        return []
    ground = None
    if any(min(spec.a, spec.b) < 0 for spec in specs):
        ground = world.add_body(r.RigidBody.fixed(), [])
    turns = rotation_matrices(scene.orientation)
    for spec in specs:
        if spec.kind not in ("spherical", "revolute", "prismatic", "weld"):
            raise CaromError(
                f"rapier3d: scene {scene.name!r} has a {spec.kind} joint; carom compare gives "
                "Rapier spherical, revolute, prismatic and fixed joints"
            )
        if spec.spring is not None or spec.angular_spring is not None:
            raise CaromError(f"rapier3d: scene {scene.name!r} has a sprung {spec.kind} joint")

        def _local(body: int, anchor: np.ndarray) -> tuple[float, float, float]:
            turn = np.eye(3) if body < 0 else turns[body]
            centre = np.zeros(3) if body < 0 else scene.position[body]
            return _vector(turn.T @ (anchor - centre))

        def frame(body: int, anchor: np.ndarray) -> Any:
            turn = np.eye(3) if body < 0 else turns[body]
            w, x, y, z = (float(c) for c in matrix_quaternion(turn.T))
            rotation = r.Rotation3(w=w, x=x, y=y, z=z)
            return r.Isometry3(translation=_local(body, anchor), rotation=rotation)

        if spec.kind == "spherical":
            builder: Any = r.SphericalJointBuilder()
        elif spec.kind == "weld":
            builder = r.FixedJointBuilder()
        else:
            assert spec.axis is not None
            make = r.RevoluteJointBuilder if spec.kind == "revolute" else r.PrismaticJointBuilder
            builder = make(_vector(spec.axis))
        if spec.kind in ("spherical", "weld"):
            builder = builder.local_frame1(frame(spec.a, spec.anchor_a)).local_frame2(
                frame(spec.b, spec.anchor_b)
            )
        else:  # (these builders take anchors and axes: their frames follow from the axis)
            builder = builder.local_anchor1(_local(spec.a, spec.anchor_a)).local_anchor2(
                _local(spec.b, spec.anchor_b)
            )
            builder = _axes(builder, spec, turns)
            if spec.limits is not None:
                a = np.eye(3) if spec.a < 0 else turns[spec.a]
                b = np.eye(3) if spec.b < 0 else turns[spec.b]
                if spec.kind == "revolute" and not np.allclose(a.T @ b, np.eye(3), atol=1e-12):
                    raise CaromError(
                        f"rapier3d: scene {scene.name!r} has a limited hinge between bodies "
                        "turned differently at the start; Rapier's hinge counts its angle from "
                        "frames built from the axis alone"
                    )
                builder = builder.limits(*spec.limits)
            if spec.motor is not None:
                speed, most = spec.motor
                builder = builder.motor_velocity(speed, 1e6).motor_max_force(most)
        builder = builder.contacts_enabled(spec.collide)
        one = ground if spec.a < 0 else handles[spec.a]
        two = ground if spec.b < 0 else handles[spec.b]
        world.impulse_joints.insert(one, two, builder, True)
    return [
        "joints as Rapier's impulse joints, each body's frame of a joint its world frame at "
        "the start (limits and motors count from there); motors: motor_velocity with a large "
        "damping factor, clamped at the motor's force or torque"
    ]


def _axes(builder: Any, spec: Any, turns: np.ndarray) -> Any:
    """A hinge's or a slider's axis in each body's frame."""
    for body, method in ((spec.a, "local_axis1"), (spec.b, "local_axis2")):
        turn = np.eye(3) if body < 0 else turns[body]
        builder = getattr(builder, method)(_vector(turn.T @ spec.axis))
    return builder


def start_rigid(scene: RigidScene3D) -> RapierSimulation:
    return RapierSimulation(scene)
