"""Forces and torques given to bodies for the next step (Box2D's ``b2Body_ApplyForce``).

A game pushes a body for a frame: :meth:`Loads.add_forces` and :meth:`Loads.add_torques`
sum what is given until the next step, which applies it and clears it. Through the step a
force ``F`` and a torque ``T`` are constant, so each path of the step takes them in its own way,
with no special case elsewhere:

- **free flight** stays exact: the centre moves under ``g + F / m``; in 2D the angle under
  ``T / I`` (``theta + w t + T t^2 / (2 I)``); in 3D the angular momentum is ``L + T t`` and the
  orientation integrated as in torque-free flight
  (:func:`carom.engines.rigid3d.motion.turn_under`);
- **exact impacts** take ``F / m`` in each body's acceleration, as they take gravity; an island
  with a torqued body is the solver's (the exact path moves bodies at constant spin);
- **the solver** adds ``h F / m`` and ``h I^-1 T`` to the velocities each substep, as it adds
  gravity (as Box2D integrates forces).

The broad and narrow phases widen each loaded body's reach by the most its load can
accelerate any of its points, ``|F| / m + |I^-1| |T| reach`` (``pull``), so a pushed body
misses no contact. The energy ledger books the loads' work: ``F . dx`` (exact for a constant
force, whatever the path), ``T dtheta`` in 2D, ``T . w h`` over the solver's substeps in 3D,
and the energy a free body gains in 3D (nothing else acts on it), so that
``E0 + work_done = E + energy_lost - energy_given`` still holds.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from carom.jit import leaf

__all__ = ["Loaded", "Loads", "fit_to_move"]

FloatArray = NDArray[np.float64]


class Loaded(NamedTuple):
    """A step's loads as it began, for booking their work at its end."""

    #: bodies with a force or a torque (N,)
    on: NDArray[np.bool_]
    #: every body's position at the step's start (N, d) [m]
    x0: FloatArray
    #: bodies with a torque (N,)
    torqued: NDArray[np.bool_]
    #: every body's angle at the step's start (N,) [rad] in 2D; empty in 3D
    turn0: FloatArray


class Loads:
    """The forces and torques summed for the next step of an engine of ``n`` bodies in
    ``dims`` dimensions.

    Attributes
    ----------
    force : (n, dims) float64
        Forces [N] at the centres of mass.
    torque : (n,) float64 in 2D, (n, 3) in 3D
        Torques [N m] (a world vector in 3D), including those of forces given off the centre.
    on : bool
        Whether any body has a load now.
    """

    def __init__(self, n: int, dims: int) -> None:
        self.dims = dims
        self.force = np.zeros((n, dims))
        self.torque = np.zeros(n) if dims == 2 else np.zeros((n, 3))
        #: what the step without loads reads: nothing torqued, no pull (kept, never written)
        self.none_torqued = np.zeros(n, np.bool_)
        self.no_pull = np.zeros(n)
        self.on = False

    def add_forces(
        self, ids: NDArray[np.int64], forces: FloatArray, arms: FloatArray | None
    ) -> None:
        """Add ``forces`` (k, d) [N] on bodies ``ids`` (k,), each at ``arms[j]`` (k, d) [m] from
        its centre of mass (None: at the centre; no torque), in order."""
        np.add.at(self.force, ids, forces)
        if arms is not None:
            if self.dims == 2:
                moment = arms[:, 0] * forces[:, 1] - arms[:, 1] * forces[:, 0]
            else:
                moment = np.cross(arms, forces)
            np.add.at(self.torque, ids, moment)
        self.on = True

    def add_torques(self, ids: NDArray[np.int64], torques: FloatArray) -> None:
        """Add ``torques`` (k,) in 2D or (k, 3) in 3D [N m] on bodies ``ids`` (k,)."""
        np.add.at(self.torque, ids, torques)
        self.on = True

    def loaded(self) -> NDArray[np.bool_]:
        """Bodies with a force or a torque (n,)."""
        spin = self.torque.reshape(self.torque.shape[0], -1)
        flags: NDArray[np.bool_] = np.any(self.force != 0.0, axis=1) | np.any(spin != 0.0, axis=1)
        return flags

    def torqued(self) -> NDArray[np.bool_]:
        """Bodies with a torque (n,)."""
        flags: NDArray[np.bool_] = np.any(
            self.torque.reshape(self.torque.shape[0], -1) != 0.0, axis=1
        )
        return flags

    def pull(self, inv_mass: FloatArray, inv_inertia: FloatArray, reach: FloatArray) -> FloatArray:
        """The most each body's load accelerates any of its points [m/s^2], (n,):
        ``|F| / m + |I^-1| |T| reach`` (``|I^-1|`` the sum of the magnitudes of its entries in
        3D, which bounds its largest eigenvalue)."""
        linear = np.linalg.norm(self.force, axis=1) * inv_mass
        if self.dims == 2:
            turning = np.abs(self.torque) * inv_inertia
        else:
            turning = np.linalg.norm(self.torque, axis=1) * np.abs(inv_inertia).sum(axis=(1, 2))
        bound: FloatArray = linear + turning * reach
        return bound

    def clear(self) -> None:
        """Forget the loads (after the step that applied them)."""
        if self.on:
            self.force[:] = 0.0
            self.torque[:] = 0.0
            self.on = False


@leaf
def fit_to_move(
    ids: np.ndarray, alive: np.ndarray, dynamic: np.ndarray, values: np.ndarray,
    points: np.ndarray, largest: float,
) -> bool:  # fmt: skip
    """Whether every one of ``ids`` (k,) is a body in the world (``alive`` (n,)) and dynamic
    (``dynamic``, the engine's rows), and every number of ``values`` and ``points`` is
    finite and within ``largest``: the game loop's checks in one compiled pass (the caller
    says what is wrong when one fails)."""
    n = alive.shape[0]
    for k in range(ids.shape[0]):
        i = ids[k]
        if i < 0 or i >= n or not alive[i] or not dynamic[i]:
            return False
    for array in (values, points):
        for r in range(array.shape[0]):
            for c in range(array.shape[1]):
                if not abs(array[r, c]) <= largest:  # (NaN too)
                    return False
    return True
