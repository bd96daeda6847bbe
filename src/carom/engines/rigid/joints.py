"""2D joints in the soft step: revolute, prismatic, distance, weld, wheel and target.

Each joint is a set of velocity constraints between body A and body B (or the world, body -1)
solved in the substeps of :func:`carom.engines.rigid.solver.solve_step` as the contacts are,
after the formulation of Box2D v3's joint solver (Catto, "Solver2D", 2024): a constraint
``C = 0`` with Jacobian ``J`` takes the impulse ``lambda = -m_s K^-1 (J v + b) - i_s lambda_acc``
with ``K = J M^-1 J^T``, the bias ``b = rate C`` and the scales ``m_s``, ``i_s`` of a soft spring
(:func:`carom.engines.stepped.solver.softness`) in a pass with the bias, and ``b = 0``,
``m_s = 1``, ``i_s = 0`` (rigid) in the relax pass. A joint's own spring (its frequency and
damping ratio) is soft in both passes. Limits are one-sided (their impulse never pulls) and
speculative: a limit not reached only stops the gap from closing faster than ``C / h``. A
motor drives a relative speed with an impulse capped at its largest force or torque times
``h``. Every impulse accumulates from substep to substep and warm-starts the next one.

Geometry within the step is tracked without new tests, as for contacts: each body's move and
turn since the step began are in the solver's state, the anchors ``r`` (from each centre of
mass, in world axes at the step's start) turn with their body, and
``d = p_B - p_A = (x_B - x_A)_0 + (dx_B - dx_A) + r_B - r_A``. Angles are unwrapped: the
relative angle ``theta_B - theta_A - theta_ref`` counts whole turns, so a revolute limit may
span more than one.

A joint's reaction after a step (:data:`FX`, :data:`FY`, :data:`TORQUE`) is the force [N] and
the couple [N m] it puts on body B: its accumulated impulses over the last substep ``h``
(Box2D's ``b2Joint_GetConstraintForce``).
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
    TARGET,
    WELD,
    WHEEL,
)
from carom.engines.stepped.solver import softness

__all__ = [
    "FREE_SHARE",
    "JOINT_FLOATS",
    "by_body",
    "prepare",
    "reactions",
    "resists",
    "solve",
    "warm_start",
]

# the float columns of a 2D joint row: what the joint is ...
LAX, LAY = 0, 1  # anchor on A from its centre of mass, in A's frame [m] (the world's: a point)
LBX, LBY = 2, 3  # anchor on B, in B's frame [m]
AXX, AXY = 4, 5  # unit axis in A's frame (prismatic, wheel)
REF = 6  # the relative angle theta_B - theta_A at which the joint is at rest [rad]
LENGTH = 7  # the distance joint's length, its spring's rest length [m]
LOWER, UPPER = 8, 9  # limits: angles [rad] (revolute), translations or lengths [m]
MOTOR_SPEED = 10  # [rad/s] (revolute, wheel) or [m/s] (prismatic)
MAX_MOTOR = 11  # the motor's largest torque [N m] or force [N]
HERTZ, DAMPING = 12, 13  # the joint's spring (the weld's linear one) [Hz], [-]
MAX_FORCE = 14  # the target joint's largest force [N]
ANG_HERTZ, ANG_DAMPING = 15, 16  # the weld's angular spring [Hz], [-] (0 Hz: rigid)
# ... the impulses it accumulated [N s] or [N m s] ...
JX, JY = 17, 18  # the point's (revolute, weld, target); JX the perpendicular one (prismatic,
JANG = 19  # wheel); the angular one (weld, prismatic)
JAXIAL = 20  # the rigid length's (distance)
JLOWER, JUPPER, JMOTOR, JSPRING = 21, 22, 23, 24
# ... and its reaction on B after the last step
FX, FY = 25, 26  # force [N]
TORQUE = 27  # couple [N m]
JOINT_FLOATS = 28
#: the names the 3D rows use too (:mod:`carom.engines.rigid3d.joints`)
LA, LB, AXA = LAX, LBX, AXX

# the columns of the state the solver keeps for each body (:mod:`.solver`)
S_VX, S_VY, S_W, S_DX, S_DY, S_COS, S_SIN, S_TURN = 0, 1, 2, 3, 4, 5, 6, 7

# what a step prepares for each active joint: the anchors in world axes at the step's start,
# (x_B - x_A) then, the axis then, the relative angle then less the reference, the inverse
# masses and moments of inertia, and the soft scales of its own springs
W_RAX, W_RAY, W_RBX, W_RBY, W_DCX, W_DCY, W_UX, W_UY, W_ANGLE = range(9)
W_MA, W_MB, W_IA, W_IB = 9, 10, 11, 12
W_RATE, W_MSCALE, W_ISCALE = 13, 14, 15  # the joint's spring
W_ARATE, W_AMSCALE, W_AISCALE = 16, 17, 18  # the weld's angular spring
PREPARED = 19


@njit(cache=True)
def prepare(
    jf: np.ndarray,
    ji: np.ndarray,
    active: np.ndarray,
    x: np.ndarray,
    angle: np.ndarray,
    inv_mass: np.ndarray,
    inv_inertia: np.ndarray,
    h: float,
) -> tuple[np.ndarray, np.ndarray]:
    """What the substeps read of the joints ``active`` (k,) at the step's start: the prepared
    rows (k, PREPARED) and each joint's two rows of the solver's state (k, 2), the world's
    being the last row (the dummy: at rest, infinite mass)."""
    n = x.shape[0]
    k_all = active.shape[0]
    prep = np.zeros((k_all, PREPARED))
    rows = np.empty((k_all, 2), np.int64)
    for k in range(k_all):
        j = active[k]
        for side in range(2):
            body = ji[j, J_A + side]
            if body < 0:
                rows[k, side] = n
                px, py, th, im, ii = 0.0, 0.0, 0.0, 0.0, 0.0
            else:
                rows[k, side] = body
                px, py, th = x[body, 0], x[body, 1], angle[body]
                im, ii = inv_mass[body], inv_inertia[body]
            c, s = math.cos(th), math.sin(th)
            lx = jf[j, LAX + 2 * side]
            ly = jf[j, LAY + 2 * side]
            prep[k, W_RAX + 2 * side] = c * lx - s * ly
            prep[k, W_RAY + 2 * side] = s * lx + c * ly
            prep[k, W_MA + side] = im
            prep[k, W_IA + side] = ii
            sign = 1.0 if side == 1 else -1.0
            prep[k, W_DCX] += sign * px
            prep[k, W_DCY] += sign * py
            prep[k, W_ANGLE] += sign * th
            if side == 0:
                ux, uy = jf[j, AXX], jf[j, AXY]
                prep[k, W_UX] = c * ux - s * uy
                prep[k, W_UY] = s * ux + c * uy
        prep[k, W_ANGLE] -= jf[j, REF]
        if jf[j, HERTZ] > 0.0:
            rate, ms, iscale = softness(jf[j, HERTZ], jf[j, DAMPING], h)
            prep[k, W_RATE], prep[k, W_MSCALE], prep[k, W_ISCALE] = rate, ms, iscale
        if jf[j, ANG_HERTZ] > 0.0:
            rate, ms, iscale = softness(jf[j, ANG_HERTZ], jf[j, ANG_DAMPING], h)
            prep[k, W_ARATE], prep[k, W_AMSCALE], prep[k, W_AISCALE] = rate, ms, iscale
    return prep, rows


@njit(cache=True, inline="always")
def _geometry(
    prep: np.ndarray, k: int, state: np.ndarray, a: int, b: int
) -> tuple[float, float, float, float, float, float, float, float, float]:
    """Joint k now: the anchors ``r_A``, ``r_B`` turned with their bodies, ``d = p_B - p_A``,
    A's axis turned with A, and the relative angle less the reference."""
    ca, sa = state[a, S_COS], state[a, S_SIN]
    cb, sb = state[b, S_COS], state[b, S_SIN]
    rax = ca * prep[k, W_RAX] - sa * prep[k, W_RAY]
    ray = sa * prep[k, W_RAX] + ca * prep[k, W_RAY]
    rbx = cb * prep[k, W_RBX] - sb * prep[k, W_RBY]
    rby = sb * prep[k, W_RBX] + cb * prep[k, W_RBY]
    dx = prep[k, W_DCX] + (state[b, S_DX] - state[a, S_DX]) + rbx - rax
    dy = prep[k, W_DCY] + (state[b, S_DY] - state[a, S_DY]) + rby - ray
    ux = ca * prep[k, W_UX] - sa * prep[k, W_UY]
    uy = sa * prep[k, W_UX] + ca * prep[k, W_UY]
    rel = prep[k, W_ANGLE] + state[b, S_TURN] - state[a, S_TURN]
    return rax, ray, rbx, rby, dx, dy, ux, uy, rel


