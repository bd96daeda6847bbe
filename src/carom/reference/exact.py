"""The smooth-sphere law in exact rational arithmetic.

For float inputs the post-impact velocities of PHYSICS.md section 1 are rational functions of
the inputs: with ``r = x1 - x2`` the normal enters only as ``n n^T = r r^T / (r . r)``,

    v1' = v1 - (1 + e) m2 / (m1 + m2) * ((v1 - v2) . r) / (r . r) * r
    v2' = v2 + (1 + e) m1 / (m1 + m2) * ((v1 - v2) . r) / (r . r) * r,

so :class:`fractions.Fraction` evaluates them with no rounding at all; the result is rounded to
float64 once. This is the "exact answer" the seven-case study and the tests measure against.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from fractions import Fraction

__all__ = ["smooth_exact"]

Vector = tuple[Fraction, ...]


def _vec(values: Sequence[float]) -> Vector:
    return tuple(Fraction(float(c)) for c in values)


def _dot(a: Vector, b: Vector) -> Fraction:
    return sum((p * q for p, q in zip(a, b, strict=True)), Fraction(0))


def smooth_exact(
    x1: Sequence[float],
    v1: Sequence[float],
    m1: float,
    x2: Sequence[float],
    v2: Sequence[float],
    m2: float,
    e: float,
) -> tuple[tuple[float, ...], tuple[float, ...], float]:
    """Exact post-impact velocities of two smooth spheres, and the kinetic energy lost.

    Parameters
    ----------
    x1, v1, x2, v2 : sequence of float, length d
        Centres [m] and velocities [m/s] at the instant of impact.
    m1, m2 : float
        Masses [kg]; ``math.inf`` for a static body (not both).
    e : float
        Coefficient of restitution in [0, 1] [-].

    Returns
    -------
    v1_after, v2_after : tuple of float
        Velocities after the impact [m/s], each correctly rounded from the exact value.
    ke_lost : float
        ``1/2 mu (1 - e^2) u^2`` [J], correctly rounded; zero when the pair is not approaching.

    Examples
    --------
    >>> smooth_exact([0, 0], [1, 0], 1.0, [1, 0], [0, 0], 3.0, 1.0)
    ((-0.5, 0.0), (0.5, 0.0), 0.0)
    """
    r = tuple(a - b for a, b in zip(_vec(x1), _vec(x2), strict=True))
    va, vb = _vec(v1), _vec(v2)
    v_rel = tuple(a - b for a, b in zip(va, vb, strict=True))
    ef = Fraction(float(e))
    rr = _dot(r, r)
    ur = _dot(v_rel, r)  # u |r|
    if ur >= 0:
        return tuple(map(float, va)), tuple(map(float, vb)), 0.0
    # share of the relative-velocity change taken by each body: m2/(m1+m2) and m1/(m1+m2)
    if math.isinf(m2):
        share1, share2, mu = Fraction(1), Fraction(0), Fraction(float(m1))
    elif math.isinf(m1):
        share1, share2, mu = Fraction(0), Fraction(1), Fraction(float(m2))
    else:
        fm1, fm2 = Fraction(float(m1)), Fraction(float(m2))
        share1, share2, mu = fm2 / (fm1 + fm2), fm1 / (fm1 + fm2), fm1 * fm2 / (fm1 + fm2)
    k = (1 + ef) * ur / rr
    v1_after = tuple(float(a - share1 * k * c) for a, c in zip(va, r, strict=True))
    v2_after = tuple(float(b + share2 * k * c) for b, c in zip(vb, r, strict=True))
    # u^2 = (ur)^2 / rr, still rational
    ke_lost = Fraction(1, 2) * mu * (1 - ef * ef) * ur * ur / rr
    return v1_after, v2_after, float(ke_lost)
