"""Model: the constants of a simulation, as plain arrays (MuJoCo's MjModel split).

A :class:`Model` never changes while a simulation runs: geometry, masses, materials, walls,
gravity and the engine's settings. Everything that changes lives in
:class:`carom.engines.edmd.state.State`.
Both are named tuples of NumPy arrays and scalars, so the Numba kernels take them as they are.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from carom.materials import PairTable

__all__ = ["Environment", "Model"]


class Model(NamedTuple):
    """Constants of a simulation of ``N`` bodies in ``d`` dimensions with ``M`` materials.

    Attributes
    ----------
    box : (d,) float64
        Box side lengths [m]; the box is ``[0, box[k]]`` on each axis.
    inv_box : (d,) float64
        ``1 / box`` [1/m] (a multiplication is cheaper than a division in the hot loop).
    periodic : bool
        Periodic boundaries (no walls) when true.
    gravity : (d,) float64 or None
        Uniform acceleration [m/s^2]; None when no gravity acts (every path is a straight
        line). None is a type of its own to Numba: the kernels are compiled without the code
        for parabolas and supports then (the branches on ``gravity is None`` are pruned
        before typing), a smaller and faster compile.
    mobile : (N,) bool
        False for static bodies (pegs, obstacles): infinite mass, never move.
    radius, mass, inv_mass : (N,) float64
        Radius [m], mass [kg] (inf when static), 1/mass [1/kg].
    q : (N,) float64 or None
        Inertia factor ``I = q m a^2`` [-]. None when no body ever spins (every pair law
        smooth, every spin zero, every orientation the identity): the state then holds no
        spins or orientations, and the kernels are compiled without the code that turns
        bodies (branches on None are pruned before typing, as for ``gravity``).
    material : (N,) int64
        Material index of each body.
    pair_law : (M, M) int64
        Impulse law per material pair (:mod:`carom.laws.kernels`).
    pair_e, pair_beta, pair_friction : (M, M) float64
        Normal restitution [-]; constant ``beta`` or Walton's ``beta0`` [-]; Coulomb
        coefficient [-].
    face_e : (2 d + P,) float64
        Restitution of the walls (lower, upper for each axis) and of the P planes [-].
    plane_point, plane_normal : (P, d) float64
        A point on each static plane [m] and its unit normal, pointing into the free side.
    t_c : float
        TC-model time [s]: a collision within ``t_c`` of a body's previous one is elastic.
    shell_thickness : float
        Neighbour-shell thickness [m]: how far a body moves before its list is rebuilt.
    cell_size : (d,) float64
        Cell-grid spacing [m], at least one shell diameter.
    ncell : (d,) int64
        Cells per axis.
    """

    box: NDArray[np.float64]
    inv_box: NDArray[np.float64]
    periodic: bool
    gravity: NDArray[np.float64] | None
    mobile: NDArray[np.bool_]
    radius: NDArray[np.float64]
    mass: NDArray[np.float64]
    inv_mass: NDArray[np.float64]
    q: NDArray[np.float64] | None
    material: NDArray[np.int64]
    pair_law: NDArray[np.int64]
    pair_e: NDArray[np.float64]
    pair_beta: NDArray[np.float64]
    pair_friction: NDArray[np.float64]
    face_e: NDArray[np.float64]
    plane_point: NDArray[np.float64]
    plane_normal: NDArray[np.float64]
    t_c: float
    shell_thickness: float
    cell_size: NDArray[np.float64]
    ncell: NDArray[np.int64]

    @property
    def dim(self) -> int:
        return int(self.box.shape[0])

    @property
    def n_bodies(self) -> int:
        return int(self.radius.shape[0])


class Environment(NamedTuple):
    """What surrounds the bodies: the box, gravity, the materials' pair table, and the static
    faces (the box's walls, lower and upper per axis, then the planes)."""

    box: NDArray[np.float64]
    periodic: bool
    gravity: NDArray[np.float64]
    pairs: PairTable
    face_e: NDArray[np.float64]
    plane_point: NDArray[np.float64]
    plane_normal: NDArray[np.float64]

    @property
    def dim(self) -> int:
        return int(self.box.shape[0])
