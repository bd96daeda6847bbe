"""The engine-neutral body table: shape, mass, inertia, material and pose of every body, as
structure-of-arrays, numbered as the caller added them.

A :class:`carom.World` keeps its bodies here; an engine is built from the table and hands the
bodies' state back in the same numbering. Static bodies have infinite mass.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from carom.shapes import SHAPE_CODES

__all__ = ["Bodies", "identity_orientations"]

FloatArray = NDArray[np.float64]


def identity_orientations(n: int, dim: int) -> FloatArray:
    """``n`` bodies unrotated: angle 0 in 2D, (n, 1); quaternion ``(1, 0, 0, 0)`` in 3D, (n, 4)."""
    if dim == 2:
        return np.zeros((n, 1))
    q = np.zeros((n, 4))
    q[:, 0] = 1.0
    return q


class Bodies:
    """N bodies in ``dim`` dimensions.

    Attributes
    ----------
    position : (N, d) float64
        Centre of mass [m].
    velocity : (N, d) float64
        [m/s].
    orientation : (N, 1) float64 in 2D, (N, 4) in 3D
        Angle about z [rad]; unit quaternion ``w, x, y, z`` (body to world).
    angular_velocity : (N, 3) float64
        [rad/s], world frame (2D: about z, column 2).
    shape : (N,) int8
        Shape code (:data:`carom.shapes.SHAPE_CODES`).
    radius : (N,) float64
        Sphere radius [m].
    mass : (N,) float64
        [kg]; inf for static bodies.
    inertia_factor : (N,) float64
        ``q`` in ``I = q m a^2`` [-].
    material : (N,) int64
        Index of the body's material in the World's list.
    """

    def __init__(self, dim: int) -> None:
        self.dim = dim
        self.position = np.zeros((0, dim))
        self.velocity = np.zeros((0, dim))
        self.orientation = identity_orientations(0, dim)
        self.angular_velocity = np.zeros((0, 3))
        self.shape = np.zeros(0, np.int8)
        self.radius = np.zeros(0)
        self.mass = np.zeros(0)
        self.inertia_factor = np.zeros(0)
        self.material = np.zeros(0, np.int64)

    @property
    def n(self) -> int:
        return int(self.position.shape[0])

    @property
    def mobile(self) -> NDArray[np.bool_]:
        """False for static bodies (infinite mass), (N,)."""
        return np.isfinite(self.mass)

    def append_spheres(
        self,
        position: FloatArray,
        velocity: FloatArray,
        angular_velocity: FloatArray,
        radius: FloatArray,
        mass: FloatArray,
        inertia_factor: float,
        material: int,
    ) -> NDArray[np.int64]:
        """Add spheres (checked by the caller); return their indices."""
        start, n = self.n, position.shape[0]
        self.position = np.concatenate([self.position, position])
        self.velocity = np.concatenate([self.velocity, velocity])
        self.orientation = np.concatenate([self.orientation, identity_orientations(n, self.dim)])
        self.angular_velocity = np.concatenate([self.angular_velocity, angular_velocity])
        self.shape = np.concatenate([self.shape, np.full(n, SHAPE_CODES["sphere"], np.int8)])
        self.radius = np.concatenate([self.radius, radius])
        self.mass = np.concatenate([self.mass, mass])
        self.inertia_factor = np.concatenate([self.inertia_factor, np.full(n, inertia_factor)])
        self.material = np.concatenate([self.material, np.full(n, material, np.int64)])
        return np.arange(start, self.n)

    def set_state(
        self,
        position: FloatArray,
        velocity: FloatArray,
        orientation: FloatArray,
        angular_velocity: FloatArray,
    ) -> None:
        """Replace the pose and motion of every body (from an engine, at its clock)."""
        self.position = position
        self.velocity = velocity
        self.orientation = orientation
        self.angular_velocity = angular_velocity
