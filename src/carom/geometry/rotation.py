"""Rotation by a constant angular velocity: a body's orientation after turning for a time.

2D orientations are angles about z [rad]; 3D ones unit quaternions ``(w, x, y, z)``, body to
world. A body spinning at ``omega`` (world frame, constant between impacts) for ``dt`` turns by
the angle ``|omega| dt`` about ``omega``: ``q' = dq q`` with
``dq = (cos(|omega| dt / 2), sin(|omega| dt / 2) omega / |omega|)``, exact (no integration error).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", inline="always")
def turn(orient: np.ndarray, i: int, w0: float, w1: float, w2: float, dt: float, dim: int) -> None:
    """Turn body ``i``'s orientation (row ``i`` of ``orient``) by spin ``w`` [rad/s] for ``dt``
    [s]; in 2D only the spin about z (``w2``) turns the angle in column 0."""
    if dt == 0.0:
        return
    if dim == 2:
        orient[i, 0] += w2 * dt
        return
    speed = math.sqrt(w0 * w0 + w1 * w1 + w2 * w2)
    if speed == 0.0:
        return
    half = 0.5 * speed * dt
    c = math.cos(half)
    s = math.sin(half) / speed
    a0, a1, a2, a3 = c, s * w0, s * w1, s * w2  # dq
    b0, b1, b2, b3 = orient[i, 0], orient[i, 1], orient[i, 2], orient[i, 3]
    q0 = a0 * b0 - a1 * b1 - a2 * b2 - a3 * b3
    q1 = a0 * b1 + a1 * b0 + a2 * b3 - a3 * b2
    q2 = a0 * b2 - a1 * b3 + a2 * b0 + a3 * b1
    q3 = a0 * b3 + a1 * b2 - a2 * b1 + a3 * b0
    norm = math.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)  # keeps |q| = 1 over many turns
    orient[i, 0] = q0 / norm
    orient[i, 1] = q1 / norm
    orient[i, 2] = q2 / norm
    orient[i, 3] = q3 / norm
