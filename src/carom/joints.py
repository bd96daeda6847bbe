"""Joints: bodies held together, solved in the same soft step as the contacts (issue 43).

A joint is described by one of the classes here, with its anchors as world points now, and
added to a world with :meth:`Joints.add_joint`, which returns its index; the world keeps it in
each body's own frame from then on. Body ``None`` (or -1) is the world itself: a fixed point.

========================  ===================================================================
:class:`Revolute`         B turns about a point of A (a pin, a hinge, a wheel on an axle);
                          limits on the angle, a motor, a spring toward the starting angle
:class:`Prismatic`        B slides along an axis fixed in A and does not turn relative to it;
                          limits on the travel, a motor, a spring
:class:`Distance`         two anchors at a fixed distance (a rod), within a range (a rope:
                          ``min_length=0``), or joined by a spring
:class:`Weld`             B held to A as one body (or by a linear and an angular spring)
:class:`Wheel`            a car's wheel: B's centre on a line of A (a suspension spring along
                          it, limits), B turning freely or by a motor
:class:`Target`           B's anchor pulled toward a world point by a spring of bounded force
                          (the mouse joint: :meth:`Joints.set_joint_target` moves the point)
========================  ===================================================================

The solver is Box2D v3's soft step (:mod:`carom.engines.rigid.joints`): each joint is
solved before the contacts in every pass, its impulses warm-start the next substep, and its
reaction (:meth:`Joints.joint_reactions`) is what it did over the last substep. Joined bodies
do not touch each other unless ``collide=True``. An island with a joint is always the soft
step's; its impacts are taken first, pair by pair (so Newton's cradle on strings sends out one
ball), then the joints and contacts are solved together. The 2D rigid engine.

>>> import carom
>>> from carom.joints import Revolute
>>> from carom.shapes import Circle
>>> world = carom.World(2, [4.0, 4.0], gravity=[0.0, -9.81], boundary="open")
>>> bob = world.add_body(Circle(0.05), [3.0, 2.0])
>>> pin = world.add_joint(Revolute(None, bob, [2.0, 2.0]))  # a 1 m pendulum from (2, 2)
>>> for _ in range(30):
...     world.step()
>>> round(float(np.hypot(*(world.positions[bob] - [2.0, 2.0]))), 2)  # (its string holds)
1.0
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, NamedTuple, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from carom.engines.base import Engine
from carom.engines.rigid import joints as rows2
from carom.engines.rigid3d import joints as rows3
from carom.engines.stepped import joints as shared
from carom.engines.stepped.driver import SteppedEngine
from carom.errors import CaromError
from carom.geometry.rotation import matrix_quaternion, orientation_matrices, rotation_matrices
from carom.laws.kinds import KIND_DYNAMIC
from carom.limits import LARGEST

__all__ = [
    "Distance",
    "Fixed",
    "Joint",
    "Joints",
    "Prismatic",
    "Revolute",
    "Spherical",
    "Target",
    "Weld",
    "Wheel",
    "anchors_now",
    "joint_lines",
]

FloatArray = NDArray[np.float64]
#: how far an anchor may lie from its body's centre, in the body's own reach: farther than
#: this a joint's lever arm is not a body's but a mistake (a point in the wrong units)
ARM_REACH = 1e6


@dataclass(frozen=True)
class Revolute:
    """B turns about one point of A.

    Parameters
    ----------
    a, b : int or None
        The bodies (``None``: the world).
    anchor : (d,) array_like
        The pin, a world point now [m].
    axis : (3,) array_like, optional
        The hinge's axis now, in 3D (required there; 2D joints turn about z).
    limits : (float, float), optional
        The least and the most relative angle [rad] from the angle now (2D: any span, angles
        are counted in whole turns; 3D: within (-pi, pi)).
    motor : (float, float), optional
        The speed B turns at relative to A [rad/s], and the largest torque the motor gives
        [N m].
    spring : (float, float), optional
        A torsion spring toward the angle now: frequency [Hz] and damping ratio [-].
    collide : bool
        Whether a and b may touch.
    """

    a: int | None
    b: int | None
    anchor: ArrayLike
    limits: tuple[float, float] | None = None
    motor: tuple[float, float] | None = None
    spring: tuple[float, float] | None = None
    collide: bool = False
    axis: ArrayLike | None = None


@dataclass(frozen=True)
class Spherical:
    """A ball and socket (3D): B turns freely about one point of A.

    Parameters
    ----------
    a, b : int or None
        The bodies (``None``: the world).
    anchor : (3,) array_like
        The socket, a world point now [m].
    collide : bool
        Whether a and b may touch.
    """

    a: int | None
    b: int | None
    anchor: ArrayLike
    collide: bool = False


@dataclass(frozen=True)
class Prismatic:
    """B slides along an axis fixed in A, without turning relative to A.

    Parameters
    ----------
    a, b : int or None
        The bodies (``None``: the world).
    anchor : (d,) array_like
        A point on the axis, a world point now [m]; the travel is measured from it.
    axis : (d,) array_like
        The axis's direction now (any length but zero).
    limits : (float, float), optional
        The least and the most travel along the axis [m].
    motor : (float, float), optional
        The speed along the axis [m/s] and the largest force [N].
    spring : (float, float), optional
        A spring toward travel 0: frequency [Hz] and damping ratio [-].
    collide : bool
        Whether a and b may touch.
    """

    a: int | None
    b: int | None
    anchor: ArrayLike
    axis: ArrayLike
    limits: tuple[float, float] | None = None
    motor: tuple[float, float] | None = None
    spring: tuple[float, float] | None = None
    collide: bool = False


@dataclass(frozen=True)
class Distance:
    """Two anchors kept at a distance: a rod, a rope or a spring.

    Parameters
    ----------
    a, b : int or None
        The bodies (``None``: the world).
    anchor_a, anchor_b : (d,) array_like
        The anchors on a and on b, world points now [m].
    length : float, optional
        The rod's length, or the spring's rest length [m]; by default the distance now.
    min_length, max_length : float, optional
        A range instead of one length [m]: a rope is ``min_length=0, max_length=L`` (slack
        below L, taut at L). With a spring they default to 0 and no most.
    spring : (float, float), optional
        A spring toward ``length``: frequency [Hz] and damping ratio [-].
    collide : bool
        Whether a and b may touch.
    """

    a: int | None
    b: int | None
    anchor_a: ArrayLike
    anchor_b: ArrayLike
    length: float | None = None
    min_length: float | None = None
    max_length: float | None = None
    spring: tuple[float, float] | None = None
    collide: bool = False


@dataclass(frozen=True)
class Weld:
    """B held to A as if one body.

    Parameters
    ----------
    a, b : int or None
        The bodies (``None``: the world).
    anchor : (d,) array_like
        The weld point, a world point now [m].
    spring : (float, float), optional
        A soft weld's linear spring: frequency [Hz] and damping ratio [-] (default rigid).
    angular_spring : (float, float), optional
        Its angular spring (default rigid).
    collide : bool
        Whether a and b may touch.
    """

    a: int | None
    b: int | None
    anchor: ArrayLike
    spring: tuple[float, float] | None = None
    angular_spring: tuple[float, float] | None = None
    collide: bool = False


@dataclass(frozen=True)
class Wheel:
    """A wheel ``b`` on a body ``a``: b's anchor stays on a line of a, b turns freely.

    Parameters
    ----------
    a, b : int or None
        The chassis and the wheel.
    anchor : (d,) array_like
        The axle, a world point now [m] (the wheel's centre, usually).
    axis : (d,) array_like
        The suspension's direction now (any length but zero).
    spring : (float, float), optional
        The suspension along the axis: frequency [Hz] and damping ratio [-] (default: none,
        the axle slides freely within its limits).
    motor : (float, float), optional
        The wheel's speed relative to a [rad/s] and the largest torque [N m].
    limits : (float, float), optional
        The least and the most travel of the axle along the axis [m].
    collide : bool
        Whether a and b may touch.
    """

    a: int | None
    b: int | None
    anchor: ArrayLike
    axis: ArrayLike
    spring: tuple[float, float] | None = None
    motor: tuple[float, float] | None = None
    limits: tuple[float, float] | None = None
    collide: bool = False


@dataclass(frozen=True)
class Target:
    """Body ``b`` pulled toward a world point by a spring of bounded force (Box2D's mouse
    joint: dragging a body).

    Parameters
    ----------
    b : int
        The body.
    target : (d,) array_like
        The point pulled toward [m] (:meth:`Joints.set_joint_target` moves it).
    anchor : (d,) array_like, optional
        The point of b pulled, a world point now [m]; b's centre by default.
    hertz, damping_ratio : float
        The spring: frequency [Hz] and damping ratio [-].
    max_force : float, optional
        The largest pull [N]; by default 1000 times b's weight (with g = 9.81 m/s^2 in a
        world without gravity).
    """

    b: int
    target: ArrayLike
    anchor: ArrayLike | None = None
    hertz: float = 5.0
    damping_ratio: float = 0.7
    max_force: float | None = None


#: Rapier's and Jolt's name for a weld
Fixed = Weld

Joint = Revolute | Prismatic | Distance | Weld | Wheel | Target | Spherical


class _World(Protocol):
    """What :class:`Joints` takes from the World it is part of."""

    @property
    def dim(self) -> int: ...

    @property
    def n_bodies(self) -> int: ...

    @property
    def alive(self) -> NDArray[np.bool_]: ...

    def build(self) -> Engine: ...


class Joints:
    """Joints of a :class:`carom.World` (the rigid engines, 2D and 3D): add, remove, read,
    drive."""

    def add_joint(self: _World, joint: Joint) -> int:
        """Add ``joint`` (one of this module's classes, its anchors world points now) and
        return its index (indices are never reused).

        Raises
        ------
        CaromError
            A body out of range, removed, or joined to itself; no dynamic body; a value not
            finite or out of range; an anchor farther from its body than a million times
            the body's reach; a zero axis; a joint of the other dimension (a wheel in 3D,
            a spherical joint in 2D); the event-driven engine. Nothing has changed then.
        """
        _refuse_elsewhere(self)
        ints, floats = _row_of(self, _poses(self), joint)
        table_i, table_f = _tables(self)
        # (a built engine takes them now; else when it is built)
        _store(
            self,
            np.concatenate((table_i, ints[None, :])),
            np.concatenate((table_f, floats[None, :])),
        )
        return int(table_i.shape[0])

    def remove_joint(self: _World, index: int) -> None:
        """Take joint ``index`` out; the others keep their indices, and its index is refused
        from then on. Its bodies wake.

        Parameters
        ----------
        index : int
            As :meth:`add_joint` returned it.

        Raises
        ------
        CaromError
            An index out of range or already removed; the event-driven engine.
        """
        _engine(self)
        j = _joint_index(self, index)
        ints, floats = _tables(self)
        ints[j, shared.J_KIND] = shared.REMOVED
        floats[j] = 0.0
        _store(self, ints, floats)

    @property
    def n_joints(self: _World) -> int:
        """Joints added so far, removed ones counted (indices run from 0 to this less 1)."""
        return int(_tables(self)[0].shape[0])

    def joint_reactions(self: _World) -> tuple[FloatArray, FloatArray]:
        """What every joint did on its body B over the last substep of the last step.

        Returns
        -------
        force : (J, d) float64
            The force [N] on B (on A: the opposite).
        torque : (J,) float64 in 2D, (J, 3) in 3D
            The couple [N m] on B beyond the force's moment (motors, limits, springs,
            welds, prismatic joints' and hinges' hold on the orientation). Zeros for a
            removed joint, or one not solved in the last step (its bodies asleep).
        """
        _engine(self)
        _, floats = _tables(self)
        if self.dim == 2:
            return floats[:, [rows2.FX, rows2.FY]].copy(), floats[:, rows2.TORQUE].copy()
        return (
            floats[:, rows3.FORCE : rows3.FORCE + 3].copy(),
            floats[:, rows3.TORQUE : rows3.TORQUE + 3].copy(),
        )

    def joint_anchors(self: _World) -> FloatArray:
        """Every joint's two anchors now (J, 2, d) [m], A's then B's (NaN for a removed
        joint): where to draw it."""
        engine = _engine(self)
        ints, floats = _tables(self)
        rows, d = _rows(self.dim), self.dim
        turn = engine.state.angle if d == 2 else engine.state.q
        return anchors_now(ints, floats[:, rows.LA : rows.LB + d], engine.state.x, turn)

    def set_joint_target(self: _World, index: int, target: ArrayLike) -> None:
        """Move a target joint's point (dragging its body: call it every frame with the
        pointer's position); its body wakes.

        Parameters
        ----------
        index : int
            A target joint's index.
        target : (d,) array_like
            The new point [m].

        Raises
        ------
        CaromError
            Not a target joint, removed, out of range; a point not finite or of another
            dimension. Nothing has changed then.
        """
        _engine(self)
        j = _joint_index(self, index)
        ints, floats = _tables(self)
        if ints[j, shared.J_KIND] != shared.TARGET:
            raise CaromError(f"joint {j} is a {_kind_name(ints, j)} joint, not a target joint")
        rows = _rows(self.dim)
        floats[j, rows.LA : rows.LA + self.dim] = _point(self, "target", target)
        _store(self, ints, floats)

    def set_joint_motor(self: _World, index: int, speed: float, most: float) -> None:
        """Drive a joint's motor (a revolute, prismatic or wheel joint); its bodies wake.

        Parameters
        ----------
        index : int
            The joint's index.
        speed : float
            The relative speed the motor drives: [rad/s] for a revolute or wheel joint,
            [m/s] for a prismatic one.
        most : float
            Its largest torque [N m] or force [N], >= 0; 0 turns it off.

        Raises
        ------
        CaromError
            A joint without a motor, removed, out of range; a value not finite or negative.
            Nothing has changed then.
        """
        _engine(self)
        j = _joint_index(self, index)
        ints, floats = _tables(self)
        kind = int(ints[j, shared.J_KIND])
        if kind not in (shared.REVOLUTE, shared.PRISMATIC, shared.WHEEL):
            raise CaromError(f"joint {j} is a {_kind_name(ints, j)} joint: it has no motor")
        speed_value = _finite("motor speed", speed)
        most_value = _at_least_zero("motor's largest force or torque", most)
        rows = _rows(self.dim)
        floats[j, rows.MOTOR_SPEED] = speed_value
        floats[j, rows.MAX_MOTOR] = most_value
        ints[j, shared.J_FLAGS] |= shared.FLAG_MOTOR
        _store(self, ints, floats)

    @property
    def joint_rows(self: _World) -> tuple[NDArray[np.int64], FloatArray]:
        """Every joint as the engine keeps it: integer rows (J, 4) (kind, bodies, flags) and
        float rows (J, F) (:mod:`carom.engines.rigid.joints`; their impulses too), for a
        checkpoint. Copies."""
        ints, floats = _tables(self)
        return ints.copy(), floats.copy()

    def share_joints(self: _World, engine: SteppedEngine) -> None:
        """Hand a newly built rigid ``engine`` the world's joints, their arrays shared (its
        solver writes their impulses and reactions into them, which checkpoints keep); their
        bodies are not woken: the engine starts as the world stands."""
        ints, floats = _tables(self)
        if len(ints):
            engine.use_joints(ints, floats, wake=False)

    def restore_joints(self: _World, ints: ArrayLike, floats: ArrayLike) -> None:
        """Take every joint from rows as :attr:`joint_rows` gave them (a checkpoint's); the
        engine, if built, takes them too."""
        _store(self, np.array(ints, dtype=np.int64), np.array(floats, dtype=np.float64), False)


def anchors_now(
    ints: NDArray[np.int64], local: FloatArray, x: FloatArray, turn: FloatArray
) -> FloatArray:
    """The joints' anchors in the world (J, 2, d) [m], A's then B's (NaN for a removed
    joint), from their rows ``ints`` (J, 4) and local anchors ``local`` (J, 2 d) (A's, then
    B's, in each body's frame; a world point for body -1) and the bodies' centres of mass
    ``x`` (N, d) [m] and orientations ``turn``: angles (N,) [rad] in 2D, unit quaternions
    (N, 4) in 3D."""
    d = x.shape[1]
    out = np.full((ints.shape[0], 2, d), np.nan)
    live = ints[:, shared.J_KIND] != shared.REMOVED
    rotations = orientation_matrices(turn, d)
    for side, col in enumerate((shared.J_A, shared.J_B)):
        body = ints[:, col]
        world = body < 0
        at = np.maximum(body, 0)
        r = (
            np.where(world[:, None, None], np.eye(d), rotations[at])
            if len(at)
            else np.zeros((0, d, d))
        )
        centre = np.where(world[:, None], 0.0, x[at])
        point = centre + np.einsum("jab,jb->ja", r, local[:, side * d : (side + 1) * d])
        out[live, side] = point[live]
    return out


def joint_lines(
    ints: NDArray[np.int64], local: FloatArray, x: FloatArray, turn: FloatArray
) -> FloatArray:
    """How to draw the joints (as Box2D's debug draw does): for each live joint a line from
    A's centre to its anchor, on to B's anchor and to B's centre (K, 4, d) [m] (the world's
    end starts or ends at its anchor). Arguments as :func:`anchors_now`."""
    anchors = anchors_now(ints, local, x, turn)
    live = ints[:, shared.J_KIND] != shared.REMOVED
    lines = np.empty((int(np.count_nonzero(live)), 4, x.shape[1]))
    a, b = ints[live, shared.J_A], ints[live, shared.J_B]
    lines[:, 1:3] = anchors[live]
    lines[:, 0] = np.where((a < 0)[:, None], anchors[live, 0], x[np.maximum(a, 0)])
    lines[:, 3] = np.where((b < 0)[:, None], anchors[live, 1], x[np.maximum(b, 0)])
    return lines


def _engine(world: _World) -> SteppedEngine:
    """The world's rigid 2D engine, built; else a CaromError."""
    _refuse_elsewhere(world)
    engine = world.build()
    if not isinstance(engine, SteppedEngine):
        raise CaromError(_NOT_RIGID)
    return engine