@njit(cache=True, inline="always")
def _push(
    state: np.ndarray, prep: np.ndarray, k: int, a: int, b: int, px: float, py: float,
    la: float, lb: float,
) -> None:  # fmt: skip
    """Impulse ``P`` on B and ``-P`` on A, with the angular impulses ``lb`` on B and ``-la`` on
    A (each the arm's cross product with ``P`` plus any couple)."""
    ma, mb, ia, ib = prep[k, W_MA], prep[k, W_MB], prep[k, W_IA], prep[k, W_IB]
    state[a, S_VX] -= ma * px
    state[a, S_VY] -= ma * py
    state[a, S_W] -= ia * la
    state[b, S_VX] += mb * px
    state[b, S_VY] += mb * py
    state[b, S_W] += ib * lb


@njit(cache=True, inline="always")
def _along(state: np.ndarray, a: int, b: int, ux: float, uy: float, sa: float, sb: float) -> float:
    """The constraint's speed ``u . (v_B - v_A) + s_B w_B - s_A w_A`` [m/s]."""
    speed: float = (
        ux * (state[b, S_VX] - state[a, S_VX])
        + uy * (state[b, S_VY] - state[a, S_VY])
        + sb * state[b, S_W]
        - sa * state[a, S_W]
    )
    return speed


