"""The two-body impulse laws as Numba kernels: the twins of :func:`carom.collide`.

Vectors are handled as three scalar components; 2D problems pass a zero third component and
keep spins along z, so one kernel serves both dimensions (a 2D spin ``w`` is ``(0, 0, w)`` and
the 3D cross products reduce to the 2D ones). The formulas and their derivation are those of
:mod:`carom.laws.spheres` and PHYSICS.md sections 1 and 3; tests hold the two against each other.
"""

from __future__ import annotations

import math

from carom.jit import kernel_only

LAW_SMOOTH = 0
LAW_ROUGH = 1  # constant tangential restitution beta
LAW_WALTON = 2  # Coulomb friction mu_f with sticking restitution beta0


@kernel_only(error_model="numpy")
def impulse_spheres(
    n0: float,
    n1: float,
    n2: float,
    g0: float,
    g1: float,
    g2: float,
    inv_m1: float,
    inv_m2: float,
    e: float,
    law: int,
    beta: float,
    friction: float,
    inv_q1: float,
    inv_q2: float,
) -> tuple[float, float, float]:
    """Impulse on body 1 [N s] for unit normal ``n`` (from 2 to 1).

    ``g`` is the contact-point relative velocity ``v1 - v2 - (a1 w1 + a2 w2) x n`` (for the
    smooth law ``v1 - v2`` is enough: spin adds nothing along ``n``). ``inv_q`` are ``1/q``.
    ``beta`` is the constant restitution for ``LAW_ROUGH`` and ``beta0`` for ``LAW_WALTON``.
    Returns zero unless the pair approaches, ``g . n < 0``.
    """
    u = g0 * n0 + g1 * n1 + g2 * n2
    if u >= 0.0:
        return 0.0, 0.0, 0.0
    mu = 1.0 / (inv_m1 + inv_m2)
    jn = -(1.0 + e) * mu * u
    j0, j1, j2 = jn * n0, jn * n1, jn * n2
    if law == LAW_SMOOTH:
        return j0, j1, j2
    t0, t1, t2 = g0 - u * n0, g1 - u * n1, g2 - u * n2
    inv_mu_t = inv_m1 * (1.0 + inv_q1) + inv_m2 * (1.0 + inv_q2)
    mu_t = 1.0 / inv_mu_t
    one_plus_beta = 1.0 + beta
    if law == LAW_WALTON:
        g_t = math.sqrt(t0 * t0 + t1 * t1 + t2 * t2)
        if g_t > 0.0:
            # Coulomb cap on 1 + beta, computed directly (no cancellation, see response.py)
            cap = friction * (1.0 + e) * (mu / mu_t) * (-u) / g_t
            if cap < one_plus_beta:
                one_plus_beta = cap
    k = one_plus_beta * mu_t
    return j0 - k * t0, j1 - k * t1, j2 - k * t2