_NOT_RIGID = (
    "joints are solved by the rigid engine; this world runs the event-driven engine (add a "
    "body that is not a sphere, or choose engine='rigid')"
)


def _refuse_elsewhere(world: Any) -> None:
    """A CaromError unless ``world`` runs a rigid engine (built or not)."""
    engine = world.engine
    if engine is not None and not isinstance(engine, SteppedEngine):
        raise CaromError(_NOT_RIGID)
    if engine is None and not world.engine_entry.stepped:
        raise CaromError(_NOT_RIGID)


class _Poses(NamedTuple):
    """What a new joint reads of its bodies now: centres of mass (n, d) [m], orientations
    (angles (n,) [rad] in 2D, quaternions (n, 4) in 3D), kinds (n,), masses (n,) [kg],
    reaches (n,) [m] (from the centre to the farthest point), gravity (d,) [m/s^2]."""

    x: FloatArray
    turn: FloatArray
    kind: NDArray[np.int64]
    mass: FloatArray
    reach: FloatArray
    gravity: FloatArray


def _poses(world: Any) -> _Poses:
    """The bodies now, from the engine if built, else from the world's table (which keeps
    each body's centre of mass as its position)."""
    engine = world.engine
    if isinstance(engine, SteppedEngine):
        m, st = engine.model, engine.state
        turn = st.angle if world.dim == 2 else st.q
        return _Poses(st.x, turn, m.kind, m.mass, m.reach, m.gravity)
    bodies = world.bodies
    reach = np.array([max((p.reach for p in pieces), default=0.0) for pieces in bodies.pieces])
    turn = np.asarray(world.orientations, np.float64)
    if world.dim == 2:
        turn = turn.reshape(-1)
    return _Poses(
        np.asarray(world.positions), turn, np.asarray(bodies.kind), np.asarray(bodies.mass),
        reach, np.asarray(world.gravity, np.float64),
    )  # fmt: skip