@njit(cache=True, inline="always")
def _axial_mass(prep: np.ndarray, k: int, sa: float, sb: float) -> float:
    kk = prep[k, W_MA] + prep[k, W_MB] + prep[k, W_IA] * sa * sa + prep[k, W_IB] * sb * sb
    return 1.0 / kk if kk > 0.0 else 0.0


@njit(cache=True, inline="always")
def _angular_mass(prep: np.ndarray, k: int) -> float:
    kk = prep[k, W_IA] + prep[k, W_IB]
    return 1.0 / kk if kk > 0.0 else 0.0


@njit(cache=True, inline="always")
def _scales(use_bias: bool, soft: tuple[float, float, float]) -> tuple[float, float, float]:
    """The bias rate [1/s], mass and impulse scales of a rigid constraint in a pass: the
    joints' softness ``soft`` with the bias, rigid (0, 1, 0) in the relax pass."""
    if use_bias:
        return soft
    return 0.0, 1.0, 0.0


@njit(cache=True, inline="always")
def _soft(c: float, use_bias: bool, soft: tuple[float, float, float]) -> tuple[float, float, float]:
    """Bias [m/s], mass and impulse scales of a rigid constraint at error ``c``
    (:func:`_scales`)."""
    rate, ms, iscale = _scales(use_bias, soft)
    return rate * c, ms, iscale


@njit(cache=True, inline="always")
def _limit(
    c: float, inv_h: float, use_bias: bool, soft: tuple[float, float, float]
) -> tuple[float, float, float]:
    """Bias, mass and impulse scales of a one-sided limit at ``c`` (>= 0: not reached):
    speculative when not reached, else as :func:`_soft`."""
    if c > 0.0:
        return c * inv_h, 1.0, 0.0
    return _soft(c, use_bias, soft)


@njit(cache=True, inline="always")
def _axial_row(
    jf: np.ndarray, j: int, col: int, prep: np.ndarray, k: int, state: np.ndarray, a: int,
    b: int, u: tuple[float, float, float, float], bias: float, ms: float, iscale: float,
    mass: float, sign: float, low: float, high: float,
) -> None:  # fmt: skip
    """One scalar constraint along ``u = (ux, uy, s_A, s_B)`` (its speed :func:`_along`),
    scaled by ``sign`` (-1: an upper limit, pushing the other way), its accumulated impulse in
    column ``col`` kept within ``[low, high]``."""
    ux, uy, sa, sb = u
    cdot = sign * _along(state, a, b, ux, uy, sa, sb)
    old = jf[j, col]
    new = min(max(old - ms * mass * (cdot + bias) - iscale * old, low), high)
    jf[j, col] = new
    lam = sign * (new - old)
    _push(state, prep, k, a, b, lam * ux, lam * uy, lam * sa, lam * sb)


