"""pymunk (Chipmunk2D) in a comparison, set up as its documentation recommends.

* Fixed step ``dt = 1/60`` s: the docs and examples step ``space.step(1/60)`` ("a fixed time
  step ... 1/60 is a good default").
* ``Circle`` shapes with ``friction = 0`` and ``elasticity`` such that the product rule the docs
  state ("the elasticity of a collision is the product of the two shapes' elasticity") gives
  carom's restitution for every pair and wall.
* Walls are static boxes as thick as the box is wide, so nothing tunnels for lack of depth.
* ``collision_slop``, the overlap the solver allows, "as high as you can without noticeable
  overlapping": the default 0.1 is meant for pixels; here 1% of the smallest radius.
* Everything else (10 iterations, collision bias, no damping, no sleeping) at its default.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pymunk
import pymunk.batch

from carom.compare.rigid import RigidScene
from carom.compare.spec import PeerScene, factor_restitution
from carom.compare.yardstick import shape_coefficients
from carom.errors import CaromError
from carom.laws.kinds import KIND_DYNAMIC, KIND_STATIC

__all__ = ["start"]

DT = 1.0 / 60.0
BODY, WALL = 1, 2  # collision types; walls are WALL + face
SLOP_PER_RADIUS = 0.01


class PymunkSimulation:
    def __init__(self, scene: PeerScene) -> None:
        body_e, wall_e, notes, walls_exact = factor_restitution(scene, "pymunk")
        space = pymunk.Space()
        space.gravity = (float(scene.gravity[0]), float(scene.gravity[1]))
        space.collision_slop = SLOP_PER_RADIUS * float(scene.radius.min())
        self.bodies: list[pymunk.Body] = []
        for i in range(scene.n):
            m, r = float(scene.mass[i]), float(scene.radius[i])
            body = pymunk.Body(m, pymunk.moment_for_circle(m, 0.0, r))
            body.position = (float(scene.positions[i, 0]), float(scene.positions[i, 1]))
            body.velocity = (float(scene.velocities[i, 0]), float(scene.velocities[i, 1]))
            shape = pymunk.Circle(body, r)
            shape.elasticity = float(body_e[i])
            shape.friction = 0.0
            shape.collision_type = BODY
            space.add(body, shape)
            self.bodies.append(body)
        width, height = (float(s) for s in scene.box)
        thick = max(width, height)
        # x_lower, x_upper, y_lower, y_upper: solid slabs outside the box
        slabs = [
            (-thick, -thick, 0.0, height + thick),
            (width, -thick, width + thick, height + thick),
            (-thick, -thick, width + thick, 0.0),
            (-thick, height, width + thick, height + thick),
        ]
        for face, ((x0, y0, x1, y1), e) in enumerate(zip(slabs, wall_e, strict=True)):
            wall = pymunk.Poly(space.static_body, [(x0, y0), (x1, y0), (x1, y1), (x0, y1)])
            wall.elasticity = float(e)
            wall.friction = 0.0
            wall.collision_type = WALL + face
            space.add(wall)
        if not walls_exact:
            # the documented override: Arbiter.restitution set in a pre_solve callback
            index = {id(shape): i for i, b in enumerate(self.bodies) for shape in b.shapes}
            table = scene.wall_restitution

            def wall_restitution(arbiter: pymunk.Arbiter, _space: Any, face: int) -> None:
                ball = next(s for s in arbiter.shapes if s.collision_type == BODY)
                arbiter.restitution = float(table[index[id(ball)], face])

            for face in range(4):
                space.on_collision(BODY, WALL + face, pre_solve=wall_restitution, data=face)
            notes.append("body-wall restitution set per contact in a pre_solve callback")
        self.space = space
        self.dt = DT
        self._ids = np.array([b.id for b in self.bodies], dtype=np.uint64)
        self._fields = (
            pymunk.batch.BodyFields.BODY_ID
            | pymunk.batch.BodyFields.POSITION
            | pymunk.batch.BodyFields.VELOCITY
        )
        self._buffer = pymunk.batch.Buffer()
        self.settings: dict[str, Any] = {
            "dt_s": DT,
            **_space_settings(space),
            "shape": "Circle",
            "friction": 0.0,
            "body_elasticity": sorted(set(body_e.tolist())),
            "wall_elasticity": wall_e.tolist(),
            "walls": "static Poly slabs as thick as the box",
            "restitution_combine": "product",
            "ccd": "none (pymunk has no continuous collision detection)",
        }
        self.notes = [
            *notes,
            f"collision_slop = {SLOP_PER_RADIUS:g} x smallest radius (the docs: as high as "
            f"possible without noticeable overlap; the default 0.1 assumes pixel units)",
            "dt = 1/60 s, the step of pymunk's documentation and examples",
        ]

    def step(self) -> None:
        self.space.step(self.dt)

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        data = _read_bodies(self.space, self._fields, self._buffer, self._ids, 4)
        return data[:, 0:2].copy(), data[:, 2:4].copy()

    def close(self) -> None:
        pass


def start(scene: PeerScene) -> PymunkSimulation:
    return PymunkSimulation(scene)


def _space_settings(space: pymunk.Space) -> dict[str, Any]:
    """The space's solver settings, by pymunk's names."""
    return {
        "iterations": space.iterations,
        "collision_slop_m": space.collision_slop,
        "collision_bias": space.collision_bias,
        "collision_persistence": space.collision_persistence,
        "damping": space.damping,
        "idle_speed_threshold": space.idle_speed_threshold,
        "sleep_time_threshold": space.sleep_time_threshold,
    }


def _read_bodies(
    space: pymunk.Space, fields: Any, buffer: Any, ids: np.ndarray, width: int
) -> np.ndarray:
    """The ``fields`` of the bodies ``ids`` (in that order), ``width`` floats a body, read in
    one batch call (the space lists other bodies too: walls, static bodies)."""
    buffer.clear()
    pymunk.batch.get_space_bodies(space, fields, buffer)
    listed = np.frombuffer(buffer.int_buf(), dtype=np.uint64)
    data = np.frombuffer(buffer.float_buf(), dtype=np.float64).reshape(-1, width)
    if np.array_equal(listed, ids):
        return data
    order = np.argsort(listed, kind="stable")
    return data[order[np.searchsorted(listed[order], ids)]]


# -- rigid bodies ---------------------------------------------------------------------------


class PymunkRigidSimulation:
    """pymunk with carom's rigid bodies, set up as its documentation recommends.

    * The scene's rate (60 Hz in every built-in scene: the docs' ``space.step(1/60)``) and
      pymunk's default 10 solver iterations.
    * Each convex piece as the matching shape: a ``Circle``, a ``Segment`` with a radius (a
      capsule or static segment) or a ``Poly`` with a radius (a rounded polygon); the
      body's mass and moment set on the ``Body`` from carom's exact mass properties.
    * ``elasticity`` and ``friction`` per material, so that pymunk's product rule gives each
      pair the scene's value.
    * ``collision_slop`` = carom's linear slop (5 mm, Box2D's; pymunk's default 0.1 is
      meant for pixels), sleeping as in the scene (pymunk's default: none).
    * Joints as pymunk's constraints (:func:`_add_joints`), joined bodies kept from touching
      unless the joint lets them (``collide_bodies``, which pymunk leaves on by default).
    """

    def __init__(self, scene: RigidScene) -> None:
        elastic, notes = shape_coefficients(
            scene, scene.restitution, "product", "pymunk", "restitution"
        )
        rough, more = shape_coefficients(scene, scene.friction, "product", "pymunk", "friction")
        settings = scene.settings
        space = pymunk.Space()
        space.gravity = (float(scene.gravity[0]), float(scene.gravity[1]))
        space.collision_slop = settings.linear_slop
        if settings.sleep:
            space.sleep_time_threshold = settings.sleep_time
            space.idle_speed_threshold = settings.sleep_speed
        self.bodies: list[pymunk.Body] = []
        for i in range(scene.bodies):
            kind = int(scene.kind[i])
            if kind == KIND_DYNAMIC:
                body = pymunk.Body(float(scene.mass[i]), float(scene.inertia[i]))
            elif kind == KIND_STATIC:
                body = pymunk.Body(body_type=pymunk.Body.STATIC)
            else:
                body = pymunk.Body(body_type=pymunk.Body.KINEMATIC)
            body.position = (float(scene.position[i, 0]), float(scene.position[i, 1]))
            body.angle = float(scene.angle[i])
            if kind != KIND_STATIC:
                body.velocity = (float(scene.velocity[i, 0]), float(scene.velocity[i, 1]))
                body.angular_velocity = float(scene.omega[i])
            shapes: list[pymunk.Shape] = []
            for piece in scene.pieces[i]:
                corners, radius = piece.vertices, piece.radius
                points = [(float(p[0]), float(p[1])) for p in corners]
                if len(points) == 1:
                    shape: pymunk.Shape = pymunk.Circle(body, radius, points[0])
                elif len(points) == 2:
                    shape = pymunk.Segment(body, points[0], points[1], radius)
                else:
                    shape = pymunk.Poly(body, points, radius=radius)
                material = int(scene.material[i])
                shape.elasticity = float(elastic[material])
                shape.friction = float(rough[material])
                shapes.append(shape)
            space.add(body, *shapes)
            self.bodies.append(body)
        joint_notes = _add_joints(space, self.bodies, scene)
        self.n = scene.n
        self.space = space
        self.dt = scene.dt
        self._ids = np.array([b.id for b in self.bodies[: scene.n]], dtype=np.uint64)
        self._fields = (
            pymunk.batch.BodyFields.BODY_ID
            | pymunk.batch.BodyFields.POSITION
            | pymunk.batch.BodyFields.ANGLE
            | pymunk.batch.BodyFields.VELOCITY
            | pymunk.batch.BodyFields.ANGULAR_VELOCITY
        )
        self._buffer = pymunk.batch.Buffer()
        self.settings: dict[str, Any] = {
            "dt_s": self.dt,
            **_space_settings(space),
            "elasticity_per_material": elastic.tolist(),
            "friction_per_material": rough.tolist(),
            "ccd": "none (pymunk has no continuous collision detection)",
        }
        self.notes = [
            *notes,
            *more,
            "shapes: Circle, Segment with radius (capsules, static segments), Poly with radius",
            "collision_slop = carom's linear slop (the docs: as high as possible without "
            "noticeable overlap; the default 0.1 assumes pixel units)",
            "dt = the scene's step (1/60 s, the docs' space.step(1/60)); iterations at the "
            "default 10",
            *joint_notes,
        ]

    def step(self) -> None:
        self.space.step(self.dt)

    def state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        # columns: position (2), angle, velocity (2), angular velocity
        data = _read_bodies(self.space, self._fields, self._buffer, self._ids, 6)
        return data[:, 0:2].copy(), data[:, 3:5].copy(), data[:, 2].copy(), data[:, 5].copy()

    def close(self) -> None:
        pass


def start_rigid(scene: RigidScene) -> PymunkRigidSimulation:
    return PymunkRigidSimulation(scene)


def _local(body: pymunk.Body, point: np.ndarray) -> tuple[float, float]:
    """A world point in ``body``'s frame (the static body's frame is the world's)."""
    local = pymunk.Vec2d(float(point[0]), float(point[1])) - body.position
    turned = local.rotated(-body.angle)
    return float(turned.x), float(turned.y)


def _reduced(*moments: float) -> float:
    """The reduced mass or moment of two bodies (a static one's is infinite)."""
    return 1.0 / sum(1.0 / m for m in moments if math.isfinite(m) and m > 0.0)


def _add_joints(space: pymunk.Space, bodies: list[pymunk.Body], scene: RigidScene) -> list[str]:
    """The scene's joints as pymunk constraints; the notes on how each kind was built.

    * revolute: a ``PivotJoint`` at the pin; limits a ``RotaryLimitJoint`` (pymunk limits
      ``b.angle - a.angle``: carom's, from the start, shifted by the angle between them then),
      a motor a ``SimpleMotor`` (pymunk's rate is ``a.w - b.w``: carom's speed negated) with
      ``max_force`` the motor's torque, a spring a ``DampedRotarySpring``;
    * distance: a ``PinJoint`` (a rod), a ``SlideJoint`` (a rope, a range), a ``DampedSpring``;
    * weld: a ``PivotJoint`` and a ``GearJoint`` of ratio 1 (or, soft, a ``DampedSpring`` and a
      ``DampedRotarySpring``);
    * prismatic and wheel: a ``GrooveJoint`` along the axis (its ends the limits, else 1 km
      each way), a ``GearJoint`` for the prismatic joint's lock on turning, a
      ``DampedSpring`` of rest length 0 for the spring, a ``SimpleMotor`` for a wheel's motor.

    A spring's stiffness ``k = m w^2`` and damping ``c = 2 m zeta w`` (w = 2 pi f) use the two
    bodies' reduced mass (moment); pymunk has no linear motor: a prismatic motor is refused.
    """
    made: list[pymunk.Constraint] = []
    kinds: set[str] = set()
    for spec in scene.joints:
        a = space.static_body if spec.a < 0 else bodies[spec.a]
        b = space.static_body if spec.b < 0 else bodies[spec.b]
        la, lb = _local(a, spec.anchor_a), _local(b, spec.anchor_b)
        ref = b.angle - a.angle
        kinds.add(spec.kind)
        mass = _reduced(a.mass, b.mass)
        moment = _reduced(a.moment, b.moment)

        def springs(hertz: float, ratio: float, inertia: float) -> tuple[float, float]:
            w = 2.0 * math.pi * hertz
            return inertia * w * w, 2.0 * inertia * ratio * w

        parts: list[pymunk.Constraint] = []
        if spec.kind == "revolute":
            parts.append(pymunk.PivotJoint(a, b, la, lb))
            if spec.limits is not None:
                low, high = spec.limits
                parts.append(pymunk.RotaryLimitJoint(a, b, ref + low, ref + high))
            if spec.motor is not None:
                motor = pymunk.SimpleMotor(a, b, -spec.motor[0])
                motor.max_force = spec.motor[1]
                parts.append(motor)
            if spec.spring is not None:
                k, c = springs(*spec.spring, moment)
                parts.append(pymunk.DampedRotarySpring(a, b, ref, k, c))
        elif spec.kind == "distance":
            if spec.spring is not None:
                k, c = springs(*spec.spring, mass)
                parts.append(pymunk.DampedSpring(a, b, la, lb, spec.length, k, c))
            elif spec.limits is not None:
                parts.append(pymunk.SlideJoint(a, b, la, lb, *spec.limits))
            else:
                pin = pymunk.PinJoint(a, b, la, lb)
                pin.distance = spec.length
                parts.append(pin)
        elif spec.kind == "weld":
            if spec.spring is not None:
                k, c = springs(*spec.spring, mass)
                parts.append(pymunk.DampedSpring(a, b, la, lb, 0.0, k, c))
            else:
                parts.append(pymunk.PivotJoint(a, b, la, lb))
            if spec.angular_spring is not None:
                k, c = springs(*spec.angular_spring, moment)
                parts.append(pymunk.DampedRotarySpring(a, b, ref, k, c))
            else:
                parts.append(pymunk.GearJoint(a, b, -ref, 1.0))
        elif spec.kind in ("prismatic", "wheel"):
            assert spec.axis is not None
            low, high = spec.limits if spec.limits is not None else (-1e3, 1e3)
            ends = [spec.anchor_a + t * spec.axis for t in (low, high)]
            parts.append(pymunk.GrooveJoint(a, b, _local(a, ends[0]), _local(a, ends[1]), lb))
            if spec.kind == "prismatic":
                parts.append(pymunk.GearJoint(a, b, -ref, 1.0))
                if spec.motor is not None:
                    raise CaromError(
                        f"scene {scene.name!r} has a prismatic motor; pymunk has no linear "
                        "motor: compare it with Box2D"
                    )
            elif spec.motor is not None:
                motor = pymunk.SimpleMotor(a, b, -spec.motor[0])
                motor.max_force = spec.motor[1]
                parts.append(motor)
            if spec.spring is not None:
                k, c = springs(*spec.spring, mass)
                parts.append(pymunk.DampedSpring(a, b, la, lb, 0.0, k, c))
        else:
            raise CaromError(
                f"scene {scene.name!r} has a {spec.kind} joint; carom compare gives pymunk "
                "revolute, distance, weld, prismatic and wheel joints"
            )
        for part in parts:
            part.collide_bodies = spec.collide
        made += parts
    if made:
        space.add(*made)
    if not kinds:
        return []
    return [
        f"joints ({', '.join(sorted(kinds))}) as pymunk constraints: {len(made)} in all "
        "(PivotJoint, PinJoint, SlideJoint, GrooveJoint, GearJoint, SimpleMotor, Damped"
        "(Rotary)Spring as each needs); joined bodies do not collide unless the joint says"
    ]
