"""The impulse of one contact point between rigid bodies in 3D, with inertia tensors and
Coulomb friction (Numba kernels): the law the 3D engine's exact impacts apply.

At the contact, body A's point less body B's moves at ``u``; an impulse ``P`` on A (``-P`` on
B) changes it by ``K P``, with the collision matrix (Mirtich 1996, eq. 3.4; Hecker 1997)

    K = (1/m_A + 1/m_B) 1 - [r_A]x I_A^-1 [r_A]x - [r_B]x I_B^-1 [r_B]x,

symmetric and positive definite (``[r]x`` is the cross-product matrix, ``I^-1`` world-frame
inverse inertia tensors, ``r`` from each centre of mass to the point). The normal ``n`` runs
from B to A, so the bodies approach when ``u . n < 0``. Newton's restitution asks the normal
velocity after to be ``-e u_n``; friction:

- *sticking*: the impulse that also stops the slip, ``P = K^-1 (-(1 + e) u_n n - u_t)``, if it
  lies in the cone ``|P_t| <= mu P_n`` and gains no energy;
- else *sliding*: ``P = j (n - mu t)`` against the slip direction ``t = u_t/|u_t|``, with ``j``
  from Newton's law along ``n``. Exact when the slip keeps its direction through the impact
  (a sphere, a body whose ``K`` has ``n`` as an axis); otherwise this is the common
  approximation of a constant slip direction (Routh's method follows its turning;
  Stronge, *Impact Mechanics*, 2000, ch. 5);
- should either gain energy (Kane's paradox), the normal impulse alone, then the tangent
  impulse that removes the most energy for it, clamped to the cone: never a gain, though
  through ``K``'s coupling the normal velocity may then leave a little off ``-e u_n``.

A ball of radius R landing on the floor with spin, sticking, leaves with the tangential
velocity ``(5 v_t + 2 R omega x n)/7`` of the rolling rule; frictionless, ``P`` is Hecker's
``j n``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

__all__ = ["collision_matrix", "point_impulse"]


@njit(cache=True, inline="always")
def _skew_sandwich(inv_inertia: np.ndarray, r: np.ndarray, k: np.ndarray) -> None:
    """``k -= [r]x I^-1 [r]x`` (3, 3)."""
    # [r]x = [[0, -rz, ry], [rz, 0, -rx], [-ry, rx, 0]]
    s = np.zeros((3, 3))
    s[0, 1], s[0, 2] = -r[2], r[1]
    s[1, 0], s[1, 2] = r[2], -r[0]
    s[2, 0], s[2, 1] = -r[1], r[0]
    for i in range(3):
        for j in range(3):
            total = 0.0
            for a in range(3):
                for b in range(3):
                    total += s[i, a] * inv_inertia[a, b] * s[b, j]
            k[i, j] -= total


@njit(cache=True)
def collision_matrix(
    inv_mass_a: float, inv_inertia_a: np.ndarray, r_a: np.ndarray,
    inv_mass_b: float, inv_inertia_b: np.ndarray, r_b: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """``K`` (3, 3) of a contact point (module docstring): velocity change of A's point less
    B's per unit impulse on A [1/kg]. A static body has zero inverse mass and tensor."""
    k = np.eye(3) * (inv_mass_a + inv_mass_b)
    _skew_sandwich(inv_inertia_a, r_a, k)
    _skew_sandwich(inv_inertia_b, r_b, k)
    return 0.5 * (k + k.T)


