"""The two-sphere laws of :func:`carom.collide` as one Numba pass over a batch.

:func:`collide_rows` reads each pair's inputs once, checks them, applies the law and writes
every field of the :class:`~carom.laws.spheres.CollisionResult` in the same pass: no NumPy
temporaries, so a batch costs about what its inputs and outputs take to move through memory.
The arithmetic is that of the NumPy laws it replaced (commit d294db6) operation for operation
(same order, no fused multiply-adds): every field agreed to the bit when it replaced them.
Tests hold a pair alone to the same pair in a batch, on any number of threads.

Inputs are C-contiguous float64 arrays whose first axis has length ``n`` or 1; a length of 1
is broadcast (row stride 0). Vectors are ``(k, d)``, per-pair scalars ``(k,)``, spins
``(k, 1)`` in 2D and ``(k, 3)`` in 3D.

The check is deliberately the simple one: a pair is flagged when any input lies outside the
range :func:`carom.collide` accepts, when both masses are infinite, or when the centres
coincide. The caller then runs the full argument checks, which name what is wrong and where.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from carom.laws.kernels import LAW_SMOOTH, LAW_WALTON

# carom.limits' bounds, repeated here because a kernel's constants must live in the kernel
# packages (their hash names the cache); a test holds the two equal
LARGEST = 1e100  # beyond it, products of three overflow
SMALLEST = 1e-100  # below it, a positive size underflows

BLOCK = 4096  # pairs per task of the threads


@njit(cache=True, error_model="numpy")
def _dot(a0: float, a1: float, a2: float, b0: float, b1: float, b2: float, d3: bool) -> float:
    """``a . b`` summed in the order of :func:`carom._inputs.dot`."""
    s = a0 * b0 + a1 * b1
    if d3:
        s = s + a2 * b2
    return s


@njit(cache=True, error_model="numpy")
def _kinetic(
    m: float,
    v0: float,
    v1: float,
    v2: float,
    w0: float,
    w1: float,
    w2: float,
    radius: float,
    q: float,
    d3: bool,
    spins: bool,
) -> float:
    """``1/2 m |v|^2 (+ 1/2 q m a^2 |w|^2)`` in the order of ``spheres.kinetic_energy``."""
    m_f = m if math.isfinite(m) else 0.0
    ke = 0.5 * m_f * _dot(v0, v1, v2, v0, v1, v2, d3)
    if spins:
        w_squared = _dot(w0, w1, w2, w0, w1, w2, True) if d3 else w0 * w0
        ke = ke + 0.5 * q * m_f * radius * radius * w_squared
    return ke


@njit(cache=True, error_model="numpy")
def _spin_cross(
    s: float, w0: float, w1: float, w2: float, n0: float, n1: float, n2: float, d3: bool
) -> tuple[float, float, float]:
    """``(s w) x n``: in 2D ``w0`` is the spin about z and the result lies in the plane."""
    if d3:
        a0, a1, a2 = s * w0, s * w1, s * w2
        return a1 * n2 - a2 * n1, a2 * n0 - a0 * n2, a0 * n1 - a1 * n0
    a = s * w0
    return -a * n1, a * n0, 0.0


@njit(cache=True, error_model="numpy")
def _out(x: float, low: float, high: float) -> bool:
    """True unless ``low <= x <= high`` (NaN is out of every range); no branch."""
    return not ((x >= low) & (x <= high))


@njit(cache=True, error_model="numpy")
def _huge(x0: float, x1: float, x2: float) -> bool:
    """True if a component is not a number or beyond ``LARGEST`` in size."""
    return _out(x0, -LARGEST, LARGEST) | _out(x1, -LARGEST, LARGEST) | _out(x2, -LARGEST, LARGEST)


@njit(cache=True, error_model="numpy", parallel=True)
def collide_rows(
    x1: np.ndarray,
    v1: np.ndarray,
    m1: np.ndarray,
    x2: np.ndarray,
    v2: np.ndarray,
    m2: np.ndarray,
    e: np.ndarray,
    w1: np.ndarray,
    w2: np.ndarray,
    radius1: np.ndarray,
    radius2: np.ndarray,
    beta: np.ndarray,
    friction: np.ndarray,
    law: int,
    spins: bool,
    q1: float,
    q2: float,
    out_v1: np.ndarray,
    out_v2: np.ndarray,
    out_w1: np.ndarray,
    out_w2: np.ndarray,
    out_impulse: np.ndarray,
    out_normal: np.ndarray,
    out_approach: np.ndarray,
    out_separation: np.ndarray,
    out_relative: np.ndarray,
    out_ke_before: np.ndarray,
    out_ke_after: np.ndarray,
    out_ke_lost: np.ndarray,
    out_beta: np.ndarray,
    out_applied: np.ndarray,
) -> int:
    """Apply the law to every pair; return the index of the first refused pair, or -1.

    ``beta`` holds the constant tangential restitution (``LAW_ROUGH``) or Walton's ``beta0``
    (``LAW_WALTON``). The outputs are the fields of a ``CollisionResult``. ``out_w1``,
    ``out_w2`` are written only with ``spins`` and ``out_beta`` only for the rough laws.
    After a refused pair the outputs are meaningless. Blocks of pairs run on Numba's
    threads; each pair is computed alone, so the bits do not depend on the thread count.
    """
    n = out_v1.shape[0]
    d3 = x1.shape[1] == 3
    # an input of one row is broadcast: its row is i * 0
    sx1, sv1, sx2, sv2 = x1.shape[0] > 1, v1.shape[0] > 1, x2.shape[0] > 1, v2.shape[0] > 1
    sm1, sm2, se = m1.shape[0] > 1, m2.shape[0] > 1, e.shape[0] > 1
    sw1, sw2 = w1.shape[0] > 1, w2.shape[0] > 1
    sr1, sr2 = radius1.shape[0] > 1, radius2.shape[0] > 1
    sb, sf = beta.shape[0] > 1, friction.shape[0] > 1
    blocks = (n + BLOCK - 1) // BLOCK
    first = np.empty(blocks, dtype=np.int64)  # the first refused pair of each block, or n
    for block in prange(blocks):
        bad = n
        for i in range(block * BLOCK, min(n, (block + 1) * BLOCK)):
            ix1, iv1, ix2, iv2 = i * sx1, i * sv1, i * sx2, i * sv2
            im1, im2, ie = i * sm1, i * sm2, i * se
            iw1, iw2, ir1, ir2, ib, i_f = i * sw1, i * sw2, i * sr1, i * sr2, i * sb, i * sf
            a0, a1 = x1[ix1, 0], x1[ix1, 1]
            b0, b1 = x2[ix2, 0], x2[ix2, 1]
            p0, p1 = v1[iv1, 0], v1[iv1, 1]
            s0, s1 = v2[iv2, 0], v2[iv2, 1]
            a2 = x1[ix1, 2] if d3 else 0.0
            b2 = x2[ix2, 2] if d3 else 0.0
            p2 = v1[iv1, 2] if d3 else 0.0
            s2 = v2[iv2, 2] if d3 else 0.0
            mass1 = m1[im1]
            mass2 = m2[im2]
            ei = e[ie]
            refused = (
                _huge(a0, a1, a2)
                | _huge(b0, b1, b2)
                | _huge(p0, p1, p2)
                | _huge(s0, s1, s2)
                | ((mass1 != math.inf) & _out(mass1, SMALLEST, LARGEST))
                | ((mass2 != math.inf) & _out(mass2, SMALLEST, LARGEST))
                | ((mass1 == math.inf) & (mass2 == math.inf))
                | _out(ei, 0.0, 1.0)
            )

            r0, r1, r2 = a0 - b0, a1 - b1, a2 - b2
            dist2 = _dot(r0, r1, r2, r0, r1, r2, d3)
            refused = refused | (dist2 == 0.0)
            # a refused pair (centres together, both masses infinite) must not divide by zero:
            # in plain Python (NUMBA_DISABLE_JIT) that raises; an accepted pair is untouched
            root = math.sqrt(dist2) if dist2 > 0.0 else 1.0
            n0, n1, n2 = r0 / root, r1 / root, r2 / root
            inv_m1 = 0.0 if math.isinf(mass1) else 1.0 / mass1
            inv_m2 = 0.0 if math.isinf(mass2) else 1.0 / mass2
            inv_sum = inv_m1 + inv_m2
            mu = 1.0 / inv_sum if inv_sum > 0.0 else 0.0
            g0, g1, g2 = p0 - s0, p1 - s1, p2 - s2  # v1 - v2
            u = _dot(g0, g1, g2, n0, n1, n2, d3)
            applied = u < 0.0
            u_in = u if applied else 0.0
            jn = -(1.0 + ei) * mu * u_in
            j0, j1, j2 = jn * n0, jn * n1, jn * n2
            ke_lost = 0.5 * mu * (1.0 - ei * ei) * u_in * u_in

            w10 = w11 = w12 = w20 = w21 = w22 = rad1 = rad2 = 0.0
            if spins:
                w10 = w1[iw1, 0]
                w20 = w2[iw2, 0]
                if d3:
                    w11, w12 = w1[iw1, 1], w1[iw1, 2]
                    w21, w22 = w2[iw2, 1], w2[iw2, 2]
                rad1 = radius1[ir1]
                rad2 = radius2[ir2]
                refused = (
                    refused
                    | _huge(w10, w11, w12)
                    | _huge(w20, w21, w22)
                    | _out(rad1, SMALLEST, LARGEST)
                    | _out(rad2, SMALLEST, LARGEST)
                )

            if law != LAW_SMOOTH:
                bi = beta[ib]
                refused = refused | _out(bi, -1.0, 1.0)
                c10, c11, c12 = _spin_cross(rad1, w10, w11, w12, n0, n1, n2, d3)
                c20, c21, c22 = _spin_cross(rad2, w20, w21, w22, n0, n1, n2, d3)
                h0, h1, h2 = g0 - c10 - c20, g1 - c11 - c21, g2 - c12 - c22
                gn = _dot(h0, h1, h2, n0, n1, n2, d3)
                t0, t1, t2 = h0 - gn * n0, h1 - gn * n1, h2 - gn * n2
                g_t2 = _dot(t0, t1, t2, t0, t1, t2, d3)
                g_t = math.sqrt(g_t2)
                inv_mu_t = inv_m1 * (1.0 + 1.0 / q1) + inv_m2 * (1.0 + 1.0 / q2)
                mu_t = 1.0 / inv_mu_t if inv_mu_t > 0.0 else 1.0
                # Work with 1 + beta and 1 - beta, never beta itself: in a sliding contact
                # with |g_t| >> |g_n| the Coulomb cap puts beta within a hair of -1, and
                # forming -1 + x then 1 + beta would cancel most of x's digits (seen: 2.6e-12
                # relative excess over mu_f |J_n|); near beta = +1, 1 + beta rounds to 2 and
                # 1 - beta^2 would vanish.
                one_plus_beta, one_minus_beta, beta_used = 1.0 + bi, 1.0 - bi, bi
                if law == LAW_WALTON:
                    fi = friction[i_f]
                    refused = refused | _out(fi, 0.0, LARGEST)
                    # Coulomb: |J_t| = (1 + beta) mu_t |g_t| <= mu_f (1 + e) mu |g_n|
                    cap = fi * (1.0 + ei) * (mu / mu_t) * (-u_in) / g_t
                    capped = (g_t > 0.0) & (cap < one_plus_beta)
                    one_plus_beta = cap if capped else one_plus_beta
                    one_minus_beta = 2.0 - cap if capped else one_minus_beta
                    beta_used = cap - 1.0 if capped else beta_used
                one_plus_beta = one_plus_beta if applied else 0.0
                kt = one_plus_beta * mu_t
                j0, j1, j2 = j0 - kt * t0, j1 - kt * t1, j2 - kt * t2
                ke_lost = ke_lost + 0.5 * mu_t * one_plus_beta * one_minus_beta * g_t2
                out_beta[i] = beta_used

            y0, y1, y2 = p0 + j0 * inv_m1, p1 + j1 * inv_m1, p2 + j2 * inv_m1  # v1 after
            z0, z1, z2 = s0 - j0 * inv_m2, s1 - j1 * inv_m2, s2 - j2 * inv_m2  # v2 after
            out_v1[i, 0], out_v1[i, 1] = y0, y1
            out_v2[i, 0], out_v2[i, 1] = z0, z1
            out_impulse[i, 0], out_impulse[i, 1] = j0, j1
            out_normal[i, 0], out_normal[i, 1] = n0, n1
            if d3:
                out_v1[i, 2], out_v2[i, 2] = y2, z2
                out_impulse[i, 2], out_normal[i, 2] = j2, n2

            o10 = o11 = o12 = o20 = o21 = o22 = 0.0  # spins after
            if spins:
                if d3:
                    k0, k1, k2 = n1 * j2 - n2 * j1, n2 * j0 - n0 * j2, n0 * j1 - n1 * j0
                else:
                    k0, k1, k2 = n0 * j1 - n1 * j0, 0.0, 0.0
                f1 = inv_m1 / (q1 * rad1)
                f2 = inv_m2 / (q2 * rad2)
                o10, o11, o12 = w10 - f1 * k0, w11 - f1 * k1, w12 - f1 * k2
                o20, o21, o22 = w20 - f2 * k0, w21 - f2 * k1, w22 - f2 * k2
                out_w1[i, 0], out_w2[i, 0] = o10, o20
                if d3:
                    out_w1[i, 1], out_w1[i, 2] = o11, o12
                    out_w2[i, 1], out_w2[i, 2] = o21, o22

            c0, c1, c2 = y0 - z0, y1 - z1, y2 - z2  # relative velocity after
            out_approach[i] = -u
            out_separation[i] = _dot(c0, c1, c2, n0, n1, n2, d3)
            out_relative[i] = math.sqrt(_dot(c0, c1, c2, c0, c1, c2, d3))
            out_ke_before[i] = _kinetic(
                mass1, p0, p1, p2, w10, w11, w12, rad1, q1, d3, spins
            ) + _kinetic(mass2, s0, s1, s2, w20, w21, w22, rad2, q2, d3, spins)
            out_ke_after[i] = _kinetic(
                mass1, y0, y1, y2, o10, o11, o12, rad1, q1, d3, spins
            ) + _kinetic(mass2, z0, z1, z2, o20, o21, o22, rad2, q2, d3, spins)
            out_ke_lost[i] = ke_lost
            out_applied[i] = applied
            bad = min(bad, i if refused else n)
        first[block] = bad
    bad = n
    for block in range(blocks):
        bad = min(bad, first[block])
    return -1 if bad == n else bad