def _rotation(poses: _Poses, body: int, dim: int) -> FloatArray:
    """Body ``body``'s rotation matrix now (d, d) (the world's: the identity)."""
    if body < 0:
        return np.eye(dim)
    if dim == 2:
        c, s = math.cos(float(poses.turn[body])), math.sin(float(poses.turn[body]))
        return np.array([[c, -s], [s, c]])
    turned: FloatArray = rotation_matrices(poses.turn[body][None, :])[0]
    return turned


def _store(world: Any, ints: NDArray[np.int64], floats: FloatArray, wake: bool = True) -> None:
    """Keep ``ints``, ``floats`` as the world's joint rows; a built engine takes them (its
    joints' bodies woken if ``wake``)."""
    world._joint_ints = ints
    world._joint_floats = floats
    engine = world.engine
    if isinstance(engine, SteppedEngine):
        engine.use_joints(ints, floats, wake)


def _tables(world: Any) -> tuple[NDArray[np.int64], FloatArray]:
    """The world's joint rows (its own arrays, which the engine shares)."""
    ints = getattr(world, "_joint_ints", None)
    if ints is None:
        world._joint_ints = np.zeros((0, shared.JOINT_INTS), np.int64)
        world._joint_floats = np.zeros((0, _rows(world.dim).JOINT_FLOATS))
    return world._joint_ints, world._joint_floats