@njit(cache=True, inline="always")
def _limits(
    jf: np.ndarray, j: int, prep: np.ndarray, k: int, state: np.ndarray, a: int, b: int,
    u: tuple[float, float, float, float], value: float, mass: float, inv_h: float,
    use_bias: bool, soft: tuple[float, float, float], lower: bool = True,
) -> None:  # fmt: skip
    """The lower (if ``lower``) and upper limits on ``value`` (a length, translation or
    angle) along ``u``."""
    inf = math.inf
    if lower:
        bias, ms, iscale = _limit(value - jf[j, LOWER], inv_h, use_bias, soft)
        _axial_row(jf, j, JLOWER, prep, k, state, a, b, u, bias, ms, iscale, mass, 1.0, 0.0, inf)
    bias, ms, iscale = _limit(jf[j, UPPER] - value, inv_h, use_bias, soft)
    _axial_row(jf, j, JUPPER, prep, k, state, a, b, u, bias, ms, iscale, mass, -1.0, 0.0, inf)


@njit(cache=True, inline="always")
def _spring(
    jf: np.ndarray, j: int, prep: np.ndarray, k: int, state: np.ndarray, a: int, b: int,
    u: tuple[float, float, float, float], c: float, mass: float,
) -> None:  # fmt: skip
    """The joint's own spring (:data:`HERTZ`) along ``u`` at error ``c``: soft in every
    pass."""
    inf = math.inf
    bias = prep[k, W_RATE] * c
    _axial_row(
        jf, j, JSPRING, prep, k, state, a, b, u, bias, prep[k, W_MSCALE], prep[k, W_ISCALE],
        mass, 1.0, -inf, inf,
    )  # fmt: skip


@njit(cache=True, inline="always")
def _motor(
    jf: np.ndarray, j: int, prep: np.ndarray, k: int, state: np.ndarray, a: int, b: int,
    u: tuple[float, float, float, float], mass: float, h: float,
) -> None:  # fmt: skip
    """The motor along ``u``: drive its speed to :data:`MOTOR_SPEED` with at most
    :data:`MAX_MOTOR` times ``h``."""
    most = jf[j, MAX_MOTOR] * h
    _axial_row(
        jf, j, JMOTOR, prep, k, state, a, b, u, -jf[j, MOTOR_SPEED], 1.0, 0.0, mass, 1.0,
        -most, most,
    )  # fmt: skip


@njit(cache=True, inline="always")
def _point(
    jf: np.ndarray, j: int, prep: np.ndarray, k: int, state: np.ndarray, a: int, b: int,
    g: tuple[float, float, float, float, float, float, float, float, float],
    soft: tuple[float, float, float], most: float,
) -> None:  # fmt: skip
    """Anchor B on anchor A (a 2x2 block): ``soft`` = (rate, mass scale, impulse scale);
    the accumulated impulse (JX, JY) is kept within ``most`` [N s] of length."""
    rax, ray, rbx, rby, dx, dy = g[0], g[1], g[2], g[3], g[4], g[5]
    ma, mb, ia, ib = prep[k, W_MA], prep[k, W_MB], prep[k, W_IA], prep[k, W_IB]
    wa, wb = state[a, S_W], state[b, S_W]
    cx = (state[b, S_VX] - wb * rby) - (state[a, S_VX] - wa * ray) + soft[0] * dx
    cy = (state[b, S_VY] + wb * rbx) - (state[a, S_VY] + wa * rax) + soft[0] * dy
    k11 = ma + mb + ia * ray * ray + ib * rby * rby
    k12 = -ia * ray * rax - ib * rby * rbx
    k22 = ma + mb + ia * rax * rax + ib * rbx * rbx
    det = k11 * k22 - k12 * k12
    inv = 1.0 / det if det != 0.0 else 0.0
    bx = inv * (k22 * cx - k12 * cy)
    by = inv * (k11 * cy - k12 * cx)
    ox, oy = jf[j, JX], jf[j, JY]
    nx = ox - soft[1] * bx - soft[2] * ox
    ny = oy - soft[1] * by - soft[2] * oy
    size = math.hypot(nx, ny)
    if size > most:
        nx *= most / size
        ny *= most / size
    jf[j, JX], jf[j, JY] = nx, ny
    px, py = nx - ox, ny - oy
    _push(state, prep, k, a, b, px, py, rax * py - ray * px, rbx * py - rby * px)


@njit(cache=True, inline="always")
def _line(
    g: tuple[float, float, float, float, float, float, float, float, float],
) -> tuple[float, float, float]:
    """A distance joint's length ``|d|`` [m] and the unit direction from A's anchor to B's
    (x along when the anchors meet)."""
    length = math.hypot(g[4], g[5])
    if length > 0.0:
        return length, g[4] / length, g[5] / length
    return length, 1.0, 0.0


