"""Rotations, in one module: quaternions and matrices, and a body's orientation after turning
for a time.

2D orientations are angles about z [rad]; 3D ones unit quaternions ``(w, x, y, z)``, body to
world; a rotation matrix is row-major (3, 3), ``x_world = R x_body``. NumPy functions work on
many orientations at once (:func:`rotation_matrices`, :func:`matrix_quaternion`,
:func:`quaternion_product`, :func:`turned_angle`, :func:`turn_z_onto`); the kernels work on one
inside a step (:func:`matrix`, :func:`axis_angle_matrix`, :func:`cos_sin`, :func:`turn`).

A body spinning at ``omega`` (world frame, constant between impacts) for ``dt`` turns by the
angle ``|omega| dt`` about ``omega``: ``q' = dq q`` with
``dq = (cos(|omega| dt / 2), sin(|omega| dt / 2) omega / |omega|)``, exact (no integration error).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit
from numpy.typing import ArrayLike, NDArray

__all__ = [
    "axis_angle_matrix",
    "cos_sin",
    "matrix",
    "matrix_quaternion",
    "orientation_matrices",
    "quaternion_product",
    "rotation_matrices",
    "turn",
    "turn_z_onto",
    "turned_angle",
]

FloatArray = NDArray[np.float64]


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


def rotation_matrices(quaternions: ArrayLike) -> FloatArray:
    """Rotation matrices (n, 3, 3) of unit quaternions ``(w, x, y, z)`` (n, 4), as they are
    (not normalised: for orientations an engine keeps unit)."""
    q = np.asarray(quaternions, float).reshape(-1, 4)
    w, x, y, z = q[:, 0], q[:, 1], q[:, 2], q[:, 3]
    out = np.empty((len(q), 3, 3))
    out[:, 0, 0] = 1 - 2 * (y * y + z * z)
    out[:, 0, 1] = 2 * (x * y - w * z)
    out[:, 0, 2] = 2 * (x * z + w * y)
    out[:, 1, 0] = 2 * (x * y + w * z)
    out[:, 1, 1] = 1 - 2 * (x * x + z * z)
    out[:, 1, 2] = 2 * (y * z - w * x)
    out[:, 2, 0] = 2 * (x * z - w * y)
    out[:, 2, 1] = 2 * (y * z + w * x)
    out[:, 2, 2] = 1 - 2 * (x * x + y * y)
    return out


def orientation_matrices(turn: ArrayLike, dim: int) -> FloatArray:
    """Rotation matrices (N, d, d) of orientations ``turn``: angles (N,) [rad] about z in 2D,
    unit quaternions (N, 4) ``(w, x, y, z)`` in 3D."""
    turn = np.asarray(turn, dtype=np.float64)
    if dim == 2:
        c, s = np.cos(turn), np.sin(turn)
        turned: FloatArray = np.stack((np.stack((c, -s), -1), np.stack((s, c), -1)), -2)
        return turned
    return rotation_matrices(turn) if len(turn) else np.zeros((0, 3, 3))


def matrix_quaternion(r: FloatArray) -> FloatArray:
    """The unit quaternion ``(w, x, y, z)``, ``w >= 0``, of a rotation matrix (Shepperd's
    method: the largest of the four squared components decides, for accuracy)."""
    t = float(np.trace(r))
    cases = [t, r[0, 0], r[1, 1], r[2, 2]]
    k = int(np.argmax(cases))
    if k == 0:
        s = 2.0 * math.sqrt(1.0 + t)
        q = [0.25 * s, (r[2, 1] - r[1, 2]) / s, (r[0, 2] - r[2, 0]) / s, (r[1, 0] - r[0, 1]) / s]
    elif k == 1:
        s = 2.0 * math.sqrt(1.0 + r[0, 0] - r[1, 1] - r[2, 2])
        q = [(r[2, 1] - r[1, 2]) / s, 0.25 * s, (r[0, 1] + r[1, 0]) / s, (r[0, 2] + r[2, 0]) / s]
    elif k == 2:
        s = 2.0 * math.sqrt(1.0 + r[1, 1] - r[0, 0] - r[2, 2])
        q = [(r[0, 2] - r[2, 0]) / s, (r[0, 1] + r[1, 0]) / s, 0.25 * s, (r[1, 2] + r[2, 1]) / s]
    else:
        s = 2.0 * math.sqrt(1.0 + r[2, 2] - r[0, 0] - r[1, 1])
        q = [(r[1, 0] - r[0, 1]) / s, (r[0, 2] + r[2, 0]) / s, (r[1, 2] + r[2, 1]) / s, 0.25 * s]
    out = np.array(q)
    out /= np.linalg.norm(out)
    return out if out[0] >= 0.0 else -out


def turn_z_onto(u: FloatArray) -> FloatArray:
    """A rotation taking the z axis onto the unit vector ``u`` (Rodrigues)."""
    z = np.array([0.0, 0.0, 1.0])
    c = float(u @ z)
    if c < -1.0 + 1e-12:
        return np.diag([1.0, -1.0, -1.0])  # half a turn about x
    k = np.cross(z, u)
    skew = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    turn: FloatArray = np.eye(3) + skew + skew @ skew / (1.0 + c)
    return turn


def quaternion_product(a: FloatArray, b: FloatArray) -> FloatArray:
    """Hamilton products ``a b`` of quaternions (..., 4) ``(w, x, y, z)``."""
    aw, ax, ay, az = np.moveaxis(np.asarray(a, float), -1, 0)
    bw, bx, by, bz = np.moveaxis(np.asarray(b, float), -1, 0)
    return np.stack(
        [
            aw * bw - ax * bx - ay * by - az * bz,
            aw * bx + ax * bw + ay * bz - az * by,
            aw * by - ax * bz + ay * bw + az * bx,
            aw * bz + ax * by - ay * bx + az * bw,
        ],
        axis=-1,
    )


def turned_angle(q: FloatArray, q0: FloatArray) -> FloatArray:
    """The angle [rad] (n,) of the rotation from orientations ``q0`` to ``q`` (n, 4)."""
    dot = np.abs(np.sum(np.asarray(q) * np.asarray(q0), axis=1))
    return np.asarray(2.0 * np.arccos(np.clip(dot, 0.0, 1.0)), float)


@njit(cache=True, inline="always")
def matrix(q: np.ndarray, i: int, r: np.ndarray) -> None:
    """Body ``i``'s rotation matrix from its quaternion (row ``i`` of ``q``) into ``r`` (9,),
    row-major."""
    w, x, y, z = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
    r[0] = 1.0 - 2.0 * (y * y + z * z)
    r[1] = 2.0 * (x * y - w * z)
    r[2] = 2.0 * (x * z + w * y)
    r[3] = 2.0 * (x * y + w * z)
    r[4] = 1.0 - 2.0 * (x * x + z * z)
    r[5] = 2.0 * (y * z - w * x)
    r[6] = 2.0 * (x * z - w * y)
    r[7] = 2.0 * (y * z + w * x)
    r[8] = 1.0 - 2.0 * (x * x + y * y)


@njit(cache=True, inline="always")
def axis_angle_matrix(ax: float, ay: float, az: float, out: np.ndarray) -> None:
    """The rotation by the angle ``|a|`` about ``a`` [rad] into ``out`` (9,), row-major
    (Rodrigues)."""
    angle = math.sqrt(ax * ax + ay * ay + az * az)
    out[:] = 0.0
    out[0] = out[4] = out[8] = 1.0
    if angle == 0.0:
        return
    kx, ky, kz = ax / angle, ay / angle, az / angle
    c = math.cos(angle)
    s = math.sin(angle)
    t = 1.0 - c
    out[0] = c + t * kx * kx
    out[1] = t * kx * ky - s * kz
    out[2] = t * kx * kz + s * ky
    out[3] = t * kx * ky + s * kz
    out[4] = c + t * ky * ky
    out[5] = t * ky * kz - s * kx
    out[6] = t * kx * kz - s * ky
    out[7] = t * ky * kz + s * kx
    out[8] = c + t * kz * kz


# Taylor coefficients of cos and sin: (-1)^k / (2k)! and (-1)^k / (2k+1)!
_C2, _C4, _C6, _C8, _C10, _C12 = ((-1.0) ** k / math.factorial(2 * k) for k in range(1, 7))
_S3, _S5, _S7, _S9, _S11, _S13 = ((-1.0) ** k / math.factorial(2 * k + 1) for k in range(1, 7))


@njit(cache=True, inline="always")
def cos_sin(phi: float) -> tuple[float, float]:
    """cos and sin of a turn ``phi`` [rad]. A substep's turn is small: below 1/4 rad the
    Taylor series to phi^12 and phi^13 (each next term below 1e-19 of the result, under half
    an ulp), which costs a dozen multiplications where the library calls cost tens of ns;
    beyond, the library."""
    if abs(phi) >= 0.25:
        return math.cos(phi), math.sin(phi)
    p2 = phi * phi
    c = 1.0 + p2 * (_C2 + p2 * (_C4 + p2 * (_C6 + p2 * (_C8 + p2 * (_C10 + p2 * _C12)))))
    s = phi * (1.0 + p2 * (_S3 + p2 * (_S5 + p2 * (_S7 + p2 * (_S9 + p2 * (_S11 + p2 * _S13))))))
    return c, s