def _kind_name(ints: NDArray[np.int64], j: int) -> str:
    kind = int(ints[j, shared.J_KIND])
    return "removed" if kind == shared.REMOVED else shared.KIND_NAMES[kind]


def _joint_index(world: Any, index: object) -> int:
    """``index`` as a live joint's index, or a CaromError naming it."""
    ints = _tables(world)[0]
    if isinstance(index, bool) or not isinstance(index, int | np.integer):
        raise CaromError(f"a joint index is a whole number; got {index!r}")
    if not 0 <= int(index) < ints.shape[0]:
        raise CaromError(
            f"joint {index} is not in the world: it has {ints.shape[0]} joint(s) "
            "(World.add_joint returns each one's index)"
        )
    if ints[int(index), shared.J_KIND] == shared.REMOVED:
        raise CaromError(f"joint {index} was removed (World.remove_joint)")
    return int(index)


def _finite(name: str, value: object) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float | np.integer | np.floating):
        raise CaromError(f"{name} must be a number; got {value!r}")
    x = float(value)
    if not math.isfinite(x) or abs(x) > LARGEST:
        raise CaromError(f"{name} must be finite and at most {LARGEST:g} in size; got {x!r}")
    return x


def _at_least_zero(name: str, value: object) -> float:
    x = _finite(name, value)
    if x < 0.0:
        raise CaromError(f"{name} must be >= 0; got {x!r}")
    return x


