"""3D joints in the soft step: spherical, revolute (a hinge), prismatic, distance, fixed and
target, as the 2D ones (:mod:`carom.engines.rigid.joints`, Box2D v3's formulation) in three
dimensions.

Every constraint is built from two pieces. A **point** holds B's anchor on A's (a 3x3 block:
``K = (m_A + m_B) 1 - [r_A] I_A^-1 [r_A] - [r_B] I_B^-1 [r_B]`` with ``[r]`` the cross-product
matrix and ``I^-1`` the world inverse inertia at the step's start, as the contacts take it).
A **row** is one scalar constraint with speed ``u . (v_B - v_A) + s_B . w_B - s_A . w_A``: a
direction ``u`` with its angular levers (a rod's line, ``s = r x u``; a slider's sideways and
axial directions fixed in A, ``s_A = (d + r_A) x u``, ``s_B = r_B x u``) or a pure turn about an
axis (``u = 0``, ``s_A = s_B = axis``). Rows are solved one after another (Gauss-Seidel), soft
with the bias and rigid in the relax pass, limits one-sided and speculative, motors capped at
their largest force or torque times ``h``.

Angles: a hinge keeps B's axis along A's by two rows about ``a_B x b`` and ``a_B x c`` (``b``,
``c`` square to A's axis), whose errors are ``a_B . b`` and ``a_B . c``; its angle about the
axis is ``atan2((p_A x p_B) . a_A, p_A . p_B)`` between reference directions square to it, one
fixed in each body (so its limits lie within a turn). A fixed joint and a slider hold the
relative orientation: the error is the rotation vector's small-angle part of
``E = R_B R_ref^T R_A^T``, ``(E - E^T)^vee / 2``, along three rows about the world axes.

Within the step the bodies' moves and turns come from the solver's state (the turn as a
matrix ``T`` since the step's start), so ``r = T r_0`` and ``R = T R_0``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.stepped.joints import (
    DISTANCE,
    FLAG_LIMIT,
    FLAG_MOTOR,
    FLAG_SPRING,
    J_A,
    J_FLAGS,
    J_KIND,
    PRISMATIC,
    REVOLUTE,
    SPHERICAL,
    TARGET,
    WELD,
)
from carom.engines.stepped.solver import softness
from carom.geometry.rotation import matrix
from carom.jit import leaf

__all__ = ["JOINT_FLOATS", "prepare", "reactions", "solve", "warm_start"]

# the float columns of a 3D joint row: what the joint is ...
LA = 0  # anchor on A from its centre of mass, in A's frame (3) [m] (the world's: a point)
LB = 3  # anchor on B, in B's frame (3) [m]
AXA = 6  # the axis in A's frame (3): a hinge's, a slider's
AXB = 9  # the hinge's axis in B's frame (3)
PA = 12  # a direction square to the axis in A's frame (3): a hinge's angle is measured
PB = 15  # from it to B's (3), the same direction when the joint was made
QREF = 18  # B's orientation in A's frame when the joint was made (4: w, x, y, z)
LENGTH = 22  # a distance joint's length [m]
LOWER, UPPER = 23, 24  # limits: an angle [rad] (hinge), a travel or a length [m]
MOTOR_SPEED, MAX_MOTOR = 25, 26  # [rad/s] or [m/s]; [N m] or [N]
HERTZ, DAMPING = 27, 28  # the joint's spring (a fixed joint's linear one)
MAX_FORCE = 29  # the target joint's largest pull [N]
ANG_HERTZ, ANG_DAMPING = 30, 31  # a fixed joint's angular spring (0 Hz: rigid)
# ... the impulses it accumulated ...
JP = 32  # the point's (3) [N s]
JANG = 35  # the angular rows' (3): a hinge's two, a lock's three [N m s]
JSIDE = 38  # a slider's two sideways rows [N s]
JAXIAL, JLOWER, JUPPER, JMOTOR, JSPRING = 40, 41, 42, 43, 44
# ... and its reaction on B after the last step
FORCE = 45  # (3) [N]
TORQUE = 48  # the couple beyond the force's moment (3) [N m]
JOINT_FLOATS = 51

#: a 3-vector as a tuple
Vec3 = tuple[float, float, float]

# the columns of a body's row in the 3D solver's state (:mod:`.solver`)
S_V, S_W, S_D, S_T = 0, 3, 6, 9

# what a step prepares for each active joint: the centres, anchors, axes and reference
# directions at the step's start in the world, the relative-orientation map, inverse masses
# and world inverse inertias, and the soft scales of its own springs
W_XA, W_XB, W_RA, W_RB, W_AA, W_AB, W_PA, W_PB = 0, 3, 6, 9, 12, 15, 18, 21
W_M = 24  # M_0 = R_B0 R_ref^T R_A0^T (9): E = T_B M_0 T_A^T
W_MA, W_MB = 33, 34
W_IA, W_IB = 35, 44  # (9 each)
W_SOFT = 53  # the joint's spring (rate, mass scale, impulse scale)
W_ASOFT = 56  # the fixed joint's angular spring
PREPARED = 59


@njit(cache=True, inline="always")
def _turn(t: np.ndarray, r: int, o: int, v: np.ndarray, p: int) -> tuple[float, float, float]:
    """Row ``r`` of ``t`` from column ``o``, a matrix (9, row-major), times ``v[p:p+3]``."""
    return (
        t[r, o] * v[p] + t[r, o + 1] * v[p + 1] + t[r, o + 2] * v[p + 2],
        t[r, o + 3] * v[p] + t[r, o + 4] * v[p + 1] + t[r, o + 5] * v[p + 2],
        t[r, o + 6] * v[p] + t[r, o + 7] * v[p + 1] + t[r, o + 8] * v[p + 2],
    )


@njit(cache=True, inline="always")
def _cross(
    a: tuple[float, float, float], b: tuple[float, float, float]
) -> tuple[float, float, float]:
    return (a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


@njit(cache=True, inline="always")
def _dot(a: tuple[float, float, float], b: tuple[float, float, float]) -> float:
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]


@njit(cache=True, inline="always")
def _apply_inertia(
    prep: np.ndarray, k: int, o: int, v: tuple[float, float, float]
) -> tuple[float, float, float]:
    """The world inverse inertia ``prep[k, o:o+9]`` times ``v``."""
    return (
        prep[k, o] * v[0] + prep[k, o + 1] * v[1] + prep[k, o + 2] * v[2],
        prep[k, o + 3] * v[0] + prep[k, o + 4] * v[1] + prep[k, o + 5] * v[2],
        prep[k, o + 6] * v[0] + prep[k, o + 7] * v[1] + prep[k, o + 8] * v[2],
    )


@njit(cache=True)
def prepare(
    jf: np.ndarray, ji: np.ndarray, active: np.ndarray, x: np.ndarray, q: np.ndarray,
    inv_mass: np.ndarray, iw: np.ndarray, h: float,
) -> tuple[np.ndarray, np.ndarray]:  # fmt: skip
    """What the substeps read of the joints ``active`` (k,) at the step's start (``iw`` (N, 9):
    the world inverse inertias): the prepared rows (k, PREPARED) and each joint's two rows of
    the solver's state (k, 2), the world's the last (the dummy)."""
    n = x.shape[0]
    prep = np.zeros((active.shape[0], PREPARED))
    rows = np.empty((active.shape[0], 2), np.int64)
    r = np.empty((2, 9))
    for k in range(active.shape[0]):
        j = active[k]
        for side in range(2):
            body = ji[j, J_A + side]
            r[side, :] = 0.0
            r[side, 0] = r[side, 4] = r[side, 8] = 1.0
            if body < 0:
                rows[k, side] = n
                continue
            rows[k, side] = body
            matrix(q, body, r[side])
            for c in range(3):
                prep[k, W_XA + 3 * side + c] = x[body, c]
            prep[k, W_MA + side] = inv_mass[body]
            for c in range(9):
                prep[k, W_IA + 9 * side + c] = iw[body, c]
        for side, (local, out) in enumerate(((LA, W_RA), (LB, W_RB))):
            v = _turn(r, side, 0, jf[j], local)
            for c in range(3):
                prep[k, out + c] = v[c]
        for side, local, out in ((0, AXA, W_AA), (1, AXB, W_AB), (0, PA, W_PA), (1, PB, W_PB)):
            v = _turn(r, side, 0, jf[j], local)
            for c in range(3):
                prep[k, out + c] = v[c]
        # M_0 = R_B0 R_ref^T R_A0^T, with R_ref B's orientation in A's frame when made
        ref = np.empty((1, 9))
        qr = np.empty((1, 4))
        for c in range(4):
            qr[0, c] = jf[j, QREF + c]
        matrix(qr, 0, ref[0])
        bt = np.zeros(9)  # R_B0 R_ref^T
        for a in range(3):
            for c in range(3):
                bt[3 * a + c] = (
                    r[1, 3 * a] * ref[0, 3 * c] + r[1, 3 * a + 1] * ref[0, 3 * c + 1]
                    + r[1, 3 * a + 2] * ref[0, 3 * c + 2]
                )  # fmt: skip
        for a in range(3):
            for c in range(3):
                prep[k, W_M + 3 * a + c] = (
                    bt[3 * a] * r[0, 3 * c] + bt[3 * a + 1] * r[0, 3 * c + 1]
                    + bt[3 * a + 2] * r[0, 3 * c + 2]
                )  # fmt: skip
        if jf[j, HERTZ] > 0.0:
            rate, ms, iscale = softness(jf[j, HERTZ], jf[j, DAMPING], h)
            prep[k, W_SOFT], prep[k, W_SOFT + 1], prep[k, W_SOFT + 2] = rate, ms, iscale
        if jf[j, ANG_HERTZ] > 0.0:
            rate, ms, iscale = softness(jf[j, ANG_HERTZ], jf[j, ANG_DAMPING], h)
            prep[k, W_ASOFT], prep[k, W_ASOFT + 1], prep[k, W_ASOFT + 2] = rate, ms, iscale
    return prep, rows


@njit(cache=True, inline="always")
def _vec(prep: np.ndarray, k: int, o: int) -> tuple[float, float, float]:
    return prep[k, o], prep[k, o + 1], prep[k, o + 2]


@leaf
def _geometry(
    prep: np.ndarray, k: int, state: np.ndarray, a: int, b: int
) -> tuple[
    tuple[float, float, float], tuple[float, float, float], tuple[float, float, float],
    tuple[float, float, float], tuple[float, float, float], tuple[float, float, float],
    tuple[float, float, float],
]:  # fmt: skip
    """Joint k now: the arms ``r_A``, ``r_B``, ``d = p_B - p_A``, A's axis, B's axis and the
    two reference directions, each turned with its body."""
    ra = _turn(state, a, S_T, prep[k], W_RA)
    rb = _turn(state, b, S_T, prep[k], W_RB)
    d0 = prep[k, W_XB] - prep[k, W_XA] + state[b, S_D] - state[a, S_D]
    d1 = prep[k, W_XB + 1] - prep[k, W_XA + 1] + state[b, S_D + 1] - state[a, S_D + 1]
    d2 = prep[k, W_XB + 2] - prep[k, W_XA + 2] + state[b, S_D + 2] - state[a, S_D + 2]
    d = (d0 + rb[0] - ra[0], d1 + rb[1] - ra[1], d2 + rb[2] - ra[2])
    aa = _turn(state, a, S_T, prep[k], W_AA)
    ab = _turn(state, b, S_T, prep[k], W_AB)
    pa = _turn(state, a, S_T, prep[k], W_PA)
    pb = _turn(state, b, S_T, prep[k], W_PB)
    return ra, rb, d, aa, ab, pa, pb


@njit(cache=True, inline="always")
def _push(
    state: np.ndarray, prep: np.ndarray, k: int, a: int, b: int,
    p: tuple[float, float, float], la: tuple[float, float, float],
    lb: tuple[float, float, float],
) -> None:  # fmt: skip
    """Impulse ``p`` on B and ``-p`` on A, angular impulses ``lb`` on B and ``-la`` on A."""
    ma, mb = prep[k, W_MA], prep[k, W_MB]
    wa = _apply_inertia(prep, k, W_IA, la)
    wb = _apply_inertia(prep, k, W_IB, lb)
    for c in range(3):
        state[a, S_V + c] -= ma * p[c]
        state[a, S_W + c] -= wa[c]
        state[b, S_V + c] += mb * p[c]
        state[b, S_W + c] += wb[c]


@njit(cache=True, inline="always")
def _speed(
    state: np.ndarray, a: int, b: int, u: tuple[float, float, float],
    sa: tuple[float, float, float], sb: tuple[float, float, float],
) -> float:  # fmt: skip
    total = 0.0
    for c in range(3):
        total += u[c] * (state[b, S_V + c] - state[a, S_V + c])
        total += sb[c] * state[b, S_W + c] - sa[c] * state[a, S_W + c]
    return total


@njit(cache=True, inline="always")
def _row(
    jf: np.ndarray, j: int, col: int, prep: np.ndarray, k: int, state: np.ndarray, a: int,
    b: int, u: tuple[float, float, float], sa: tuple[float, float, float],
    sb: tuple[float, float, float], bias: float, ms: float, iscale: float, sign: float,
    low: float, high: float,
) -> None:  # fmt: skip
    """One scalar row (module docstring) scaled by ``sign``, its accumulated impulse in
    column ``col`` kept within ``[low, high]``."""
    kk = prep[k, W_MA] + prep[k, W_MB] + _dot(sa, _apply_inertia(prep, k, W_IA, sa))
    kk += _dot(sb, _apply_inertia(prep, k, W_IB, sb))
    if kk <= 0.0:
        return
    cdot = sign * _speed(state, a, b, u, sa, sb)
    old = jf[j, col]
    new = min(max(old - ms * (cdot + bias) / kk - iscale * old, low), high)
    jf[j, col] = new
    lam = sign * (new - old)
    _push(
        state, prep, k, a, b, (lam * u[0], lam * u[1], lam * u[2]),
        (lam * sa[0], lam * sa[1], lam * sa[2]), (lam * sb[0], lam * sb[1], lam * sb[2]),
    )  # fmt: skip


@njit(cache=True, inline="always")
def _rigid(
    c: float, use_bias: bool, soft: tuple[float, float, float]
) -> tuple[float, float, float]:
    """Bias, mass and impulse scales of a rigid row at error ``c``: the joints' softness with
    the bias, rigid in the relax pass."""
    if use_bias:
        return soft[0] * c, soft[1], soft[2]
    return 0.0, 1.0, 0.0


@njit(cache=True, inline="always")
def _limit(
    c: float, inv_h: float, use_bias: bool, soft: tuple[float, float, float]
) -> tuple[float, float, float]:
    if c > 0.0:
        return c * inv_h, 1.0, 0.0
    return _rigid(c, use_bias, soft)


@njit(cache=True)
def _point(
    jf: np.ndarray, j: int, prep: np.ndarray, k: int, state: np.ndarray, a: int, b: int,
    ra: tuple[float, float, float], rb: tuple[float, float, float],
    d: tuple[float, float, float], soft: tuple[float, float, float], most: float,
) -> None:  # fmt: skip
    """B's anchor on A's (a 3x3 block); ``soft`` = (rate, mass scale, impulse scale), the
    accumulated impulse within ``most`` [N s] of length."""
    ma, mb = prep[k, W_MA], prep[k, W_MB]
    kk = np.zeros((3, 3))
    for c in range(3):
        e = (1.0 if c == 0 else 0.0, 1.0 if c == 1 else 0.0, 1.0 if c == 2 else 0.0)
        # column c: the relative velocity of the anchors per unit impulse along e
        ta = _cross(_apply_inertia(prep, k, W_IA, _cross(ra, e)), ra)
        tb = _cross(_apply_inertia(prep, k, W_IB, _cross(rb, e)), rb)
        for r in range(3):
            kk[r, c] = (ma + mb) * e[r] + ta[r] + tb[r]
    va = (state[a, S_V], state[a, S_V + 1], state[a, S_V + 2])
    vb = (state[b, S_V], state[b, S_V + 1], state[b, S_V + 2])
    wa = (state[a, S_W], state[a, S_W + 1], state[a, S_W + 2])
    wb = (state[b, S_W], state[b, S_W + 1], state[b, S_W + 2])
    ca = _cross(wa, ra)
    cb = _cross(wb, rb)
    rhs = np.empty(3)
    for c in range(3):
        rhs[c] = vb[c] + cb[c] - va[c] - ca[c] + soft[0] * d[c]
    sol = np.empty(3)
    if not _solve3(kk, rhs, sol):
        return
    new = np.empty(3)
    for c in range(3):
        old = jf[j, JP + c]
        new[c] = old - soft[1] * sol[c] - soft[2] * old
    size = math.sqrt(new[0] ** 2 + new[1] ** 2 + new[2] ** 2)
    if size > most:
        new *= most / size
    p = (new[0] - jf[j, JP], new[1] - jf[j, JP + 1], new[2] - jf[j, JP + 2])
    for c in range(3):
        jf[j, JP + c] = new[c]
    _push(state, prep, k, a, b, p, _cross(ra, p), _cross(rb, p))


@njit(cache=True)
def _solve3(kk: np.ndarray, rhs: np.ndarray, out: np.ndarray) -> bool:
    """``kk^-1 rhs`` for a 3x3 ``kk`` by its cofactors (Cramer) into ``out``; False when
    ``kk`` is singular."""
    c00 = kk[1, 1] * kk[2, 2] - kk[1, 2] * kk[2, 1]
    c01 = kk[1, 2] * kk[2, 0] - kk[1, 0] * kk[2, 2]
    c02 = kk[1, 0] * kk[2, 1] - kk[1, 1] * kk[2, 0]
    det = kk[0, 0] * c00 + kk[0, 1] * c01 + kk[0, 2] * c02
    if det == 0.0:
        return False
    inv = np.empty((3, 3))
    inv[0, 0] = c00
    inv[1, 0] = c01
    inv[2, 0] = c02
    inv[0, 1] = kk[0, 2] * kk[2, 1] - kk[0, 1] * kk[2, 2]
    inv[1, 1] = kk[0, 0] * kk[2, 2] - kk[0, 2] * kk[2, 0]
    inv[2, 1] = kk[0, 1] * kk[2, 0] - kk[0, 0] * kk[2, 1]
    inv[0, 2] = kk[0, 1] * kk[1, 2] - kk[0, 2] * kk[1, 1]
    inv[1, 2] = kk[0, 2] * kk[1, 0] - kk[0, 0] * kk[1, 2]
    inv[2, 2] = kk[0, 0] * kk[1, 1] - kk[0, 1] * kk[1, 0]
    for r in range(3):
        out[r] = (inv[r, 0] * rhs[0] + inv[r, 1] * rhs[1] + inv[r, 2] * rhs[2]) / det
    return True


@njit(cache=True, inline="always")
def _square(
    u: tuple[float, float, float],
) -> tuple[tuple[float, float, float], tuple[float, float, float]]:
    """Two unit directions square to unit ``u`` and to each other."""
    b = _cross(u, (1.0, 0.0, 0.0)) if abs(u[0]) < 0.57735 else _cross(u, (0.0, 1.0, 0.0))
    size = math.sqrt(_dot(b, b))
    b = (b[0] / size, b[1] / size, b[2] / size)
    return b, _cross(u, b)


@njit(cache=True)
def _lock(
    jf: np.ndarray, j: int, prep: np.ndarray, k: int, state: np.ndarray, a: int, b: int,
    bias_on: bool, soft: tuple[float, float, float], spring: bool,
) -> None:  # fmt: skip
    """No turn of B relative to A: three rows about the world axes, their errors the
    small-angle part of ``E = T_B M_0 T_A^T`` (module docstring); ``spring``: soft in every
    pass with ``soft``."""
    inf = math.inf
    e = np.empty(9)  # T_B M_0
    for r in range(3):
        for c in range(3):
            e[3 * r + c] = (
                state[b, S_T + 3 * r] * prep[k, W_M + c]
                + state[b, S_T + 3 * r + 1] * prep[k, W_M + 3 + c]
                + state[b, S_T + 3 * r + 2] * prep[k, W_M + 6 + c]
            )
    f = np.empty(9)  # (T_B M_0) T_A^T
    for r in range(3):
        for c in range(3):
            f[3 * r + c] = (
                e[3 * r] * state[a, S_T + 3 * c] + e[3 * r + 1] * state[a, S_T + 3 * c + 1]
                + e[3 * r + 2] * state[a, S_T + 3 * c + 2]
            )  # fmt: skip
    err = (0.5 * (f[7] - f[5]), 0.5 * (f[2] - f[6]), 0.5 * (f[3] - f[1]))
    zero = (0.0, 0.0, 0.0)
    for c in range(3):
        axis = (1.0 if c == 0 else 0.0, 1.0 if c == 1 else 0.0, 1.0 if c == 2 else 0.0)
        if spring:
            bias, ms, iscale = soft[0] * err[c], soft[1], soft[2]
        else:
            bias, ms, iscale = _rigid(err[c], bias_on, soft)
        _row(
            jf, j, JANG + c, prep, k, state, a, b, zero, axis, axis, bias, ms, iscale, 1.0,
            -inf, inf,
        )  # fmt: skip


@njit(cache=True)
def _drive(
    jf: np.ndarray, j: int, flags: int, prep: np.ndarray, k: int, state: np.ndarray, a: int,
    b: int, line: tuple[Vec3, Vec3, Vec3], value: float, stretch: float, lower: bool,
    steps: tuple[float, float], use_bias: bool, soft: tuple[float, float, float],
) -> None:  # fmt: skip
    """A joint's own rows along ``line`` (``u``, ``s_A``, ``s_B``) at ``value`` (a hinge's
    angle, a slider's travel, a rod's length), in Box2D's order: its spring at error
    ``stretch``, its motor, its limits (``flags``: which it has; ``lower``: whether the lower
    limit is one); ``steps``: the substep ``h`` and ``1 / h``."""
    inf = math.inf
    u, sa, sb = line
    h, inv_h = steps
    if flags & FLAG_SPRING and jf[j, HERTZ] > 0.0:
        bias, ms, iscale = prep[k, W_SOFT] * stretch, prep[k, W_SOFT + 1], prep[k, W_SOFT + 2]
        _row(jf, j, JSPRING, prep, k, state, a, b, u, sa, sb, bias, ms, iscale, 1.0, -inf, inf)
    if flags & FLAG_MOTOR:
        most = jf[j, MAX_MOTOR] * h
        speed = -jf[j, MOTOR_SPEED]
        _row(jf, j, JMOTOR, prep, k, state, a, b, u, sa, sb, speed, 1.0, 0.0, 1.0, -most, most)
    if flags & FLAG_LIMIT:
        if lower:
            bias, ms, iscale = _limit(value - jf[j, LOWER], inv_h, use_bias, soft)
            _row(jf, j, JLOWER, prep, k, state, a, b, u, sa, sb, bias, ms, iscale, 1.0, 0.0, inf)
        bias, ms, iscale = _limit(jf[j, UPPER] - value, inv_h, use_bias, soft)
        _row(jf, j, JUPPER, prep, k, state, a, b, u, sa, sb, bias, ms, iscale, -1.0, 0.0, inf)


@njit(cache=True, inline="always")
def _unit(d: Vec3) -> tuple[float, Vec3]:
    """A rod's length ``|d|`` [m] and its direction from A's anchor to B's (x when they
    meet)."""
    length = math.sqrt(_dot(d, d))
    if length > 0.0:
        return length, (d[0] / length, d[1] / length, d[2] / length)
    return length, (1.0, 0.0, 0.0)


@njit(cache=True)
def solve(
    jf: np.ndarray, ji: np.ndarray, active: np.ndarray, prep: np.ndarray, rows: np.ndarray,
    state: np.ndarray, h: float, soft: tuple[float, float, float], use_bias: bool,
) -> None:  # fmt: skip
    """One Gauss-Seidel pass over the joints ``active`` (k,), as in 2D
    (:func:`carom.engines.rigid.joints.solve`)."""
    steps = (h, 1.0 / h)
    inf = math.inf
    zero = (0.0, 0.0, 0.0)
    for k in range(active.shape[0]):
        j = active[k]
        a, b = rows[k, 0], rows[k, 1]
        kind = ji[j, J_KIND]
        flags = ji[j, J_FLAGS]
        ra, rb, d, aa, ab, pa, pb = _geometry(prep, k, state, a, b)
        rigid = _scales(use_bias, soft)
        if kind == TARGET:
            own = (prep[k, W_SOFT], prep[k, W_SOFT + 1], prep[k, W_SOFT + 2])
            _point(jf, j, prep, k, state, a, b, ra, rb, d, own, jf[j, MAX_FORCE] * h)
        elif kind == SPHERICAL:
            _point(jf, j, prep, k, state, a, b, ra, rb, d, rigid, inf)
        elif kind == REVOLUTE:
            # the angle about the hinge, from A's reference direction to B's
            angle = math.atan2(_dot(_cross(pa, pb), aa), _dot(pa, pb))
            hinge = (zero, aa, aa)
            _drive(
                jf, j, flags, prep, k, state, a, b, hinge, angle, angle, True, steps, use_bias,
                soft,
            )  # fmt: skip
            # B's axis along A's: two rows about a_B x b and a_B x c
            sq1, sq2 = _square(aa)
            for c, sq in enumerate((sq1, sq2)):
                u = _cross(ab, sq)
                bias, ms, iscale = _rigid(_dot(ab, sq), use_bias, soft)
                _row(
                    jf, j, JANG + c, prep, k, state, a, b, zero, u, u, bias, ms, iscale, 1.0,
                    -inf, inf,
                )  # fmt: skip
            _point(jf, j, prep, k, state, a, b, ra, rb, d, rigid, inf)
        elif kind == WELD:
            if jf[j, ANG_HERTZ] > 0.0:
                angular = (prep[k, W_ASOFT], prep[k, W_ASOFT + 1], prep[k, W_ASOFT + 2])
                _lock(jf, j, prep, k, state, a, b, use_bias, angular, True)
            else:
                _lock(jf, j, prep, k, state, a, b, use_bias, soft, False)
            if jf[j, HERTZ] > 0.0:
                linear = (prep[k, W_SOFT], prep[k, W_SOFT + 1], prep[k, W_SOFT + 2])
            else:
                linear = rigid
            _point(jf, j, prep, k, state, a, b, ra, rb, d, linear, inf)
        elif kind == DISTANCE:
            length, u = _unit(d)
            rod = (u, _cross(ra, u), _cross(rb, u))
            if jf[j, LOWER] < jf[j, UPPER]:  # a spring or a rope: a range (a least length 0
                # is no limit: a length is never less)
                _drive(
                    jf, j, flags | FLAG_LIMIT, prep, k, state, a, b, rod, length,
                    length - jf[j, LENGTH], jf[j, LOWER] > 0.0, steps, use_bias, soft,
                )  # fmt: skip
            else:
                bias, ms, iscale = _rigid(length - jf[j, LENGTH], use_bias, soft)
                _row(
                    jf, j, JAXIAL, prep, k, state, a, b, rod[0], rod[1], rod[2], bias, ms,
                    iscale, 1.0, -inf, inf,
                )  # fmt: skip
        else:  # PRISMATIC: B's anchor on A's axis, no relative turn
            lever = (d[0] + ra[0], d[1] + ra[1], d[2] + ra[2])
            along = _dot(aa, d)
            slide = (aa, _cross(lever, aa), _cross(rb, aa))
            _drive(
                jf, j, flags, prep, k, state, a, b, slide, along, along, True, steps, use_bias,
                soft,
            )  # fmt: skip
            _lock(jf, j, prep, k, state, a, b, use_bias, soft, False)
            sq1, sq2 = _square(aa)
            for c, sq in enumerate((sq1, sq2)):
                bias, ms, iscale = _rigid(_dot(sq, d), use_bias, soft)
                _row(
                    jf, j, JSIDE + c, prep, k, state, a, b, sq, _cross(lever, sq), _cross(rb, sq),
                    bias, ms, iscale, 1.0, -inf, inf,
                )  # fmt: skip


@njit(cache=True, inline="always")
def _scales(use_bias: bool, soft: tuple[float, float, float]) -> tuple[float, float, float]:
    if use_bias:
        return soft
    return 0.0, 1.0, 0.0


@njit(cache=True)
def _impulses(
    jf: np.ndarray, j: int, kind: int, geometry: tuple[Vec3, Vec3, Vec3, Vec3, Vec3, Vec3, Vec3]
) -> tuple[Vec3, Vec3, Vec3]:
    """A joint's accumulated impulses as one: the impulse on B [N s], the arm on A it acts at,
    and the couple on B [N m s] (on A: the opposite of all)."""
    ra, _, d, aa, ab, _, _ = geometry
    p = (jf[j, JP], jf[j, JP + 1], jf[j, JP + 2])
    couple = (0.0, 0.0, 0.0)
    arm = ra
    if kind == REVOLUTE:
        spin = jf[j, JSPRING] + jf[j, JMOTOR] + jf[j, JLOWER] - jf[j, JUPPER]
        sq1, sq2 = _square(aa)
        u1, u2 = _cross(ab, sq1), _cross(ab, sq2)
        couple = _sum3(
            (spin * aa[0], spin * aa[1], spin * aa[2]),
            (jf[j, JANG] * u1[0], jf[j, JANG] * u1[1], jf[j, JANG] * u1[2]),
            (jf[j, JANG + 1] * u2[0], jf[j, JANG + 1] * u2[1], jf[j, JANG + 1] * u2[2]),
        )
    elif kind == WELD:
        couple = (jf[j, JANG], jf[j, JANG + 1], jf[j, JANG + 2])
    elif kind == DISTANCE:
        _, u = _unit(d)
        lam = jf[j, JAXIAL] + jf[j, JSPRING] + jf[j, JLOWER] - jf[j, JUPPER]
        p = (lam * u[0], lam * u[1], lam * u[2])
    elif kind == PRISMATIC:
        lam = jf[j, JSPRING] + jf[j, JMOTOR] + jf[j, JLOWER] - jf[j, JUPPER]
        sq1, sq2 = _square(aa)
        p = _sum3(
            (lam * aa[0], lam * aa[1], lam * aa[2]),
            (jf[j, JSIDE] * sq1[0], jf[j, JSIDE] * sq1[1], jf[j, JSIDE] * sq1[2]),
            (jf[j, JSIDE + 1] * sq2[0], jf[j, JSIDE + 1] * sq2[1], jf[j, JSIDE + 1] * sq2[2]),
        )
        arm = (d[0] + ra[0], d[1] + ra[1], d[2] + ra[2])
        couple = (jf[j, JANG], jf[j, JANG + 1], jf[j, JANG + 2])
    return p, arm, couple


@njit(cache=True, inline="always")
def _sum3(
    a: tuple[float, float, float], b: tuple[float, float, float], c: tuple[float, float, float]
) -> tuple[float, float, float]:
    return a[0] + b[0] + c[0], a[1] + b[1] + c[1], a[2] + b[2] + c[2]


@njit(cache=True)
def warm_start(
    jf: np.ndarray, ji: np.ndarray, active: np.ndarray, prep: np.ndarray, rows: np.ndarray,
    state: np.ndarray,
) -> None:  # fmt: skip
    """Apply every active joint's accumulated impulses again, with its geometry now."""
    for k in range(active.shape[0]):
        j = active[k]
        a, b = rows[k, 0], rows[k, 1]
        g = _geometry(prep, k, state, a, b)
        p, arm, couple = _impulses(jf, j, ji[j, J_KIND], g)
        la = _sum3(_cross(arm, p), couple, (0.0, 0.0, 0.0))
        lb = _sum3(_cross(g[1], p), couple, (0.0, 0.0, 0.0))
        _push(state, prep, k, a, b, p, la, lb)


@njit(cache=True)
def reactions(
    jf: np.ndarray, ji: np.ndarray, active: np.ndarray, prep: np.ndarray, rows: np.ndarray,
    state: np.ndarray, h: float,
) -> None:  # fmt: skip
    """Each active joint's force [N] and couple [N m] on B over the last substep ``h``."""
    for k in range(active.shape[0]):
        j = active[k]
        g = _geometry(prep, k, state, rows[k, 0], rows[k, 1])
        p, _, couple = _impulses(jf, j, ji[j, J_KIND], g)
        for c in range(3):
            jf[j, FORCE + c] = p[c] / h
            jf[j, TORQUE + c] = couple[c] / h
