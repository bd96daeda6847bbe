"""Joints in ``carom compare``: the scene's joints as plain data for the peers, and what is
measured of them (issue 43).

:func:`joint_specs` reads a world's joint rows (:attr:`carom.World.joint_rows`) as
:class:`JointSpec` records in world terms at the start (anchors, axis, length, limits, motor,
springs), which each peer turns into its own joints. :class:`JointGauge` measures every
engine alike from the poses it reports:

* **joint gap**: the largest distance by which a joint's two anchors break its constraint
  over the run [m], with carom's own local anchors on each engine's poses (a pin's two
  anchors apart; a rod's length off; a rope longer than its most; a slider's anchor off its
  axis);
* **a lone pendulum's period** against the finite-amplitude closed form
  ``T = 4 sqrt(L/g) K(sin(theta0 / 2))`` (``L = I_p / (m d)`` for a body pinned by a revolute
  joint, the rod's length for a body hung at its centre on a rigid distance joint), released
  from rest; the period is read from the times its angle crosses zero (interpolated between
  samples: (omega h)^2 h / 12 of error, below 1e-5 relative at 60 Hz);
* **Newton's cradle on strings** (equal balls hung on rigid distance joints in a touching row,
  the first let go from the side, e = 1): the closed form sends the last ball out at the
  first one's speed at the strike, ``sqrt(2 g L (1 - cos theta0))``, and leaves the others at
  rest. Measured over the last ball's swing out, after the strike (once the blow has passed
  along the row): each ball's speed from its energy, ``sqrt(v^2 + 2 g L (1 - cos phi))`` at
  its string's angle ``phi`` from the vertical, which its free swing keeps whatever the
  sample's time (and however much a soft string stretches): the last ball's at the top of
  its swing (where it is all height, and an integrator's energy error, ``h omega^2 x v``,
  vanishes with v), and the largest of the others', over the strike speed.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom.engines.rigid import joints as rows2
from carom.engines.rigid3d import joints as rows3
from carom.engines.stepped import joints as shared
from carom.geometry.rotation import orientation_matrices
from carom.joints import anchors_now
from carom.laws.kinds import KIND_DYNAMIC

__all__ = ["JointGauge", "JointSpec", "elliptic_k", "joint_specs", "pendulum_period"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class JointSpec:
    """One joint of a scene as the peers build it: what it is, in world terms at the start.

    Attributes
    ----------
    kind : str
        ``"revolute"``, ``"prismatic"``, ``"distance"``, ``"weld"``, ``"wheel"``,
        ``"spherical"`` or ``"target"``.
    a, b : int
        The bodies (-1: the world).
    anchor_a, anchor_b : (d,) float64
        The anchors on a and on b, world points at the start [m] (one point for a pin).
    axis : (d,) float64 or None
        The unit axis in the world at the start (a slider's, a wheel's suspension, a 3D
        hinge's).
    length : float
        A distance joint's length (a spring's rest length) [m].
    limits : (float, float) or None
        Limits on the angle from the start [rad] (revolute) or the travel [m] (prismatic,
        wheel); a distance joint's least and most length when they differ (a rope).
    motor : (float, float) or None
        The motor's speed [rad/s] or [m/s] and its largest torque [N m] or force [N].
    spring : (float, float) or None
        The joint's spring (a weld's linear one): frequency [Hz] and damping ratio [-].
    angular_spring : (float, float) or None
        A weld's angular spring.
    collide : bool
        Whether a and b may touch.
    """

    kind: str
    a: int
    b: int
    anchor_a: FloatArray
    anchor_b: FloatArray
    axis: FloatArray | None
    length: float
    limits: tuple[float, float] | None
    motor: tuple[float, float] | None
    spring: tuple[float, float] | None
    angular_spring: tuple[float, float] | None
    collide: bool

    @property
    def rigid_rod(self) -> bool:
        """A distance joint that holds one length (no spring, no range)."""
        return self.kind == "distance" and self.spring is None and self.limits is None


def _rows(dim: int) -> Any:
    return rows2 if dim == 2 else rows3


def joint_specs(
    ints: IntArray, floats: FloatArray, x: FloatArray, turn: FloatArray
) -> tuple[JointSpec, ...]:
    """The live joints of rows ``ints`` (J, 4) and ``floats`` (J, F) (a world's
    :attr:`~carom.World.joint_rows`) as :class:`JointSpec` records, for bodies at centres of
    mass ``x`` (N, d) [m] turned by ``turn`` (angles (N,) [rad] in 2D, quaternions (N, 4)
    in 3D)."""
    dim = x.shape[1]
    rows = _rows(dim)
    if ints.shape[0] == 0:
        return ()
    anchors = anchors_now(ints, floats[:, : 2 * dim], x, turn)
    rotations = orientation_matrices(turn, dim)
    specs = []
    for j in range(ints.shape[0]):
        kind = int(ints[j, shared.J_KIND])
        if kind == shared.REMOVED:
            continue
        a, b, flags = (int(ints[j, c]) for c in (shared.J_A, shared.J_B, shared.J_FLAGS))
        f = floats[j]
        name = shared.KIND_NAMES[kind]
        axis = None
        if name in ("prismatic", "wheel") or (name == "revolute" and dim == 3):
            local = f[rows.AXA : rows.AXA + dim]
            axis = local if a < 0 else rotations[a] @ local
        limits = None
        if flags & shared.FLAG_LIMIT:
            limits = (float(f[rows.LOWER]), float(f[rows.UPPER]))
        spring = None
        if flags & shared.FLAG_SPRING or (name == "weld" and f[rows.HERTZ] > 0.0):
            spring = (float(f[rows.HERTZ]), float(f[rows.DAMPING]))
        if name == "distance" and not flags & shared.FLAG_SPRING and f[rows.LOWER] < f[rows.UPPER]:
            limits = (float(f[rows.LOWER]), float(f[rows.UPPER]))
        angular = None
        if name == "weld" and f[rows.ANG_HERTZ] > 0.0:
            angular = (float(f[rows.ANG_HERTZ]), float(f[rows.ANG_DAMPING]))
        motor = None
        if flags & shared.FLAG_MOTOR:
            motor = (float(f[rows.MOTOR_SPEED]), float(f[rows.MAX_MOTOR]))
        specs.append(
            JointSpec(
                kind=name,
                a=a,
                b=b,
                anchor_a=anchors[j, 0].copy(),
                anchor_b=anchors[j, 1].copy(),
                axis=None if axis is None else np.asarray(axis, np.float64).copy(),
                length=float(f[rows.LENGTH]),
                limits=limits,
                motor=motor,
                spring=spring,
                angular_spring=angular,
                collide=bool(flags & shared.FLAG_COLLIDE),
            )
        )
    return tuple(specs)


def elliptic_k(k: float) -> float:
    """The complete elliptic integral of the first kind K(k), modulus ``k`` in [0, 1), by
    the arithmetic-geometric mean: ``K = pi / (2 AGM(1, sqrt(1 - k^2)))`` (Abramowitz and
    Stegun 17.6), to round-off."""
    if not 0.0 <= k < 1.0:
        raise ValueError(f"the modulus k lies in [0, 1); got {k!r}")
    a, g = 1.0, math.sqrt(1.0 - k * k)
    for _ in range(64):  # quadratic convergence: a handful of rounds reach round-off
        if a - g <= 4.0 * math.ulp(a):
            break
        a, g = 0.5 * (a + g), math.sqrt(a * g)
    return math.pi / (a + g)


def pendulum_period(length: float, g: float, amplitude: float) -> float:
    """A simple pendulum's period at a finite ``amplitude`` [rad]:
    ``4 sqrt(L/g) K(sin(theta0 / 2))`` [s] (``length`` L [m], ``g`` [m/s^2])."""
    return 4.0 * math.sqrt(length / g) * elliptic_k(math.sin(0.5 * amplitude))


@dataclass(frozen=True)
class _Pendulum:
    """A lone pendulum: body ``body`` swinging about ``pivot`` (d,), its angle measured from
    gravity's direction ``down`` (d,) toward ``side`` (d,); the closed-form ``period`` [s]."""

    body: int
    pivot: FloatArray
    down: FloatArray
    side: FloatArray
    period: float
    amplitude: float


