"""What is measured of a simulation: energies, momentum, temperatures, pressure, rates.

Functions of a body table and its state (any engine's), and :class:`Stats`, the averages of a
:class:`carom.World` over a window, from its engine's running counters. The formulas are those
of PHYSICS.md section 6 (``k_B = 1``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np
from numpy.typing import NDArray

from carom.bodies import Bodies
from carom.engines.base import Counters
from carom.geometry.rotation import rotation_matrices
from carom.recording import Frame

__all__ = [
    "RunHistory",
    "Stats",
    "angular_momentum",
    "kinetic_energy",
    "momentum",
    "potential_energy",
    "rotational_energy",
    "rotational_temperature",
    "temperature",
]

FloatArray = NDArray[np.float64]


def kinetic_energy(
    bodies: Bodies,
    velocities: FloatArray,
    angular_velocities: FloatArray,
    orientations: FloatArray | None = None,
) -> float:
    """Kinetic energy [J], translation and rotation, of the moving bodies with these
    velocities (N, d) [m/s] and angular velocities (N, 3) [rad/s] (3D rigid bodies: at these
    orientations, :func:`rotational_energy`)."""
    m = bodies.mobile
    v, mass = velocities[m], bodies.mass[m]
    ke = 0.5 * np.sum(mass * np.sum(v * v, axis=1))
    return float(ke + rotational_energy(bodies, angular_velocities, orientations))


def _spin_momenta(
    bodies: Bodies, angular_velocities: FloatArray, orientations: FloatArray | None
) -> FloatArray:
    """Each moving body's spin angular momentum ``I w`` (n, 3) [kg m^2/s]: with its full
    inertia tensor turned to the world, ``R I R^T w``, for 3D bodies at ``orientations``
    (N, 4); with its moment ``q m a^2`` otherwise (spheres, 2D)."""
    m = bodies.mobile
    spin = angular_velocities[m]
    if bodies.dim != 3 or orientations is None:
        moments: FloatArray = bodies.inertia[m, None] * spin
        return moments
    r = rotation_matrices(np.asarray(orientations, float)[m])
    body_spin = np.einsum("nji,nj->ni", r, spin)  # R^T w
    turned: FloatArray = np.einsum(
        "nij,nj->ni", r, np.einsum("nij,nj->ni", bodies.inertia_tensor[m], body_spin)
    )
    return turned


def rotational_energy(
    bodies: Bodies, angular_velocities: FloatArray, orientations: FloatArray | None = None
) -> float:
    """The rotational part ``sum w . I w / 2`` [J] of :func:`kinetic_energy`, over the moving
    bodies with these angular velocities (N, 3) [rad/s]; 3D rigid bodies' full inertia
    tensors need their ``orientations`` (N, 4) (without, each body's mean moment)."""
    m = bodies.mobile
    spin = angular_velocities[m]
    return float(0.5 * np.sum(spin * _spin_momenta(bodies, angular_velocities, orientations)))


def angular_momentum(
    bodies: Bodies,
    positions: FloatArray,
    velocities: FloatArray,
    angular_velocities: FloatArray,
    orientations: FloatArray | None = None,
) -> FloatArray:
    """Total angular momentum (3,) [kg m^2/s] about the origin of the moving bodies at these
    positions (N, d) [m] with these velocities (N, d) [m/s] and angular velocities (N, 3)
    [rad/s]: orbital ``sum m x × v`` plus spin ``sum I w`` (2D: only z is nonzero; 3D rigid
    bodies' full tensors at their ``orientations`` (N, 4))."""
    m = bodies.mobile
    x, v = positions[m], velocities[m]
    mass = bodies.mass[m]
    total: FloatArray = np.sum(_spin_momenta(bodies, angular_velocities, orientations), axis=0)
    if bodies.dim == 2:
        total[2] += np.sum(mass * (x[:, 0] * v[:, 1] - x[:, 1] * v[:, 0]))
    else:
        total += np.sum(mass[:, None] * np.cross(x, v), axis=0)
    return total


def momentum(bodies: Bodies, velocities: FloatArray) -> FloatArray:
    """Total momentum (d,) [kg m/s] of the moving bodies with these velocities (N, d)."""
    m = bodies.mobile
    result: FloatArray = np.sum(bodies.mass[m, None] * velocities[m], axis=0)
    return result


def potential_energy(bodies: Bodies, positions: FloatArray, gravity: FloatArray) -> float:
    """Gravitational potential energy ``-sum m g . x`` [J] of the moving bodies at these
    positions (N, d) [m]; zero without gravity."""
    if not np.any(gravity):
        return 0.0
    m = bodies.mobile
    return float(-np.sum(bodies.mass[m] * (positions[m] @ gravity)))


def temperature(bodies: Bodies, velocities: FloatArray) -> float:
    """Translational granular temperature ``T = sum m |v - v_cm|^2 / (d N)`` [J] (``k_B = 1``)
    of the moving bodies: velocities relative to their centre of mass, so a drifting gas
    has the temperature of the same gas at rest."""
    m = bodies.mobile
    n = int(np.count_nonzero(m))
    if n == 0:
        return 0.0
    return 2.0 * _peculiar_kinetic_energy(bodies, velocities) / (bodies.dim * n)


def rotational_temperature(bodies: Bodies, angular_velocities: FloatArray) -> float:
    """Rotational temperature ``sum I w^2 / (f N)`` [J] of the moving bodies, with ``f`` the
    rotational degrees of freedom (3 in 3D, 1 in 2D); equal to :func:`temperature` in
    equilibrium (equipartition)."""
    m = bodies.mobile
    n = int(np.count_nonzero(m))
    if n == 0:
        return 0.0
    spin = angular_velocities[m] if bodies.dim == 3 else angular_velocities[m][:, 2:]
    inertia = bodies.inertia_factor[m] * bodies.mass[m] * bodies.radius[m] ** 2
    f = 3 if bodies.dim == 3 else 1
    return float(np.sum(inertia * np.sum(spin * spin, axis=1)) / (f * n))


def _peculiar_kinetic_energy(bodies: Bodies, velocities: FloatArray) -> float:
    """``sum m |v - v_cm|^2 / 2`` [J] over the moving bodies: translation relative to the
    centre of mass."""
    m = bodies.mobile
    v, mass = velocities[m], bodies.mass[m]
    v_cm = np.sum(mass[:, None] * v, axis=0) / np.sum(mass)
    dv = v - v_cm
    return float(0.5 * np.sum(mass * np.sum(dv * dv, axis=1)))


class Observed(Protocol):
    """What the observables read of a :class:`carom.World` (which imports this module)."""

    dim: int
    bodies: Bodies
    #: (d,) [m]
    box: NDArray[np.float64]
    #: (d,) [m/s^2]
    gravity: NDArray[np.float64]

    @property
    def time(self) -> float: ...

    @property
    def velocities(self) -> NDArray[np.float64]: ...

    @property
    def angular_velocities(self) -> NDArray[np.float64]: ...

    def counters(self) -> Counters: ...

    def frame(self) -> Frame: ...


class Stats:
    """Observables of a :class:`carom.World`; averages run since the last :meth:`reset`."""

    def __init__(self, world: Observed) -> None:
        self._world = world
        self._t0 = world.time
        self._start = world.counters()

    def reset(self) -> None:
        """Start a new averaging window now."""
        self._t0 = self._world.time
        self._start = self._world.counters()

    def _since(self) -> Counters:
        return self._world.counters().minus(self._start)

    @property
    def collisions(self) -> int:
        """Collisions between two bodies since the last reset."""
        return self._since().collisions

    @property
    def wall_collisions(self) -> int:
        """Collisions with walls and planes since the last reset."""
        return self._since().wall_collisions

    @property
    def events_processed(self) -> int:
        """Events the engine processed since the last reset: collisions, and its own
        bookkeeping (neighbour-shell rebuilds, stale predictions)."""
        return self._since().events

    @property
    def tc_collisions(self) -> int:
        """Collisions the TC model made elastic since the last reset."""
        return self._since().tc_collisions

    @property
    def floor_collisions(self) -> int:
        """Collisions since the last reset whose parting speed the engine raised to its floor
        (``docs/engine.md``, "Minimum parting speed")."""
        return self._since().floor_collisions

    @property
    def kinetic_energy(self) -> float:
        """Total kinetic energy now, translation and rotation [J]."""
        frame = self._world.frame()  # one sample of the engine for both
        return kinetic_energy(
            self._world.bodies, frame.velocities, frame.angular_velocities, frame.orientations
        )

    @property
    def momentum(self) -> FloatArray:
        """Total momentum of the moving bodies now, (d,) [kg m/s]."""
        return momentum(self._world.bodies, self._world.velocities)

    @property
    def temperature(self) -> float:
        """Translational temperature now, relative to the centre of mass [J] (``k_B = 1``)."""
        return temperature(self._world.bodies, self._world.velocities)

    @property
    def rotational_temperature(self) -> float:
        """Rotational temperature now [J] (``k_B = 1``)."""
        return rotational_temperature(self._world.bodies, self._world.angular_velocities)

    @property
    def pressure(self) -> float:
        """Pressure from the collision virial over the window [Pa] (2D: [N/m]).

        ``P = (2 K + sum J . r / dt) / (d V)`` with ``K`` the translational kinetic energy
        relative to the centre of mass now (so neither spin nor a drift of the whole gas
        counts; constant in elastic systems, not stationary in dissipative ones): pairs
        contribute ``J . (x1 - x2)``, walls and planes ``J . x`` with ``x`` the sphere's
        centre (PHYSICS.md section 6). In a periodic box this is the bulk pressure; in a box
        with walls, the pressure of the fluid whose centres fill the box. NaN under gravity
        or before any time has passed.
        """
        w = self._world
        dt = w.time - self._t0
        if dt <= 0.0 or np.any(w.gravity != 0.0):
            return math.nan
        volume = float(np.prod(w.box))
        kinetic = _peculiar_kinetic_energy(w.bodies, w.velocities)
        return (2.0 * kinetic + self._since().virial / dt) / (w.dim * volume)

    @property
    def mean_free_time(self) -> float:
        """Mean time between collisions of a body with another [s]: ``N dt / (2 C)``."""
        w = self._world
        n = int(np.count_nonzero(w.bodies.mobile))
        coll = self.collisions
        dt = w.time - self._t0
        return math.inf if coll == 0 else n * dt / (2.0 * coll)

    @property
    def energy_lost(self) -> float:
        """Kinetic energy dissipated by collisions since the last reset [J] (the impact laws'
        part: it never decreases)."""
        return self._since().energy_lost

    @property
    def energy_given(self) -> float:
        """Kinetic energy the parting-speed floor (the rigid engine: its solver) gave since the
        last reset [J]."""
        return self._since().energy_given

    @property
    def work_done(self) -> float:
        """Work kinematic bodies did on the others since the last reset [J]; the ledger closes
        as ``E0 + work_done = E + energy_lost - energy_given``."""
        return self._since().work_done


@dataclass
class RunHistory:
    """A run's observables, recorded as it goes (for its plots and summary): time [s],
    kinetic energy (translation and rotation) and its rotational part [J], potential energy
    [J], energy dissipated so far [J], energy given so far (by the parting-speed floor, or by
    the rigid solver) [J], work done by kinematic bodies so far [J], total momentum [kg m/s],
    total angular momentum about the origin [kg m^2/s], and collisions so far (bodies and
    walls) [-]."""

    time: list[float] = field(default_factory=list)
    kinetic: list[float] = field(default_factory=list)
    rotational: list[float] = field(default_factory=list)
    potential: list[float] = field(default_factory=list)
    dissipated: list[float] = field(default_factory=list)
    given: list[float] = field(default_factory=list)
    work: list[float] = field(default_factory=list)
    momentum: list[NDArray[np.float64]] = field(default_factory=list)
    angular_momentum: list[NDArray[np.float64]] = field(default_factory=list)
    collisions: list[int] = field(default_factory=list)

    def add(self, world: Observed, frame: Frame) -> None:
        """Record ``frame`` of ``world`` (taken now: the dissipation so far is the world's)."""
        b = world.bodies
        x, v, w = frame.positions, frame.velocities, frame.angular_velocities
        q = frame.orientations
        self.time.append(frame.time)
        self.kinetic.append(kinetic_energy(b, v, w, q))
        self.rotational.append(rotational_energy(b, w, q))
        self.potential.append(potential_energy(b, x, world.gravity))
        counters = world.counters()
        self.dissipated.append(counters.energy_lost)
        self.given.append(counters.energy_given)
        self.work.append(counters.work_done)
        self.momentum.append(momentum(b, v))
        self.angular_momentum.append(angular_momentum(b, x, v, w, q))
        self.collisions.append(counters.collisions + counters.wall_collisions)

    def arrays(self) -> dict[str, NDArray[np.float64]]:
        """Every series as an array, by name (for checkpoints)."""
        return {name: np.array(getattr(self, name)) for name in self.__dataclass_fields__}

    @classmethod
    def from_arrays(cls, arrays: dict[str, NDArray[np.float64]]) -> RunHistory:
        """The history :meth:`arrays` saved.

        Raises
        ------
        KeyError
            A series is missing (the checkpoint was written by a carom that kept fewer).
        """
        history = cls(**{name: arrays[name].tolist() for name in cls.__dataclass_fields__})
        history.momentum = list(arrays["momentum"])
        history.angular_momentum = list(arrays["angular_momentum"])
        return history