@njit(cache=True, inline="always")
def _levers(
    g: tuple[float, float, float, float, float, float, float, float, float], ux: float, uy: float
) -> tuple[float, float, float, float]:
    """A direction fixed in A through B's anchor: ``(ux, uy, (d + r_A) x u, r_B x u)``."""
    ax = g[4] + g[0]
    ay = g[5] + g[1]
    return ux, uy, ax * uy - ay * ux, g[2] * uy - g[3] * ux


@njit(cache=True)
def solve(
    jf: np.ndarray,
    ji: np.ndarray,
    active: np.ndarray,
    prep: np.ndarray,
    rows: np.ndarray,
    state: np.ndarray,
    h: float,
    soft: tuple[float, float, float],
    use_bias: bool,
) -> None:
    """One Gauss-Seidel pass over the joints ``active`` (k,), in order: with the joints'
    softness ``soft`` (rate, mass scale, impulse scale) and the bias if ``use_bias``, else
    rigid (the relax pass)."""
    inv_h = 1.0 / h
    inf = math.inf
    for k in range(active.shape[0]):
        j = active[k]
        a, b = rows[k, 0], rows[k, 1]
        kind = ji[j, J_KIND]
        flags = ji[j, J_FLAGS]
        g = _geometry(prep, k, state, a, b)
        spin = (0.0, 0.0, 1.0, 1.0)  # the relative angle's direction: w_B - w_A
        if kind in (REVOLUTE, WELD, TARGET):
            if kind == REVOLUTE:
                mass = _angular_mass(prep, k)
                if flags & FLAG_SPRING and jf[j, HERTZ] > 0.0:
                    _spring(jf, j, prep, k, state, a, b, spin, g[8], mass)
                if flags & FLAG_MOTOR:
                    _motor(jf, j, prep, k, state, a, b, spin, mass, h)
                if flags & FLAG_LIMIT:
                    _limits(jf, j, prep, k, state, a, b, spin, g[8], mass, inv_h, use_bias, soft)
                _point(jf, j, prep, k, state, a, b, g, _scales(use_bias, soft), inf)
            elif kind == WELD:
                mass = _angular_mass(prep, k)
                if jf[j, ANG_HERTZ] > 0.0:
                    rate, ms, iscale = prep[k, W_ARATE], prep[k, W_AMSCALE], prep[k, W_AISCALE]
                    bias = rate * g[8]
                else:
                    bias, ms, iscale = _soft(g[8], use_bias, soft)
                _axial_row(
                    jf, j, JANG, prep, k, state, a, b, spin, bias, ms, iscale, mass, 1.0,
                    -inf, inf,
                )  # fmt: skip
                if jf[j, HERTZ] > 0.0:
                    linear = (prep[k, W_RATE], prep[k, W_MSCALE], prep[k, W_ISCALE])
                else:
                    linear = _scales(use_bias, soft)
                _point(jf, j, prep, k, state, a, b, g, linear, inf)
            else:  # the target: B's anchor pulled to A's point by a spring of bounded force
                linear = (prep[k, W_RATE], prep[k, W_MSCALE], prep[k, W_ISCALE])
                _point(jf, j, prep, k, state, a, b, g, linear, jf[j, MAX_FORCE] * h)
        elif kind == DISTANCE:
            length, ux, uy = _line(g)
            line = (ux, uy, g[0] * uy - g[1] * ux, g[2] * uy - g[3] * ux)
            mass = _axial_mass(prep, k, line[2], line[3])
            if jf[j, LOWER] < jf[j, UPPER]:
                if flags & FLAG_SPRING and jf[j, HERTZ] > 0.0:
                    _spring(jf, j, prep, k, state, a, b, line, length - jf[j, LENGTH], mass)
                # (a rope's least length 0 is no limit: a length is never less)
                _limits(
                    jf, j, prep, k, state, a, b, line, length, mass, inv_h, use_bias, soft,
                    jf[j, LOWER] > 0.0,
                )  # fmt: skip
            else:
                bias, ms, iscale = _soft(length - jf[j, LENGTH], use_bias, soft)
                _axial_row(
                    jf, j, JAXIAL, prep, k, state, a, b, line, bias, ms, iscale, mass, 1.0,
                    -inf, inf,
                )  # fmt: skip
        else:  # PRISMATIC, WHEEL: B's anchor on the line of A's axis
            ux, uy = g[6], g[7]
            axis = _levers(g, ux, uy)
            mass = _axial_mass(prep, k, axis[2], axis[3])
            along = ux * g[4] + uy * g[5]
            if kind == WHEEL:
                if flags & FLAG_MOTOR:
                    _motor(jf, j, prep, k, state, a, b, spin, _angular_mass(prep, k), h)
                if flags & FLAG_SPRING and jf[j, HERTZ] > 0.0:
                    _spring(jf, j, prep, k, state, a, b, axis, along, mass)
                if flags & FLAG_LIMIT:
                    _limits(jf, j, prep, k, state, a, b, axis, along, mass, inv_h, use_bias, soft)
                perp = _levers(g, -g[7], g[6])
                bias, ms, iscale = _soft(perp[0] * g[4] + perp[1] * g[5], use_bias, soft)
                _axial_row(
                    jf, j, JX, prep, k, state, a, b, perp, bias, ms, iscale,
                    _axial_mass(prep, k, perp[2], perp[3]), 1.0, -inf, inf,
                )  # fmt: skip
            else:
                if flags & FLAG_SPRING and jf[j, HERTZ] > 0.0:
                    _spring(jf, j, prep, k, state, a, b, axis, along, mass)
                if flags & FLAG_MOTOR:
                    _motor(jf, j, prep, k, state, a, b, axis, mass, h)
                if flags & FLAG_LIMIT:
                    _limits(jf, j, prep, k, state, a, b, axis, along, mass, inv_h, use_bias, soft)
                _slide(jf, j, prep, k, state, a, b, g, _scales(use_bias, soft))


