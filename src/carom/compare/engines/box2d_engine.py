"""pybox2d (Box2D 2.3, ``box2d`` on PyPI) with carom's rigid bodies, set up as its manual
recommends.

* The scene's rate (60 Hz: the manual's "a time step of 1/60 seconds") with 8 velocity and 3
  position iterations ("the suggested iteration count for Box2D is 8 for velocity and 3 for
  position").
* Each convex piece as the matching fixture: a circle, an edge (a static segment), a polygon
  (at most ``b2_maxPolygonVertices`` corners); a capsule as a box and two circles on one
  body. Box2D 2.3 has no rounded polygons, so a polygon with a rounding radius is refused.
  The body's mass, centre and inertia are set from carom's exact mass properties
  (``massData``).
* ``friction`` per material under Box2D's ``sqrt(f_a f_b)`` rule and ``restitution`` under its
  ``max(r_a, r_b)`` rule, so that each pair gets the scene's value.
* Continuous collision (time of impact against static bodies) on, as by default; sleeping as
  in the scene.
* Joints as Box2D's own (:func:`_add_joints`): revolute, distance, rope, weld, prismatic and
  wheel joints, with their limits, motors and springs, ``collideConnected`` as the joint says.

Box2D 2.3 computes in single precision (float32): its answers agree with a closed form to
about 1e-7 relative at best.
"""

from __future__ import annotations

import warnings
from typing import Any

import numpy as np

from carom.compare.rigid import RigidScene
from carom.compare.yardstick import shape_coefficients
from carom.errors import CaromError
from carom.laws.kinds import KIND_DYNAMIC, KIND_STATIC

with warnings.catch_warnings():
    # its SWIG wrapper warns on import ("builtin type SwigPyPacked has no __module__"), and
    # made an error (python -W error, pytest's filterwarnings) that warning crashes the import
    warnings.simplefilter("ignore", DeprecationWarning)
    import Box2D

__all__ = ["start_rigid"]

VELOCITY_ITERATIONS = 8
POSITION_ITERATIONS = 3


class Box2DRigidSimulation:
    def __init__(self, scene: RigidScene) -> None:
        rough, notes = shape_coefficients(scene, scene.friction, "geometric", "Box2D", "friction")
        elastic, more = shape_coefficients(scene, scene.restitution, "max", "Box2D", "restitution")
        world = Box2D.b2World(
            gravity=(float(scene.gravity[0]), float(scene.gravity[1])),
            doSleep=scene.settings.sleep,
        )
        self.bodies: list[Any] = []
        for i in range(scene.bodies):
            kind = int(scene.kind[i])
            where = {
                "position": (float(scene.position[i, 0]), float(scene.position[i, 1])),
                "angle": float(scene.angle[i]),
            }
            if kind == KIND_DYNAMIC:
                body = world.CreateDynamicBody(**where)
            elif kind == KIND_STATIC:
                body = world.CreateStaticBody(**where)
            else:
                body = world.CreateKinematicBody(**where)
            material = int(scene.material[i])
            surface = {"friction": float(rough[material]), "restitution": float(elastic[material])}
            for piece in scene.pieces[i]:
                corners, radius = piece.vertices, piece.radius
                _add_piece(body, corners, radius, surface, i)
            if kind == KIND_DYNAMIC:
                mass = Box2D.b2MassData()
                mass.mass = float(scene.mass[i])
                mass.center = (0.0, 0.0)
                mass.I = float(scene.inertia[i])
                body.massData = mass
            if kind != KIND_STATIC:
                body.linearVelocity = (float(scene.velocity[i, 0]), float(scene.velocity[i, 1]))
                body.angularVelocity = float(scene.omega[i])
            self.bodies.append(body)
        joint_notes = _add_joints(world, self.bodies, scene)
        self.world = world
        self.n = scene.n
        self.dt = scene.dt
        self.settings: dict[str, Any] = {
            "dt_s": self.dt,
            "velocity_iterations": VELOCITY_ITERATIONS,
            "position_iterations": POSITION_ITERATIONS,
            "continuous_physics": world.continuousPhysics,
            "sleep": world.allowSleeping,
            "friction_per_material": rough.tolist(),
            "restitution_per_material": elastic.tolist(),
            "linear_slop_m": Box2D.b2_linearSlop,
            "polygon_radius_m": Box2D.b2_polygonRadius,
            "precision": "float32",
        }
        self.notes = [
            *notes,
            *more,
            "8 velocity and 3 position iterations at 1/60 s, the manual's suggestion",
            "massData from carom's exact mass properties (Box2D's own from density agree)",
            "Box2D 2.3 computes in float32",
            *joint_notes,
        ]

    def step(self) -> None:
        self.world.Step(self.dt, VELOCITY_ITERATIONS, POSITION_ITERATIONS)

    def state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        rows = [
            (*b.position, *b.linearVelocity, b.angle, b.angularVelocity)
            for b in self.bodies[: self.n]
        ]
        data = np.array(rows, dtype=np.float64).reshape(-1, 6)
        return data[:, 0:2].copy(), data[:, 2:4].copy(), data[:, 4].copy(), data[:, 5].copy()

    def close(self) -> None:
        pass