def _pair(name: str, value: object, low_name: str, high_name: str) -> tuple[float, float]:
    """``value`` as two finite numbers (low, high) with low <= high."""
    if not isinstance(value, tuple | list | np.ndarray) or len(value) != 2:
        raise CaromError(f"{name} must be two numbers ({low_name}, {high_name}); got {value!r}")
    low = _finite(f"{name}'s {low_name}", value[0])
    high = _finite(f"{name}'s {high_name}", value[1])
    return low, high


def _point(world: _World, name: str, value: ArrayLike) -> FloatArray:
    """``value`` as a finite world point (d,), or a CaromError naming ``name``."""
    try:
        p = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError):
        raise CaromError(f"{name} must be {world.dim} numbers; got {value!r}") from None
    if p.shape != (world.dim,):
        raise CaromError(f"{name} must be {world.dim} numbers [m]; got shape {p.shape}")
    if not np.all(np.isfinite(p)) or np.any(np.abs(p) > LARGEST):
        raise CaromError(f"{name} must be finite and within {LARGEST:g} m; got {p.tolist()}")
    return p


def _axis(world: _World, value: ArrayLike) -> FloatArray:
    u = _point(world, "axis", value)
    size = float(np.linalg.norm(u))
    if size == 0.0:
        raise CaromError("axis must not be zero: give the direction of the joint's axis")
    return u / size