@dataclass(frozen=True)
class _Cradle:
    """Newton's cradle on strings: ``balls`` in the row's order (the first one let go), their
    strings' fixed ends ``pivots`` (k, d) [m] and ``lengths`` (k,) [m], gravity's direction
    ``down`` (d,) and size ``g`` [m/s^2], ``strike`` [s] and ``speed`` [m/s] of the first
    impact, the window ``since`` to ``until`` [s] the balls are watched in."""

    balls: IntArray
    pivots: FloatArray
    lengths: FloatArray
    down: FloatArray
    g: float
    strike: float
    speed: float
    since: float
    until: float

    def speeds(self, x: FloatArray, v: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Each ball's speed from its energy, ``sqrt(v^2 + 2 g L (1 - cos phi))`` [m/s] (k,),
        and its string's ``1 - cos phi`` (k,)."""
        r = x[self.balls] - self.pivots
        tilt = 1.0 - (r @ self.down) / np.linalg.norm(r, axis=1)
        square = np.sum(v[self.balls] ** 2, axis=1) + 2.0 * self.g * self.lengths * tilt
        return np.sqrt(np.maximum(square, 0.0)), tilt


class JointGauge:
    """What is measured of a scene's joints (module docstring): the joint gap, lone
    pendulums' periods, a cradle's one ball out.

    Parameters
    ----------
    scene : RigidSceneBase
        The scene (its ``joint_ints``, ``joint_floats``, bodies and start).
    """

    def __init__(self, scene: Any) -> None:
        ints, floats = scene.joint_ints, scene.joint_floats
        live = ints[:, shared.J_KIND] != shared.REMOVED
        self._ints = np.ascontiguousarray(ints[live])
        self._floats = np.ascontiguousarray(floats[live])
        self._dim = int(scene.dim)
        rows = _rows(self._dim)
        kind = self._ints[:, shared.J_KIND]
        flags = self._ints[:, shared.J_FLAGS]
        self._point = np.isin(kind, (shared.REVOLUTE, shared.WELD, shared.SPHERICAL))
        distance = kind == shared.DISTANCE
        sprung = flags & shared.FLAG_SPRING != 0
        self._rod = distance & ~sprung
        self._low = self._floats[:, rows.LOWER]
        self._high = self._floats[:, rows.UPPER]
        self._slider = np.isin(kind, (shared.PRISMATIC, shared.WHEEL))
        self._axis = self._floats[:, rows.AXA : rows.AXA + self._dim]
        self.max_gap = 0.0
        self.pendulums = _pendulums(scene, self._ints, self._floats)
        self._angles: dict[int, list[tuple[float, float]]] = {p.body: [] for p in self.pendulums}
        self.cradle = _cradle(scene, self._ints, self._floats, self.pendulums)
        self._peaks: FloatArray | None = None
        self._highest = (-math.inf, 0.0)  # the last ball's highest 1 - cos phi, its speed then

    def gaps(self, x: FloatArray, turn: FloatArray) -> FloatArray:
        """How far each joint breaks its constraint [m] (J,) for poses ``x``, ``turn``."""
        anchors = anchors_now(self._ints, self._floats[:, : 2 * self._dim], x, turn)
        apart = anchors[:, 1] - anchors[:, 0]
        length = np.linalg.norm(apart, axis=1)
        gap = np.zeros(length.shape[0])
        gap[self._point] = length[self._point]
        rod = self._rod
        gap[rod] = np.maximum(
            np.maximum(length[rod] - self._high[rod], 0.0), self._low[rod] - length[rod]
        )
        if np.any(self._slider):
            a = self._ints[self._slider, shared.J_A]
            axis = self._axis[self._slider]
            turned = orientation_matrices(turn, self._dim)[np.maximum(a, 0)]
            axis = np.where((a < 0)[:, None], axis, np.einsum("jab,jb->ja", turned, axis))
            along = np.sum(apart[self._slider] * axis, axis=1)
            gap[self._slider] = np.linalg.norm(apart[self._slider] - along[:, None] * axis, axis=1)
        return gap

    def observe(self, time: float, x: FloatArray, v: FloatArray, turn: FloatArray) -> None:
        """Take the poses and velocities of the bodies after a step at ``time`` [s]."""
        if self._ints.shape[0]:
            self.max_gap = max(self.max_gap, float(self.gaps(x, turn).max()))
        for p in self.pendulums:
            r = x[p.body] - p.pivot
            self._angles[p.body].append((time, math.atan2(float(r @ p.side), float(r @ p.down))))
        cradle = self.cradle
        if cradle is not None and cradle.since < time <= cradle.until:
            speeds, tilt = cradle.speeds(x, v)
            self._peaks = speeds if self._peaks is None else np.maximum(self._peaks, speeds)
            if tilt[-1] > self._highest[0]:
                self._highest = (float(tilt[-1]), float(speeds[-1]))

    def result(self) -> dict[str, Any]:
        """The measurements, as JSON-ready numbers: ``joint_gap_m``, ``pendulums`` (per body:
        the measured and the closed-form period [s] and the relative error), ``cradle`` (the
        last ball's and the largest other peak speed over the strike speed)."""
        pendulums = []
        for p in self.pendulums:
            measured = _period(self._angles[p.body])
            pendulums.append(
                {
                    "body": p.body,
                    "amplitude_rad": p.amplitude,
                    "period_s": p.period,
                    "measured_s": measured,
                    "error": None if measured is None else abs(measured - p.period) / p.period,
                }
            )
        cradle = None
        if self.cradle is not None:
            peaks = self._peaks if self._peaks is not None else np.zeros(len(self.cradle.balls))
            cradle = {
                "strike_s": self.cradle.strike,
                "strike_speed_m_s": self.cradle.speed,
                "out": self._highest[1] / self.cradle.speed,
                "others": float(peaks[:-1].max()) / self.cradle.speed,
            }
        return {
            "joint_gap_m": self.max_gap if self._ints.shape[0] else None,
            "pendulums": pendulums,
            "cradle": cradle,
        }

    @property
    def source(self) -> str | None:
        """The closed forms the joints are held to, in words (None: none)."""
        said = []
        for p in self.pendulums:
            said.append(
                f"body {p.body} a lone pendulum from {math.degrees(p.amplitude):.4g} degrees: "
                f"period 4 sqrt(L/g) K(sin(theta0/2)) = {p.period:.6g} s"
            )
        if self.cradle is not None:
            said.append(
                f"Newton's cradle: the first ball strikes at {self.cradle.speed:.4g} m/s at "
                f"t = {self.cradle.strike:.4g} s; the last ball goes out at that speed, the "
                "others stay at rest"
            )
        return "; ".join(said) or None

    def error(self) -> float | None:
        """The largest departure from the closed forms: a pendulum's period's relative error,
        the cradle's ``|1 - out|`` and ``others`` (None: no closed form)."""
        measured = self.result()
        errors = [p["error"] for p in measured["pendulums"]]
        if measured["cradle"] is not None:
            c = measured["cradle"]
            errors += [abs(1.0 - c["out"]), c["others"]]
        if not errors:
            return None
        return math.inf if None in errors else max(errors)


def _period(series: list[tuple[float, float]]) -> float | None:
    """The period [s] of an angle's swing, from the times (interpolated) it crosses zero: two
    crossings apart per period; None with fewer than three crossings."""
    crossings = []
    for (t0, a0), (t1, a1) in itertools.pairwise(series):
        if (a0 < 0.0 <= a1) or (a0 > 0.0 >= a1):
            crossings.append(t0 + (t1 - t0) * a0 / (a0 - a1))
    if len(crossings) < 3:
        return None
    return 2.0 * (crossings[-1] - crossings[0]) / (len(crossings) - 1)


def _lone_joints(ints: IntArray) -> dict[int, int]:
    """Body -> its one joint, for bodies with exactly one joint, to the world."""
    count: dict[int, int] = {}
    for j in range(ints.shape[0]):
        for body in (int(ints[j, shared.J_A]), int(ints[j, shared.J_B])):
            count[body] = count.get(body, 0) + 1
    lone = {}
    for j in range(ints.shape[0]):
        a, b = int(ints[j, shared.J_A]), int(ints[j, shared.J_B])
        if min(a, b) == -1 and max(a, b) >= 0 and count[max(a, b)] == 1:
            lone[max(a, b)] = j
    return lone


def _pivot(ints: IntArray, floats: FloatArray, body: int, dim: int) -> FloatArray:
    """The world point a body with one joint to the world hangs from [m] (d,)."""
    rows = _rows(dim)
    j = _lone_joints(ints)[body]
    side = rows.LA if int(ints[j, shared.J_B]) == body else rows.LB
    point: FloatArray = floats[j, side : side + dim].copy()
    return point


def _hung(scene: Any, ints: IntArray, floats: FloatArray) -> list[_Pendulum]:
    """Every dynamic body hung from the world by its one joint (a revolute one in 2D, a
    spherical one holding a ball in 3D, or a rigid distance joint anchored at its centre), at
    rest at the start, and its closed form."""
    dim, rows = int(scene.dim), _rows(int(scene.dim))
    g = float(np.linalg.norm(scene.gravity))
    if g == 0.0:
        return []
    down = np.asarray(scene.gravity, np.float64) / g
    hung = []
    x, v = scene.position, scene.velocity
    spin = np.asarray(scene.omega, np.float64)
    for body, j in sorted(_lone_joints(ints).items()):
        kind = int(ints[j, shared.J_KIND])
        on_b = int(ints[j, shared.J_B]) == body
        local = floats[j, rows.LB : rows.LB + dim] if on_b else floats[j, rows.LA : rows.LA + dim]
        pivot_local = (
            floats[j, rows.LA : rows.LA + dim] if on_b else floats[j, rows.LB : rows.LB + dim]
        )
        rests = not np.any(v[body]) and not np.any(spin[body])
        if scene.kind[body] != KIND_DYNAMIC or not rests:
            continue
        r = x[body] - pivot_local
        d = float(np.linalg.norm(r))
        if kind == shared.DISTANCE:
            rigid = floats[j, rows.LOWER] == floats[j, rows.UPPER]
            if not rigid or ints[j, shared.J_FLAGS] & shared.FLAG_SPRING or np.any(local):
                continue
            length = d
        elif kind == shared.REVOLUTE and dim == 2 and d > 0.0:
            mass = float(scene.mass[body])
            length = (float(scene.inertia[body]) + mass * d * d) / (mass * d)
        elif kind == shared.SPHERICAL and d > 0.0:
            # a ball and socket swings in one plane when the body's inertia is the same about
            # every axis (a ball): then a physical pendulum about the plane's normal
            inertia = np.asarray(scene.inertia[body], np.float64)
            moment = float(inertia[0, 0])
            if not np.allclose(inertia, moment * np.eye(3), rtol=0.0, atol=1e-12 * moment):
                continue
            mass = float(scene.mass[body])
            length = (moment + mass * d * d) / (mass * d)
        else:
            continue
        if d == 0.0:
            continue
        across = r - (r @ down) * down
        width = float(np.linalg.norm(across))
        if width == 0.0:
            continue  # hanging straight down: it does not swing
        side = across / width
        amplitude = math.atan2(width, float(r @ down))
        hung.append(
            _Pendulum(
                body,
                pivot_local.copy(),
                down,
                side,
                pendulum_period(length, g, amplitude),
                amplitude,
            )
        )
    return hung


def _pendulums(scene: Any, ints: IntArray, floats: FloatArray) -> list[_Pendulum]:
    """The lone pendulums: hung bodies (:func:`_hung`) with nothing near at the start (every
    other body's centre farther from the pivot than the arm and both bodies' reaches)."""
    reach = scene.model.reach
    lone = []
    for p in _hung(scene, ints, floats):
        arm = float(np.linalg.norm(scene.position[p.body] - p.pivot))
        apart = np.linalg.norm(scene.position[: scene.n] - p.pivot, axis=1)
        near = apart <= arm + reach[p.body] + reach[: scene.n]
        near[p.body] = False
        if not np.any(near):
            lone.append(p)
    return lone


def _cradle(
    scene: Any, ints: IntArray, floats: FloatArray, lone: list[_Pendulum]
) -> _Cradle | None:
    """Newton's cradle on strings, when the scene is one: every body a dynamic ball of one
    mass and radius hung on a rigid distance joint at its centre, in a touching row across
    gravity, the first let go from the side (a hung pendulum), the row's restitution 1."""
    n = scene.n
    if n < 2 or lone:
        return None
    hung = {p.body: p for p in _hung(scene, ints, floats)}
    lone_joints = _lone_joints(ints)
    if len(lone_joints) != n or ints.shape[0] != n:
        return None
    pieces = scene.pieces
    if any(len(pieces[i]) != 1 or pieces[i][0].vertices.shape[0] != 1 for i in range(n)):
        return None
    radius = {float(pieces[i][0].radius) for i in range(n)}
    mass = {float(scene.mass[i]) for i in range(n)}
    if len(radius) != 1 or len(mass) != 1 or len(hung) != 1:
        return None
    (first,) = hung.values()
    r = radius.pop()
    rest = [i for i in range(n) if i != first.body]
    x = scene.position
    line = x[rest[-1]] - x[rest[0]]
    if float(np.linalg.norm(line)) == 0.0:
        return None
    line = line / np.linalg.norm(line)
    order = sorted(rest, key=lambda i: float(x[i] @ line))
    if float((x[order[0]] - x[first.body]) @ line) < 0.0:
        order = order[::-1]
    gaps = np.linalg.norm(np.diff(x[order], axis=0), axis=1)
    if not np.allclose(gaps, 2.0 * r, rtol=1e-9, atol=0.0):
        return None
    if abs(float(line @ first.down)) > 1e-9:
        return None
    e = scene.restitution[scene.material[order[0]], scene.material[order[0]]]
    if e != 1.0:
        return None
    # the first ball strikes at the bottom of its swing, a quarter period after its release
    g = float(np.linalg.norm(scene.gravity))
    length = float(np.linalg.norm(x[first.body] - first.pivot))
    speed = math.sqrt(2.0 * g * length * (1.0 - math.cos(first.amplitude)))
    strike = 0.25 * first.period
    # the last ball out rises for a quarter swing (a little more at a finite amplitude) and
    # comes back after two: watch one and a half, from a tenth of one on (a soft step passes
    # the blow along the row over a few steps)
    quarter = 0.25 * 2.0 * math.pi * math.sqrt(length / g)
    balls = np.array([first.body, *order], np.int64)
    pivots = np.array([_pivot(ints, floats, int(i), int(scene.dim)) for i in balls])
    return _Cradle(
        balls,
        pivots,
        np.linalg.norm(x[balls] - pivots, axis=1),
        first.down,
        g,
        strike,
        speed,
        strike + 0.1 * quarter,
        strike + 1.5 * quarter,
    )
