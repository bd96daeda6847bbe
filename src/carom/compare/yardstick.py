"""What ``carom compare`` measures of rigid bodies alike in 2D and 3D: the scene's common
reading (:class:`RigidSceneBase`), the yardstick every monitor applies (:class:`Yardstick`),
per-material coefficients for a peer's mixing rule (:func:`shape_coefficients`), and a body's
size (:func:`extent`). :mod:`carom.compare.rigid` (2D) and :mod:`carom.compare.rigid3d` (3D)
build on it; neither imports the other.
"""

from __future__ import annotations

import copy
import functools
import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any, ClassVar, Protocol, Self

import numpy as np
from numpy.typing import NDArray

from carom.compare.jointed import JointGauge, JointSpec, joint_specs
from carom.compare.spec import steps_to
from carom.engines.stepped.settings import RigidSettings
from carom.errors import CaromError
from carom.laws.kinds import KIND_DYNAMIC

if TYPE_CHECKING:
    from carom.world import World

__all__ = [
    "FLIGHT_STEP",
    "LEVEL",
    "Expectation",
    "ImpactBase",
    "RigidSceneBase",
    "Yardstick",
    "check_time",
    "extent",
    "next_contact",
    "shape_coefficients",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: at most this many points of the series are kept per engine
SERIES_POINTS = 1500
#: the closed form's post-impact flight is searched for a second contact at this step [s]
FLIGHT_STEP = 1e-4
#: two corners within this height of each other [m] land together (an edge or face lands)
LEVEL = 1e-12


class Expectation(Protocol):
    """What the yardstick reads of a closed form (2D ``ImpactCheck``, 3D ``ImpactCheck3D``):
    the ``body``, the check ``time`` [s], its ``velocity`` [m/s] and ``omega`` [rad/s] then,
    the contact's approach ``speed`` [m/s] and the body's ``reach`` [m]."""

    @property
    def body(self) -> int: ...

    @property
    def time(self) -> float: ...

    @property
    def velocity(self) -> FloatArray: ...

    @property
    def omega(self) -> Any: ...

    @property
    def speed(self) -> float: ...

    @property
    def reach(self) -> float: ...


class Piece(Protocol):
    """A convex piece as the scenes keep it (2D or 3D): corners (k, d) [m] and a radius [m]."""

    @property
    def vertices(self) -> FloatArray: ...

    @property
    def radius(self) -> float: ...


@dataclass(frozen=True)
class RigidSceneBase:
    """What a 2D and a 3D rigid scene are alike: plain data read off carom's engine as it
    would start, each body as the engine sees it.

    Attributes
    ----------
    name, title : str
        The scene's name and title.
    n : int
        The caller's bodies: the first ``n`` rows. The rows after them are the box's walls
        (static slabs) and the planes.
    settings : RigidSettings
        carom's engine settings (rate, substeps, sleep); the peers take the same rate.
    until : float
        Simulated time [s].
    model, start
        carom's engine's constants and its state at the start; the properties read them:
        ``kind`` (B,), ``mass`` [kg] and ``inertia`` (inf for static and kinematic bodies),
        ``material`` (B,), ``restitution`` and ``friction`` (M, M) [-], ``gravity``
        [m/s^2], ``position`` and ``velocity`` [m], [m/s] (centres of mass).
    world : callable
        A fresh copy of the scene's :class:`World`, not yet run.
    joint_ints, joint_floats : ndarray
        The world's joint rows (J, 4) and (J, F) (:attr:`carom.World.joint_rows`); the
        :attr:`joints` property reads them as :class:`~carom.compare.jointed.JointSpec`.

    A dimension's scene adds its bodies' ``pieces`` (each body's convex pieces in its frame,
    centre of mass at the origin [m]) and says how its engine's parts are read
    (:meth:`_parts`, :meth:`_pieces`).
    """

    name: str
    title: str
    n: int
    settings: RigidSettings
    until: float
    model: Any = field(compare=False, repr=False)
    start: Any = field(compare=False, repr=False)
    world: Callable[[], World] = field(compare=False, repr=False)
    joint_ints: IntArray = field(compare=False, repr=False)
    joint_floats: FloatArray = field(compare=False, repr=False)

    #: 2 or 3
    dim: ClassVar[int]

    @classmethod
    def from_world(
        cls, build: Callable[[], World], name: str, until: float, title: str = ""
    ) -> Self:
        """Read the world ``build()`` makes, as its rigid engine would start."""
        world = build()
        model, state = cls._parts(world)
        joint_ints, joint_floats = world.joint_rows
        return cls(
            name=name,
            title=title or name,
            n=world.n_bodies,
            settings=world.rigid_settings,
            until=float(until),
            model=model,
            start=state,
            world=functools.partial(copy.deepcopy, world),
            joint_ints=joint_ints,
            joint_floats=joint_floats,
            pieces=cls._pieces(model),  # type: ignore[call-arg]
        )

    @classmethod
    def _parts(cls, world: World) -> tuple[Any, Any]:
        """The engine's constants and starting state for ``world``; a world of another
        dimension is refused with a :class:`CaromError`."""
        raise NotImplementedError

    @staticmethod
    def _pieces(model: Any) -> tuple[tuple[Any, ...], ...]:
        """Each body's pieces in its frame, read off the engine's constants."""
        raise NotImplementedError

    kind = property(lambda self: self.model.kind)
    mass = property(lambda self: self.model.mass)
    inertia = property(lambda self: self.model.inertia)
    material = property(lambda self: self.model.material)
    restitution = property(lambda self: self.model.e_table)
    friction = property(lambda self: self.model.mu_table)
    gravity = property(lambda self: self.model.gravity)
    position = property(lambda self: self.start.x)
    velocity = property(lambda self: self.start.v)

    @property
    def joints(self) -> tuple[JointSpec, ...]:
        """The live joints in world terms at the start, for the peers to build."""
        turn = self.start.angle if self.dim == 2 else self.start.q
        return joint_specs(self.joint_ints, self.joint_floats, self.position, turn)

    @property
    def bodies(self) -> int:
        """Every row: the caller's bodies, walls and planes."""
        return int(self.kind.shape[0])

    @property
    def dt(self) -> float:
        """carom's step [s]."""
        return self.settings.dt

    def steps(self, dt: float) -> int:
        """Steps of ``dt`` [s] that reach ``until``."""
        return steps_to(self.until, dt)

    def needed_pairs(self) -> list[tuple[int, int]]:
        """Pairs of materials that can meet: a dynamic body's material with any other
        body's (a material with itself only when two bodies have it)."""
        count = np.bincount(self.material, minlength=self.restitution.shape[0])
        dynamic = sorted(set(self.material[self.kind == KIND_DYNAMIC].tolist()))
        every = sorted(set(self.material.tolist()))
        return [(a, b) for a in dynamic for b in every if a != b or count[a] >= 2]


@dataclass(frozen=True)
class ImpactBase:
    """The closed form of one body landing on flat ground, as both dimensions give it.

    Attributes
    ----------
    body : int
        The falling body.
    impact_time : float
        When its lowest point reaches the ground [s] (free fall).
    time : float
        When the engines are checked [s]: after the impact, before any second contact.
    velocity : (d,) float64
        Centre-of-mass velocity at ``time`` [m/s].
    omega : float or (3,) float64
        Angular velocity at ``time`` [rad/s] (about z in 2D; the world frame in 3D).
    speed : float
        Approach speed of the contact point at the impact [m/s] (the error scale).
    reach : float
        Farthest point of the body from its centre [m] (turns omega errors into speeds).
    source : str
        What the closed form is.
    """

    body: int
    impact_time: float
    time: float
    velocity: FloatArray
    omega: Any
    speed: float
    reach: float
    source: str


def next_contact(
    t_hit: float, until: float, step: float, touches: Callable[[float], bool]
) -> float:
    """The first time after an impact at ``t_hit`` [s], in steps of ``step`` [s], at which
    ``touches(t)`` (asked in order, once a time), or ``until`` [s] if none comes before."""
    t = t_hit + step
    while t < until:
        if touches(t):
            return t
        t += step
    return until


def check_time(t_hit: float, t_next: float, step: float) -> float | None:
    """When the engines are checked after an impact at ``t_hit`` [s]: the first multiple of
    ``step`` [s] two steps after it, if it comes a step before the body's next contact at
    ``t_next`` [s]; else None (no step fits between them)."""
    first = math.ceil((t_hit + 2.0 * step) / step) * step
    return None if first > t_next - step else first


def shape_coefficients(
    scene: RigidSceneBase, table: FloatArray, rule: str, engine: str, quantity: str
) -> tuple[FloatArray, list[str]]:
    """Per-material coefficients that reproduce ``table`` under a peer's mixing rule.

    Parameters
    ----------
    table : (M, M) float64
        The scene's restitution or friction of each pair of materials [-].
    rule : {"product", "geometric", "max"}
        How the peer mixes two surfaces' coefficients: ``c_a c_b`` (pymunk),
        ``sqrt(c_a c_b)`` (Box2D's friction), ``max(c_a, c_b)`` (Box2D's restitution).
    engine, quantity : str
        For the messages.

    Returns
    -------
    coefficient : (M,) float64
        One per material [-].
    notes : list of str

    Raises
    ------
    CaromError
        When no coefficients give every pair of materials that can meet its value.
    """
    m = table.shape[0]
    pairs = scene.needed_pairs()
    c = np.full(m, np.nan)
    if rule == "max":
        for a, b in pairs:  # the smallest value a material must reach
            for k in (a, b):
                c[k] = table[a, b] if np.isnan(c[k]) else min(c[k], table[a, b])
        mix: Callable[[float, float], float] = max
    else:
        product = table if rule == "product" else table**2
        for a, b in pairs:
            if a == b:
                c[a] = math.sqrt(product[a, a])
        for _ in range(m):  # propagate c_b = e_ab / c_a along the pairs
            for a, b in pairs:
                for p, q in ((a, b), (b, a)):
                    if np.isnan(c[q]) and not np.isnan(c[p]) and c[p] > 0.0:
                        c[q] = product[a, b] / c[p]
        for a, b in pairs:  # a pair with neither side fixed: one side takes it all
            if np.isnan(c[a]) and np.isnan(c[b]):
                c[a], c[b] = 1.0, product[a, b]
        if rule == "product":
            mix = float.__mul__
        else:

            def mix(x: float, y: float) -> float:
                return math.sqrt(x * y)

    c = np.where(np.isnan(c), 0.0, c)
    for a, b in pairs:
        got = mix(float(c[a]), float(c[b]))
        if abs(got - table[a, b]) > 1e-12 * max(1.0, table[a, b]):
            raise CaromError(
                f"{engine} mixes two surfaces' {quantity} by its own rule ({rule}), and no "
                f"coefficient per material gives scene {scene.name!r} its {quantity} "
                f"{table[a, b]:g} between materials {a} and {b} (it would be {got:g}); give "
                f"the materials {quantity} that the rule can reproduce"
            )
    notes = [
        f"{engine} mixes {quantity} as {rule}: per-material coefficients "
        f"{', '.join(f'{x:.6g}' for x in c.tolist())} reproduce the scene's pairs"
    ]
    return c, notes


class Yardstick:
    """What the 2D and 3D monitors measure alike, from the poses and velocities each engine
    reports after a step: energies and their largest gain, the largest rotation, the top
    body's drift, bodies through static ones, the deepest overlap (ten times a simulated
    second), the state at the closed form's check, and the series to plot.

    A monitor sets its own geometry up (:meth:`_setup`), and gives the five measures
    that differ with the dimension: :meth:`_energy`, :meth:`_turns`, :meth:`_momentum`,
    :meth:`_overlap` and :meth:`_passed`. Orientations (``turn``) are angles in 2D and
    quaternions in 3D; angular velocities (``spin``) scalars in 2D and vectors in 3D.
    """

    scene: RigidSceneBase
    expected: Expectation | None

    def __init__(self, scene: Any, expected: Expectation | None, dt: float) -> None:
        self.scene = scene
        self.expected = expected
        self.joints = JointGauge(scene) if scene.joint_ints.shape[0] else None
        dyn = np.nonzero(scene.kind[: scene.n] == KIND_DYNAMIC)[0]
        top = self._setup(dyn)
        self._begin(dt, dyn, top, extent(scene.pieces[top]) if top >= 0 else 1.0)

    def _setup(self, dynamic: IntArray) -> int:
        """The monitor's own geometry, for the ``dynamic`` bodies (indices); return the top
        one (-1: none), whose drift is watched."""
        raise NotImplementedError

    def _begin(self, dt: float, dynamic: IntArray, top: int, size: float) -> None:
        """The counters and series, for observations ``dt`` [s] apart of the ``dynamic``
        bodies (indices), of which ``top`` (-1: none) of size ``size`` [m] is watched."""
        self._dynamic = dynamic
        self._top = top
        self._size = size
        self._every_overlap = max(1, round(0.1 / dt))  # overlaps: ten times a second
        self._every = max(1, math.ceil(self.scene.until / dt / SERIES_POINTS))
        self._previous: FloatArray | None = None
        self.steps = 0
        self.max_overlap = 0.0
        self.through: set[int] = set()
        self.max_top = 0.0
        self.top_drift = 0.0
        self.max_rotation = 0.0
        self.final_rotation = 0.0
        self.energy0: float | None = None
        self.energy_gain = 0.0
        self.final: tuple[float, float, float] = (0.0, 0.0, 0.0)
        self._best: tuple[float, FloatArray, FloatArray] = (
            math.inf,
            np.zeros(self.scene.dim),
            np.zeros(0),
        )
        self.series: dict[str, list[float]] = {
            "time": [],
            "translation": [],
            "rotation": [],
            "potential": [],
            "angular_momentum": [],
            "overlap": [],
        }

    def _energy(
        self, x: FloatArray, v: FloatArray, turn: FloatArray, spin: FloatArray
    ) -> tuple[float, float, float]:
        """Translational and rotational kinetic and potential energy [J]."""
        raise NotImplementedError

    def _turns(self, turn: FloatArray) -> FloatArray:
        """How far each dynamic body has turned since the start [rad]."""
        raise NotImplementedError

    def _momentum(self, x: FloatArray, v: FloatArray, turn: FloatArray, spin: FloatArray) -> float:
        """The angular momentum about the origin [kg m^2/s] (3D: its magnitude)."""
        raise NotImplementedError

    def _overlap(self, x: FloatArray, turn: FloatArray) -> float:
        """Deepest overlap [m] of the poses, by carom's exact contact geometry."""
        raise NotImplementedError

    def _passed(self, before: FloatArray, after: FloatArray, rows: IntArray) -> None:
        """Note the bodies whose centre's path in the step entered a static piece's core."""
        raise NotImplementedError

    def observe(
        self, time: float, x: FloatArray, v: FloatArray, turn: FloatArray, spin: FloatArray
    ) -> None:
        """Take the state of the first ``n`` bodies after a step (time [s]; centres and
        velocities (n, d); orientations and angular velocities as the scene keeps them)."""
        scene, dyn = self.scene, self._dynamic
        translation, rotation, potential = self._energy(x, v, turn, spin)
        total = translation + rotation + potential
        if self.energy0 is None:
            self.energy0 = total
        self.energy_gain = max(self.energy_gain, total - self.energy0)
        self.final = (translation, rotation, potential)
        turned = self._turns(turn) if dyn.shape[0] else np.zeros(1)
        self.final_rotation = float(turned.max())
        self.max_rotation = max(self.max_rotation, self.final_rotation)
        if self._top >= 0:
            self.top_drift = float(np.linalg.norm(x[self._top] - scene.position[self._top]))
            self.max_top = max(self.max_top, self.top_drift)
        if self._previous is not None:
            self._passed(self._previous[dyn], x[dyn], dyn)
        self._previous = x.copy()
        overlap = math.nan
        if self.steps % self._every_overlap == 0:
            overlap = self._overlap(x, turn)
            self.max_overlap = max(self.max_overlap, overlap)
        if self.expected is not None:
            check = self.expected
            gap = abs(time - check.time)
            if gap < self._best[0]:
                moved = v[check.body] + scene.gravity * (check.time - time)
                self._best = (gap, moved, np.array(spin[check.body], float))
        if self.joints is not None:
            self.joints.observe(time, x, v, turn)
        if self.steps % self._every == 0:
            self.series["time"].append(time)
            self.series["translation"].append(translation)
            self.series["rotation"].append(rotation)
            self.series["potential"].append(potential)
            self.series["angular_momentum"].append(self._momentum(x, v, turn, spin))
            self.series["overlap"].append(overlap)
        self.steps += 1

    def result(self) -> dict[str, Any]:
        """The measurements, as JSON-ready numbers (docs/compare.md)."""
        velocity_error = omega_error = None
        if self.expected is not None:
            check = self.expected
            _, v, w = self._best
            velocity_error = float(np.linalg.norm(v - check.velocity)) / check.speed
            miss = float(np.linalg.norm(np.atleast_1d(w - check.omega)))  # 2D: |w - w_exact|
            omega_error = miss * check.reach / check.speed
        e0 = self.energy0 if self.energy0 is not None else 0.0
        scale = abs(e0) if e0 != 0.0 else 1.0
        joints: dict[str, Any] = {"joint_gap_m": None, "pendulums": [], "cradle": None}
        if self.joints is not None:
            joints = self.joints.result()
        return {
            **joints,
            "joint_error": None if self.joints is None else self.joints.error(),
            "velocity_error": velocity_error,
            "omega_error": omega_error,
            "energy_gain": self.energy_gain / scale,
            "final_energy_J": {
                "translation": self.final[0],
                "rotation": self.final[1],
                "potential": self.final[2],
            },
            "max_overlap_m": self.max_overlap,
            "tunnelled": bool(self.through),
            "bodies_through_static": len(self.through),
            "top_body": self._top,
            "top_drift_m": self.top_drift,
            "top_drift_per_size": self.top_drift / self._size,
            "max_top_drift_m": self.max_top,
            "max_rotation_deg": math.degrees(self.max_rotation),
            "final_rotation_deg": math.degrees(self.final_rotation),
            "samples": self.steps,
        }


def extent(pieces: Sequence[Piece]) -> float:
    """A body's size [m]: the longer side of its bounding box in its own frame."""
    corners = np.concatenate([p.vertices for p in pieces])
    radius = max(p.radius for p in pieces)
    return float(np.max(corners.max(axis=0) - corners.min(axis=0)) + 2.0 * radius)