def _body(world: _World, name: str, value: object) -> int:
    """``value`` as a body index (-1: the world), or a CaromError naming ``name``."""
    if value is None:
        return -1
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise CaromError(f"{name} must be a body index or None (the world); got {value!r}")
    i = int(value)
    if i == -1:
        return -1
    if not 0 <= i < world.n_bodies:
        raise CaromError(
            f"{name} = {i} is not in the world: its indices run from 0 to {world.n_bodies - 1}"
        )
    if not world.alive[i]:
        raise CaromError(f"{name} = {i} was removed (World.remove_body)")
    return i


def _rows(dim: int) -> Any:
    """The dimension's joint rows' module (its column names)."""
    return rows2 if dim == 2 else rows3


def _local(poses: _Poses, body: int, name: str, point: FloatArray) -> FloatArray:
    """World ``point`` in ``body``'s frame (from its centre of mass), refused when farther
    from the body than :data:`ARM_REACH` times its reach."""
    if body < 0:
        return point
    r = point - poses.x[body]
    reach = max(float(poses.reach[body]), 1e-300)
    far = float(np.linalg.norm(r))
    if far > ARM_REACH * reach:
        raise CaromError(
            f"{name} {point.tolist()} is {far:.3g} m from body {body}'s centre, more than "
            f"{ARM_REACH:g} times its reach ({reach:.3g} m): give a point on or near the body, "
            "in metres"
        )
    local: FloatArray = _rotation(poses, body, point.shape[0]).T @ r
    return local