@njit(cache=True)
def point_impulse(u: np.ndarray, n: np.ndarray, k: np.ndarray, e: float, mu: float) -> np.ndarray:
    """The impulse ``P`` (3,) [N s] on body A at the contact point (``-P`` on B).

    Parameters
    ----------
    u : (3,) float64
        Velocity of A's contact point less B's, before [m/s].
    n : (3,) float64
        Unit normal from B to A.
    k : (3, 3) float64
        The collision matrix (:func:`collision_matrix`) [1/kg].
    e, mu : float
        Restitution and friction coefficients [-].

    Returns
    -------
    (3,) float64
        Zero when the points are not approaching (``u . n >= 0``).
    """
    un = _dot(u, n)
    if un >= 0.0:
        return np.zeros(3)
    ut = u - un * n
    target = -(1.0 + e) * un  # the normal velocity change Newton asks for
    if mu > 0.0:
        stick = _solve3(k, target * n - ut)
        pn = _dot(stick, n)
        pt = stick - pn * n
        if pn >= 0.0 and math.sqrt(_dot(pt, pt)) <= mu * pn and _gain(stick, u, k) <= 0.0:
            return stick
        # against the slip; with no slip, against the way the sticking impulse would push
        slip = ut if _dot(ut, ut) > 0.0 else -pt
        size = math.sqrt(_dot(slip, slip))
        t = slip / size if size > 0.0 else slip
        direction = n - mu * t
        denominator = _dot(n, _times(k, direction))
        if denominator > 0.0:
            slide: np.ndarray = (target / denominator) * direction
            if _gain(slide, u, k) <= 0.0:
                return slide
    jn = target / _dot(n, _times(k, n))
    p: np.ndarray = jn * n
    if mu == 0.0:
        return p
    # for that normal impulse, the tangent impulse that removes the most energy (stops the
    # slip as far as the tangent block of K allows), clamped to the cone
    t1, t2 = _tangents(n)
    after = u + _times(k, p)
    r1 = -_dot(t1, after)
    r2 = -_dot(t2, after)
    a11 = _dot(t1, _times(k, t1))
    a12 = _dot(t1, _times(k, t2))
    a22 = _dot(t2, _times(k, t2))
    det = a11 * a22 - a12 * a12
    x1 = (a22 * r1 - a12 * r2) / det
    x2 = (a11 * r2 - a12 * r1) / det
    size = math.sqrt(x1 * x1 + x2 * x2)
    if size > mu * jn:
        x1 *= mu * jn / size
        x2 *= mu * jn / size
    total: np.ndarray = p + x1 * t1 + x2 * t2
    return total


@njit(cache=True)
def _solve3(k: np.ndarray, b: np.ndarray) -> np.ndarray:
    """``K^-1 b`` for a symmetric positive definite (3, 3) ``K``, by its adjugate (no LAPACK:
    the core needs nothing beyond NumPy and Numba)."""
    c00 = k[1, 1] * k[2, 2] - k[1, 2] * k[2, 1]
    c01 = k[1, 2] * k[2, 0] - k[1, 0] * k[2, 2]
    c02 = k[1, 0] * k[2, 1] - k[1, 1] * k[2, 0]
    c11 = k[0, 0] * k[2, 2] - k[0, 2] * k[2, 0]
    c12 = k[0, 1] * k[2, 0] - k[0, 0] * k[2, 1]
    c22 = k[0, 0] * k[1, 1] - k[0, 1] * k[1, 0]
    det = k[0, 0] * c00 + k[0, 1] * c01 + k[0, 2] * c02
    x = np.empty(3)
    # K is symmetric, so its adjugate is too: c10 = c01, c20 = c02, c21 = c12
    x[0] = (c00 * b[0] + c01 * b[1] + c02 * b[2]) / det
    x[1] = (c01 * b[0] + c11 * b[1] + c12 * b[2]) / det
    x[2] = (c02 * b[0] + c12 * b[1] + c22 * b[2]) / det
    return x


@njit(cache=True, inline="always")
def _gain(p: np.ndarray, u: np.ndarray, k: np.ndarray) -> float:
    """Kinetic energy an impulse ``p`` adds [J]: ``p . u + p . K p / 2``."""
    gain: float = _dot(p, u) + 0.5 * _dot(p, _times(k, p))
    return gain


@njit(cache=True, inline="always")
def _dot(u: np.ndarray, v: np.ndarray) -> float:
    """u . v of two (3,) vectors (not "@": Numba's "@" calls BLAS through SciPy, and the
    core needs nothing beyond NumPy and Numba)."""
    total: float = u[0] * v[0] + u[1] * v[1] + u[2] * v[2]
    return total


@njit(cache=True, inline="always")
def _times(k: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``K v`` for a (3, 3) matrix and a (3,) vector."""
    out = np.empty(3)
    for i in range(3):
        out[i] = k[i, 0] * v[0] + k[i, 1] * v[1] + k[i, 2] * v[2]
    return out


@njit(cache=True)
def _tangents(n: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Two unit vectors completing ``n`` to a right-handed frame."""
    a = np.array([1.0, 0.0, 0.0]) if abs(n[0]) < 0.9 else np.array([0.0, 1.0, 0.0])
    t1 = np.cross(n, a)
    t1 /= math.sqrt(_dot(t1, t1))
    return t1, np.cross(n, t1)