@njit(cache=True, inline="always")
def _slide(
    jf: np.ndarray, j: int, prep: np.ndarray, k: int, state: np.ndarray, a: int, b: int,
    g: tuple[float, float, float, float, float, float, float, float, float],
    soft: tuple[float, float, float],
) -> None:  # fmt: skip
    """The prismatic joint's block: B's anchor on A's axis and no relative turn (2x2),
    ``soft`` = (rate, mass scale, impulse scale)."""
    px, py, s1, s2 = _levers(g, -g[7], g[6])
    ma, mb, ia, ib = prep[k, W_MA], prep[k, W_MB], prep[k, W_IA], prep[k, W_IB]
    c1 = _along(state, a, b, px, py, s1, s2) + soft[0] * (px * g[4] + py * g[5])
    c2 = state[b, S_W] - state[a, S_W] + soft[0] * g[8]
    k11 = ma + mb + ia * s1 * s1 + ib * s2 * s2
    k12 = ia * s1 + ib * s2
    k22 = ia + ib
    if k22 == 0.0:
        k22 = 1.0
    det = k11 * k22 - k12 * k12
    inv = 1.0 / det if det != 0.0 else 0.0
    b1 = inv * (k22 * c1 - k12 * c2)
    b2 = inv * (k11 * c2 - k12 * c1)
    o1, o2 = jf[j, JX], jf[j, JANG]
    n1 = o1 - soft[1] * b1 - soft[2] * o1
    n2 = o2 - soft[1] * b2 - soft[2] * o2
    jf[j, JX], jf[j, JANG] = n1, n2
    d1, d2 = n1 - o1, n2 - o2
    _push(state, prep, k, a, b, d1 * px, d1 * py, d1 * s1 + d2, d1 * s2 + d2)


@njit(cache=True, inline="always")
def _impulses(
    jf: np.ndarray, j: int, kind: int, g: tuple[float, float, float, float, float, float,
    float, float, float],
) -> tuple[float, float, float, float, float, float]:  # fmt: skip
    """A joint's accumulated impulses as one: the impulse on B (x, y) [N s], the arm on A it
    acts at (from A's centre), and the couple on B [N m s] (on A: the opposite of all)."""
    rax, ray = g[0], g[1]
    axial = jf[j, JSPRING] + jf[j, JLOWER] - jf[j, JUPPER]
    if kind == REVOLUTE:
        return jf[j, JX], jf[j, JY], rax, ray, axial + jf[j, JMOTOR], 0.0
    if kind in (WELD, TARGET):
        return jf[j, JX], jf[j, JY], rax, ray, jf[j, JANG], 0.0
    if kind == DISTANCE:
        _, ux, uy = _line(g)
        lam = axial + jf[j, JAXIAL]
        return lam * ux, lam * uy, rax, ray, 0.0, 0.0
    ux, uy = g[6], g[7]
    couple = jf[j, JMOTOR] if kind == WHEEL else jf[j, JANG]
    if kind == PRISMATIC:
        axial += jf[j, JMOTOR]
    px = axial * ux - jf[j, JX] * uy
    py = axial * uy + jf[j, JX] * ux
    return px, py, g[4] + rax, g[5] + ray, couple, 0.0