def _spring_of(name: str, value: object) -> tuple[float, float]:
    hertz, ratio = _pair(name, value, "frequency [Hz]", "damping ratio")
    if hertz < 0.0 or ratio < 0.0:
        raise CaromError(f"{name}'s frequency and damping ratio must be >= 0; got {value!r}")
    return hertz, ratio


def _row_of(world: _World, poses: _Poses, joint: object) -> tuple[
    NDArray[np.int64], FloatArray
]:  # fmt: skip
    """The rows of ``joint``, every value checked; nothing is changed."""
    dim = world.dim
    rows = _rows(dim)
    ints = np.zeros(shared.JOINT_INTS, np.int64)
    f = np.zeros(rows.JOINT_FLOATS)
    flags = 0
    kinds = {
        Revolute: shared.REVOLUTE,
        Prismatic: shared.PRISMATIC,
        Distance: shared.DISTANCE,
        Weld: shared.WELD,
        Wheel: shared.WHEEL,
        Spherical: shared.SPHERICAL,
    }
    if isinstance(joint, Target):
        a, b = -1, _body(world, "b", joint.b)
        if b < 0:
            raise CaromError("a target joint pulls a body: give its index as b")
        kind = shared.TARGET
    elif type(joint) in kinds:
        assert isinstance(joint, Revolute | Prismatic | Distance | Weld | Wheel | Spherical)
        a = _body(world, "a", joint.a)
        b = _body(world, "b", joint.b)
        if a == b:
            raise CaromError(
                f"a joint joins two different bodies; a and b are both "
                f"{'the world' if a < 0 else f'body {a}'}"
            )
        kind = kinds[type(joint)]
        if joint.collide:
            flags |= shared.FLAG_COLLIDE
    else:
        raise CaromError(
            f"add_joint takes a joint of carom.joints (Revolute, Prismatic, Distance, Weld, "
            f"Wheel, Spherical, Target); got {joint!r}"
        )
    if kind == shared.WHEEL and dim == 3:
        raise CaromError("a wheel joint is 2D; in 3D join a wheel with a Revolute about its axle")
    if kind == shared.SPHERICAL and dim == 2:
        raise CaromError("a spherical joint is 3D; in 2D a Revolute pins two bodies at a point")
    if not any(i >= 0 and poses.kind[i] == KIND_DYNAMIC for i in (a, b)):
        raise CaromError("a joint needs a dynamic body to move: neither of its bodies is dynamic")
    ra, rb = _rotation(poses, a, dim), _rotation(poses, b, dim)
    la, lb = slice(rows.LA, rows.LA + dim), slice(rows.LB, rows.LB + dim)
    if dim == 2:
        turn = poses.turn
        f[rows2.REF] = (float(turn[b]) if b >= 0 else 0.0) - (float(turn[a]) if a >= 0 else 0.0)
    else:  # B's orientation in A's frame (w, x, y, z)
        f[rows3.QREF : rows3.QREF + 4] = matrix_quaternion(ra.T @ rb)
    if isinstance(joint, Target):
        target = _point(world, "target", joint.target)
        anchor = poses.x[b] if joint.anchor is None else _point(world, "anchor", joint.anchor)
        f[la] = target
        f[lb] = _local(poses, b, "anchor", anchor)
        hertz = _finite("hertz", joint.hertz)
        ratio = _at_least_zero("damping_ratio", joint.damping_ratio)
        if hertz <= 0.0:
            raise CaromError(f"a target joint's hertz must be > 0 [Hz]; got {hertz!r}")
        if joint.max_force is None:
            g = float(np.linalg.norm(poses.gravity)) or 9.81
            most = 1000.0 * float(poses.mass[b]) * g
        else:
            most = _finite("max_force", joint.max_force)
            if most <= 0.0:
                raise CaromError(f"max_force must be > 0 [N]; got {most!r}")
        f[rows.HERTZ], f[rows.DAMPING], f[rows.MAX_FORCE] = hertz, ratio, most
    elif isinstance(joint, Distance):
        pa = _point(world, "anchor_a", joint.anchor_a)
        pb = _point(world, "anchor_b", joint.anchor_b)
        f[la] = _local(poses, a, "anchor_a", pa)
        f[lb] = _local(poses, b, "anchor_b", pb)
        now = float(np.linalg.norm(pb - pa))
        length = now if joint.length is None else _at_least_zero("length", joint.length)
        spring = None if joint.spring is None else _spring_of("spring", joint.spring)
        if spring is not None and spring[0] > 0.0:
            flags |= shared.FLAG_SPRING
            f[rows.HERTZ], f[rows.DAMPING] = spring
            low, high = 0.0, math.inf
        else:
            low = high = length
        if joint.min_length is not None:
            low = _at_least_zero("min_length", joint.min_length)
        if joint.max_length is not None:
            high = _at_least_zero("max_length", joint.max_length)
        if low > high:
            raise CaromError(f"min_length ({low:g} m) is more than max_length ({high:g} m)")
        if joint.min_length is not None or joint.max_length is not None:
            length = min(max(length, low), high)
        f[rows.LENGTH], f[rows.LOWER], f[rows.UPPER] = length, low, high
    else:
        anchor = _point(world, "anchor", joint.anchor)
        f[la] = _local(poses, a, "anchor", anchor)
        f[lb] = _local(poses, b, "anchor", anchor)
        axis = getattr(joint, "axis", None)
        if isinstance(joint, Revolute) and dim == 2 and axis is not None:
            raise CaromError("a 2D revolute joint turns about z: leave its axis out")
        if isinstance(joint, Revolute) and dim == 3 and axis is None:
            raise CaromError("a 3D revolute joint needs its axis: Revolute(a, b, anchor, axis=...)")
        if axis is not None:
            u = _axis(world, axis)
            f[rows.AXA : rows.AXA + dim] = ra.T @ u
            if dim == 3:  # the hinge's axis in B, and a direction square to it in each body
                f[rows3.AXB : rows3.AXB + 3] = rb.T @ u
                square = np.cross(u, [1.0, 0.0, 0.0] if abs(u[0]) < 0.57735 else [0.0, 1.0, 0.0])
                square /= np.linalg.norm(square)
                f[rows3.PA : rows3.PA + 3] = ra.T @ square
                f[rows3.PB : rows3.PB + 3] = rb.T @ square
        if isinstance(joint, Weld):
            for name, value, cols in (
                ("spring", joint.spring, (rows.HERTZ, rows.DAMPING)),
                ("angular_spring", joint.angular_spring, (rows.ANG_HERTZ, rows.ANG_DAMPING)),
            ):
                if value is not None:
                    f[cols[0]], f[cols[1]] = _spring_of(name, value)
        elif not isinstance(joint, Spherical):
            if joint.limits is not None:
                f[rows.LOWER], f[rows.UPPER] = _pair("limits", joint.limits, "least", "most")
                if f[rows.LOWER] > f[rows.UPPER]:
                    raise CaromError(
                        f"limits must be (least, most) with least <= most; got {joint.limits!r}"
                    )
                if (
                    dim == 3
                    and isinstance(joint, Revolute)
                    and (f[rows.LOWER] <= -math.pi or f[rows.UPPER] >= math.pi)
                ):
                    raise CaromError(
                        "a 3D revolute joint's limits lie within a turn, (-pi, pi) [rad]; got "
                        f"{joint.limits!r}"
                    )
                flags |= shared.FLAG_LIMIT
            if joint.motor is not None:
                speed, most = _pair("motor", joint.motor, "speed", "largest force or torque")
                if most < 0.0:
                    raise CaromError(
                        f"the motor's largest force or torque must be >= 0; got {most!r}"
                    )
                f[rows.MOTOR_SPEED], f[rows.MAX_MOTOR] = speed, most
                flags |= shared.FLAG_MOTOR
            if joint.spring is not None:
                f[rows.HERTZ], f[rows.DAMPING] = _spring_of("spring", joint.spring)
                if f[rows.HERTZ] > 0.0:
                    flags |= shared.FLAG_SPRING
    ints[shared.J_KIND], ints[shared.J_A], ints[shared.J_B] = kind, a, b
    ints[shared.J_FLAGS] = flags
    return ints, f