def _add_piece(
    body: Any, corners: np.ndarray, radius: float, surface: dict[str, float], row: int
) -> None:
    """One convex piece as Box2D 2.3 fixtures (density 1: massData replaces it)."""
    points = [(float(p[0]), float(p[1])) for p in corners]
    if len(points) == 1:
        body.CreateCircleFixture(radius=radius, pos=points[0], density=1.0, **surface)
        return
    if len(points) == 2 and radius == 0.0:
        body.CreateEdgeFixture(vertices=points, density=1.0, **surface)
        return
    if len(points) == 2:  # a capsule: the box between the two ends and a circle at each
        a, b = np.asarray(points[0]), np.asarray(points[1])
        along = (b - a) / float(np.linalg.norm(b - a))
        side = np.array([-along[1], along[0]]) * radius
        box = [a - side, b - side, b + side, a + side]
        body.CreatePolygonFixture(
            vertices=[(float(p[0]), float(p[1])) for p in box], density=1.0, **surface
        )
        for end in points:
            body.CreateCircleFixture(radius=radius, pos=end, density=1.0, **surface)
        return
    if radius > 0.0:
        raise CaromError(
            f"body {row} has a rounded polygon (radius {radius:g} m); Box2D 2.3 has no "
            f"rounded polygons: compare it with pymunk, or give the polygon radius 0"
        )
    if len(points) > Box2D.b2_maxPolygonVertices:
        raise CaromError(
            f"body {row} has a polygon of {len(points)} corners; Box2D 2.3 takes at most "
            f"{Box2D.b2_maxPolygonVertices}: split it into a compound"
        )
    body.CreatePolygonFixture(vertices=points, density=1.0, **surface)


def _add_joints(world: Any, bodies: list[Any], scene: RigidScene) -> list[str]:
    """The scene's joints as Box2D 2.3 joints; the notes on how they were built.

    Anchors are world points at the start (Box2D keeps them in each body's frame, its
    reference angles from the bodies' angles then, as carom does). A distance joint is
    Box2D's distance joint (rigid, or a spring by ``frequencyHz`` and ``dampingRatio``), a
    range with no least length its rope joint; a weld's angular spring is Box2D 2.3's weld
    softness (it has no linear one, nor a revolute or prismatic spring: refused).
    """
    ground: Any = None
    kinds: set[str] = set()
    for spec in scene.joints:
        if ground is None and min(spec.a, spec.b) < 0:
            ground = world.CreateStaticBody(position=(0.0, 0.0))
        a = ground if spec.a < 0 else bodies[spec.a]
        b = ground if spec.b < 0 else bodies[spec.b]
        pa = (float(spec.anchor_a[0]), float(spec.anchor_a[1]))
        pb = (float(spec.anchor_b[0]), float(spec.anchor_b[1]))
        common = {"bodyA": a, "bodyB": b, "collideConnected": spec.collide}
        kinds.add(spec.kind)
        unable = None
        if spec.kind == "revolute":
            extra: dict[str, Any] = {}
            if spec.limits is not None:
                extra = {
                    "enableLimit": True,
                    "lowerAngle": spec.limits[0],
                    "upperAngle": spec.limits[1],
                }
            if spec.motor is not None:
                extra |= {
                    "enableMotor": True,
                    "motorSpeed": spec.motor[0],
                    "maxMotorTorque": spec.motor[1],
                }
            unable = "a revolute spring" if spec.spring is not None else None
            world.CreateRevoluteJoint(anchor=pa, **common, **extra)
        elif spec.kind == "distance" and spec.limits is not None and spec.limits[0] == 0.0:
            world.CreateRopeJoint(
                localAnchorA=a.GetLocalPoint(pa),
                localAnchorB=b.GetLocalPoint(pb),
                maxLength=spec.limits[1],
                **common,
            )
        elif spec.kind == "distance":
            unable = "a distance joint with a least length" if spec.limits is not None else None
            hertz, ratio = spec.spring if spec.spring is not None else (0.0, 0.0)
            joint = world.CreateDistanceJoint(
                anchorA=pa, anchorB=pb, frequencyHz=hertz, dampingRatio=ratio, **common
            )
            joint.length = spec.length
        elif spec.kind == "weld":
            unable = "a weld's linear spring" if spec.spring is not None else None
            hertz, ratio = spec.angular_spring if spec.angular_spring else (0.0, 0.0)
            world.CreateWeldJoint(anchor=pa, frequencyHz=hertz, dampingRatio=ratio, **common)
        elif spec.kind in ("prismatic", "wheel"):
            assert spec.axis is not None
            axis = (float(spec.axis[0]), float(spec.axis[1]))
            extra = {}
            if spec.motor is not None:
                torque = "maxMotorForce" if spec.kind == "prismatic" else "maxMotorTorque"
                extra = {"enableMotor": True, "motorSpeed": spec.motor[0], torque: spec.motor[1]}
            if spec.kind == "prismatic":
                if spec.limits is not None:
                    extra |= {
                        "enableLimit": True,
                        "lowerTranslation": spec.limits[0],
                        "upperTranslation": spec.limits[1],
                    }
                unable = "a prismatic spring" if spec.spring is not None else None
                world.CreatePrismaticJoint(anchor=pa, axis=axis, **common, **extra)
            else:
                unable = "a wheel joint's limits" if spec.limits is not None else None
                hertz, ratio = spec.spring if spec.spring is not None else (0.0, 0.0)
                world.CreateWheelJoint(
                    anchor=pa, axis=axis, frequencyHz=hertz, dampingRatio=ratio, **common, **extra
                )
        else:
            unable = f"a {spec.kind} joint"
        if unable is not None:
            raise CaromError(
                f"scene {scene.name!r} has {unable}, which Box2D 2.3 does not have: compare "
                "it with pymunk"
            )
    if not kinds:
        return []
    return [
        f"joints ({', '.join(sorted(kinds))}) as Box2D 2.3's own joints (a rope joint for a "
        "range from 0), collideConnected as each joint says"
    ]


def start_rigid(scene: RigidScene) -> Box2DRigidSimulation:
    return Box2DRigidSimulation(scene)