@njit(cache=True)
def warm_start(
    jf: np.ndarray, ji: np.ndarray, active: np.ndarray, prep: np.ndarray, rows: np.ndarray,
    state: np.ndarray,
) -> None:  # fmt: skip
    """Apply every active joint's accumulated impulses again, with its anchors now."""
    for k in range(active.shape[0]):
        j = active[k]
        a, b = rows[k, 0], rows[k, 1]
        g = _geometry(prep, k, state, a, b)
        px, py, ax, ay, couple, _ = _impulses(jf, j, ji[j, J_KIND], g)
        la = ax * py - ay * px + couple
        lb = g[2] * py - g[3] * px + couple
        _push(state, prep, k, a, b, px, py, la, lb)


@njit(cache=True)
def reactions(
    jf: np.ndarray, ji: np.ndarray, active: np.ndarray, prep: np.ndarray, rows: np.ndarray,
    state: np.ndarray, h: float,
) -> None:  # fmt: skip
    """Each active joint's force [N] and couple [N m] on B over the last substep ``h``."""
    for k in range(active.shape[0]):
        j = active[k]
        g = _geometry(prep, k, state, rows[k, 0], rows[k, 1])
        px, py, _, _, couple, _ = _impulses(jf, j, ji[j, J_KIND], g)
        jf[j, FX] = px / h
        jf[j, FY] = py / h
        jf[j, TORQUE] = couple / h


@njit(cache=True)
def by_body(rows: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The active joints of each body (the rows of :func:`prepare`), as ``start`` (n + 2,)
    and ``members``: body i's are ``members[start[i]:start[i + 1]]`` (the world's dummy row
    ``n`` included)."""
    count = np.zeros(n + 2, np.int64)
    for k in range(rows.shape[0]):
        count[rows[k, 0] + 1] += 1
        count[rows[k, 1] + 1] += 1
    start = np.cumsum(count)
    members = np.empty(max(start[-1], 1), np.int64)
    filled = start[:-1].copy()
    for k in range(rows.shape[0]):
        for side in range(2):
            body = rows[k, side]
            members[filled[body]] = k
            filled[body] += 1
    return start, members


#: a rope shorter than its most length by this fraction of it is slack
SLACK = 0.005
#: an impact is taken first only where its bodies' joints would take no more than this
#: share of its impulse: the square of the cosine between the impact's normal and a
#: constrained direction (1%: a string within 6 degrees of square to the impact)
FREE_SHARE = 0.01


@njit(cache=True)
def resists(
    jf: np.ndarray, ji: np.ndarray, active: np.ndarray, prep: np.ndarray, rows: np.ndarray,
    start: np.ndarray, members: np.ndarray, state: np.ndarray, body: int, nx: float,
    ny: float,
) -> bool:  # fmt: skip
    """Whether a joint of ``body`` holds it along the direction ``(nx, ny)`` now: a pin,
    weld or slider's sideways hold always; a rod or taut rope whose line is not square to it
    (:data:`FREE_SHARE`). A spring, a target joint and a slack rope give way, as does a
    slider along its axis."""
    for at in range(start[body], start[body + 1]):
        k = members[at]
        j = active[k]
        kind = ji[j, J_KIND]
        if kind == TARGET:
            continue
        if kind in (REVOLUTE, WELD):
            return True
        g = _geometry(prep, k, state, rows[k, 0], rows[k, 1])
        if kind == DISTANCE:
            length, ux, uy = _line(g)
            if ji[j, J_FLAGS] & FLAG_SPRING and jf[j, HERTZ] > 0.0:
                continue
            if jf[j, LOWER] < length < (1.0 - SLACK) * jf[j, UPPER]:
                continue  # a slack rope
        else:  # PRISMATIC, WHEEL: held square to the axis
            ux, uy = -g[7], g[6]
        c = ux * nx + uy * ny
        if c * c > FREE_SHARE:
            return True
    return False
