"""The soft-step contact solver in 3D, in the 2D engine's named stages
(:mod:`carom.engines.rigid.solver`; Box2D v3's soft step, Catto 2024).

One step of ``dt`` is split into ``n`` substeps of ``h = dt/n``. Each substep **integrates
velocities** (gravity),
**warm-starts** every contact point with the impulse it ended the last substep with, **solves**
the contacts once with a soft bias that pushes overlapping bodies apart, **integrates
positions** (the centre by ``h v``; the orientation turned torque-free with its angular
momentum kept, :func:`.motion.free_turn`, which carries the gyroscopic term), and **relaxes**
once without the bias. After the substeps one **restitution** pass gives contacts that were
approaching faster than the threshold their bounce.

A contact point is a spring-damper (frequency ``f``, damping ratio ``zeta``) solved implicitly
over the substep, as in 2D; a point still apart is speculative and only stops the gap from
closing faster than ``s/h``. The separation within the step needs no new collision test: the
normal and anchors stay fixed, and ``s = base + (dx_A + dR_A c_A - dx_B - dR_B c_B) . n`` with
``dx`` each body's move and ``dR`` its turn since the step began, at the core anchors ``c``
(:mod:`.contacts`: a rolling ball's separation does not change).

Friction is Coulomb's cone per point: the tangent impulse along ``t1`` and ``t2`` is solved
from each direction's effective mass, then the pair is scaled back into the disk
``|j_t| <= mu j_n``. Rolling resistance is an angular impulse about the two tangents against the
bodies' relative rolling, within the disk ``|j_r| <= c_r sum j_n`` (``c_r`` a length [m], the
rolling-resistance coefficient: the torque needed to roll a body is ``c_r`` times the load).

The inverse inertia in the world frame is taken at the step's start and kept over its
substeps for the impulses, as Box2D does with its bodies' inertia.

**Layout: colours and lanes**, as in 2D (:mod:`carom.engines.rigid.solver`, Box2D v3's
graph colouring and wide solver): the contacts are coloured so that no two of a colour share a
body that impulses move (:func:`carom.engines.stepped.solver.color_groups`), each colour cut into
groups of ``LANES = 16`` contacts; a group's rows (its normal and tangents, softness, both
bodies' inverse masses and world inverse tensors, and each of its four points' anchors,
masses and impulses) are followed by rows for its bodies' velocities, moves and turns since
the step began, loaded from the bodies before each pass over the group and stored back after
(the pass works on the group in place: only the bodies are copied), and every stage runs over
the sixteen lanes at once, which the compiler turns into vector instructions. A contact of
fewer than four points fills the rest with points that never touch. The lanes of a group are
independent, so this is Gauss-Seidel in colour order: per contact, the same arithmetic as one
contact after another. Each body's velocity, angular velocity, move and turn share one row of
the solver's state; padding lanes join a dummy body that nothing moves.

Vectors are multiplied in scalars, never with ``@`` (Numba's ``@`` calls BLAS through SciPy).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.rigid3d import joints
from carom.engines.rigid3d.contacts import (
    F_E,
    F_JR1,
    F_JR2,
    F_MU,
    F_NX,
    F_NY,
    F_NZ,
    F_ROLL,
    F_T1X,
    F_T1Y,
    F_T1Z,
    F_T2X,
    F_T2Y,
    F_T2Z,
    I_FLAGS,
    P_BASE,
    P_JN,
    P_JT1,
    P_JT2,
    P_KA,
    P_KB,
    P_NMASS,
    P_RAX,
    P_T1MASS,
    P_T2MASS,
    P_TOTAL,
    P_VREL,
    POINT0,
    POINT_FLOATS,
    point_offset,
)
from carom.engines.rigid3d.motion import (
    apply_impulse,
    free_turn,
    relative_velocity,
    world_inverse_inertia,
)
from carom.engines.stepped import solver as shared
from carom.engines.stepped.joints import joint_softness
from carom.engines.stepped.rows import I_BODY_A, I_BODY_B, I_COUNT
from carom.engines.stepped.solver import LANE_MATH, LANES, soft_bias
from carom.geometry.manifold3d import MAX_POINTS
from carom.geometry.rotation import axis_angle_matrix, matrix
from carom.jit import leaf

__all__ = ["solve_step"]


# rows of a group (each LANES wide, row r from r * LANES on): the contact's ...
R_N = 0  # normal (3 rows), from B to A
R_T1 = 3  # first tangent (3)
R_T2 = 6  # second tangent (3)
R_MU = 9
R_RATE = 10  # soft bias rate [1/s]
R_MSCALE = 11  # soft mass scale [-]
R_ISCALE = 12  # soft impulse scale [-]
R_IMA = 13  # body A's inverse mass [1/kg]
R_IMB = 14
R_IWA = 15  # body A's inverse inertia in the world, row-major (9 rows) [1/(kg m^2)]
R_IWB = 24
R_ROLL = 33  # rolling resistance [m]
R_JR1 = 34  # rolling impulse about t1, t2 [N m s]
R_JR2 = 35
R_RM1 = 36  # angular effective masses about t1, t2 [kg m^2]
R_RM2 = 37
R_POINT = 38  # point p's rows start at R_POINT + p * POINT_ROWS
Q_RA = 0  # anchor on A (3) [m]
Q_RB = 3  # anchor on B (3)
Q_KA = 6  # core anchors along n [m]
Q_KB = 7
Q_BASE = 8
Q_NMASS = 9
Q_T1MASS = 10
Q_T2MASS = 11
Q_JN = 12
Q_JT1 = 13
Q_JT2 = 14
Q_TOTAL = 15
POINT_ROWS = 16
GROUP_ROWS = R_POINT + MAX_POINTS * POINT_ROWS
# ... then its two bodies' velocities, moves and turns, loaded for each pass
B_VA = GROUP_ROWS  # velocity of A (3) [m/s]
B_WA = GROUP_ROWS + 3  # angular velocity of A (3) [rad/s]
B_VB = GROUP_ROWS + 6
B_WB = GROUP_ROWS + 9
B_D = GROUP_ROWS + 12  # A's move less B's since the step began (3) [m]
B_TA = GROUP_ROWS + 15  # A's turn since the step began, row-major (9)
B_TB = GROUP_ROWS + 24
BUFFER_ROWS = GROUP_ROWS + 33
# columns of a body's row in the solver's state (N+1, STATE_COLS)
S_V = 0  # velocity (3)
S_W = 3  # angular velocity (3)
S_D = 6  # move since the step began (3)
S_T = 9  # turn since the step began, row-major (9)
STATE_COLS = 18


@njit(cache=True, inline="always")
def _turning(body: int, r: np.ndarray, dx: float, dy: float, dz: float, iw: np.ndarray) -> float:
    """``(r x d) . I^-1 (r x d)`` of one body [1/kg]."""
    cx = r[1] * dz - r[2] * dy
    cy = r[2] * dx - r[0] * dz
    cz = r[0] * dy - r[1] * dx
    total: float = (
        cx * (iw[body, 0] * cx + iw[body, 1] * cy + iw[body, 2] * cz)
        + cy * (iw[body, 3] * cx + iw[body, 4] * cy + iw[body, 5] * cz)
        + cz * (iw[body, 6] * cx + iw[body, 7] * cy + iw[body, 8] * cz)
    )
    return total


@njit(cache=True, inline="always")
def _mass_along(
    a: int, b: int, r_a: np.ndarray, r_b: np.ndarray, dx: float, dy: float, dz: float,
    inv_mass: np.ndarray, iw: np.ndarray,
) -> float:  # fmt: skip
    """``1 / (m_A^-1 + m_B^-1 + (r_A x d) . I_A^-1 (r_A x d) + (r_B x d) . I_B^-1 (r_B x d))``,
    the effective mass along unit ``d`` [kg] (0 if nothing can move)."""
    k = inv_mass[a] + inv_mass[b]
    k += _turning(a, r_a, dx, dy, dz, iw) + _turning(b, r_b, dx, dy, dz, iw)
    return 1.0 / k if k > 0.0 else 0.0


@njit(cache=True, inline="always")
def _angular_mass(a: int, b: int, dx: float, dy: float, dz: float, iw: np.ndarray) -> float:
    """``1 / (d . (I_A^-1 + I_B^-1) d)``: the angular effective mass about unit ``d``
    [kg m^2] (0 if neither body can turn)."""
    k = 0.0
    for body in range(2):
        c = a if body == 0 else b
        k += (
            dx * (iw[c, 0] * dx + iw[c, 1] * dy + iw[c, 2] * dz)
            + dy * (iw[c, 3] * dx + iw[c, 4] * dy + iw[c, 5] * dz)
            + dz * (iw[c, 6] * dx + iw[c, 7] * dy + iw[c, 8] * dz)
        )
    return 1.0 / k if k > 0.0 else 0.0


@njit(cache=True, inline="always")
def _fixed_work(
    a: int, b: int, px: float, py: float, pz: float, r_a: np.ndarray, r_b: np.ndarray,
    inv_mass: np.ndarray, v: np.ndarray, w: np.ndarray,
) -> float:  # fmt: skip
    """Work [J] that an impulse ``P`` on A (``-P`` on B) does through a body of infinite mass:
    the impulse on the other body times the fixed body's velocity at the point."""
    total = 0.0
    if inv_mass[a] == 0.0:
        ux = v[a, 0] + w[a, 1] * r_a[2] - w[a, 2] * r_a[1]
        uy = v[a, 1] + w[a, 2] * r_a[0] - w[a, 0] * r_a[2]
        uz = v[a, 2] + w[a, 0] * r_a[1] - w[a, 1] * r_a[0]
        total -= px * ux + py * uy + pz * uz
    if inv_mass[b] == 0.0:
        ux = v[b, 0] + w[b, 1] * r_b[2] - w[b, 2] * r_b[1]
        uy = v[b, 1] + w[b, 2] * r_b[0] - w[b, 0] * r_b[2]
        uz = v[b, 2] + w[b, 0] * r_b[1] - w[b, 1] * r_b[0]
        total += px * ux + py * uy + pz * uz
    return total


@njit(cache=True)
def _restitution(
    cf: np.ndarray, ci: np.ndarray, nc: int, threshold: float, inv_mass: np.ndarray,
    iw: np.ndarray, v: np.ndarray, w: np.ndarray, work: np.ndarray,
) -> None:  # fmt: skip
    """Points that approached faster than ``threshold`` and were pushed leave at ``-e`` times
    their approach speed (Newton's restitution, per point, in order)."""
    layout = (POINT0, POINT_FLOATS, P_VREL, P_TOTAL)
    todo = shared.bouncing(cf, ci, nc, threshold, I_FLAGS, F_E, layout)
    for k in range(todo.shape[0]):
        m = todo[k, 0]
        o = todo[k, 1]
        a = ci[m, I_BODY_A]
        b = ci[m, I_BODY_B]
        nx = cf[m, F_NX]
        ny = cf[m, F_NY]
        nz = cf[m, F_NZ]
        r_a = cf[m, o + P_RAX : o + P_RAX + 3]
        r_b = cf[m, o + P_RAX + 3 : o + P_RAX + 6]
        ux, uy, uz = relative_velocity(a, b, r_a, r_b, v, w)
        un = ux * nx + uy * ny + uz * nz
        dj = shared.restitution_impulse(cf, m, o, un, cf[m, F_E], P_JN, P_NMASS, P_VREL, P_TOTAL)
        work[0] += _fixed_work(a, b, dj * nx, dj * ny, dj * nz, r_a, r_b, inv_mass, v, w)
        apply_impulse(a, b, dj * nx, dj * ny, dj * nz, r_a, r_b, inv_mass, iw, v, w)


@njit(cache=True)
def _pack(
    cf: np.ndarray, ci: np.ndarray, lanes: np.ndarray, inv_mass: np.ndarray, iw: np.ndarray,
    state: np.ndarray, soft_moving: tuple[float, float, float],
    soft_fixed: tuple[float, float, float], group: np.ndarray, pair: np.ndarray,
    kinematic: np.ndarray, rolling: np.ndarray,
) -> None:  # fmt: skip
    """Copy the contacts of ``lanes`` into ``group`` (G, BUFFER_ROWS * LANES), with each
    point's effective masses along the normal and the tangents, and the rolling masses; their
    bodies into ``pair`` (G, 2 * LANES); ``kinematic[g]``: a lane of group g touches a moving
    body of infinite mass; ``rolling[g]``: a lane of group g has rolling resistance. Padding
    lanes join the dummy body (the state's last row)."""
    dummy = state.shape[0] - 1
    for g in range(lanes.shape[0]):
        kinematic[g] = False
        rolling[g] = False
        for lane in range(LANES):
            m = lanes[g, lane]
            if m < 0:
                shared.pad_lane(
                    group, pair, g, lane, dummy, GROUP_ROWS, R_POINT, POINT_ROWS, MAX_POINTS, Q_BASE
                )
                continue
            a, b = shared.pack_pair(
                ci, m, group, pair, g, lane, inv_mass, soft_moving, soft_fixed, cf[m, F_MU],
                (R_MU, R_RATE, R_MSCALE, R_ISCALE, R_IMA, R_IMB),
            )  # fmt: skip
            for k in range(3):
                group[g, (R_N + k) * LANES + lane] = cf[m, F_NX + k]
                group[g, (R_T1 + k) * LANES + lane] = cf[m, F_T1X + k]
                group[g, (R_T2 + k) * LANES + lane] = cf[m, F_T2X + k]
            for k in range(9):
                group[g, (R_IWA + k) * LANES + lane] = iw[a, k]
                group[g, (R_IWB + k) * LANES + lane] = iw[b, k]
            group[g, R_ROLL * LANES + lane] = cf[m, F_ROLL]
            rolling[g] = rolling[g] or cf[m, F_ROLL] > 0.0
            group[g, R_JR1 * LANES + lane] = cf[m, F_JR1]
            group[g, R_JR2 * LANES + lane] = cf[m, F_JR2]
            group[g, R_RM1 * LANES + lane] = _angular_mass(
                a, b, cf[m, F_T1X], cf[m, F_T1Y], cf[m, F_T1Z], iw
            )
            group[g, R_RM2 * LANES + lane] = _angular_mass(
                a, b, cf[m, F_T2X], cf[m, F_T2Y], cf[m, F_T2Z], iw
            )
            count = ci[m, I_COUNT]
            for p in range(MAX_POINTS):
                q = R_POINT + p * POINT_ROWS
                if p >= count:
                    shared.absent_point(group, g, lane, q, POINT_ROWS, Q_BASE)
                    continue
                o = point_offset(p)
                r_a = cf[m, o + P_RAX : o + P_RAX + 3]
                r_b = cf[m, o + P_RAX + 3 : o + P_RAX + 6]
                for k in range(3):
                    group[g, (q + Q_RA + k) * LANES + lane] = r_a[k]
                    group[g, (q + Q_RB + k) * LANES + lane] = r_b[k]
                group[g, (q + Q_KA) * LANES + lane] = cf[m, o + P_KA]
                group[g, (q + Q_KB) * LANES + lane] = cf[m, o + P_KB]
                group[g, (q + Q_BASE) * LANES + lane] = cf[m, o + P_BASE]
                group[g, (q + Q_NMASS) * LANES + lane] = _mass_along(
                    a, b, r_a, r_b, cf[m, F_NX], cf[m, F_NY], cf[m, F_NZ], inv_mass, iw
                )
                group[g, (q + Q_T1MASS) * LANES + lane] = _mass_along(
                    a, b, r_a, r_b, cf[m, F_T1X], cf[m, F_T1Y], cf[m, F_T1Z], inv_mass, iw
                )
                group[g, (q + Q_T2MASS) * LANES + lane] = _mass_along(
                    a, b, r_a, r_b, cf[m, F_T2X], cf[m, F_T2Y], cf[m, F_T2Z], inv_mass, iw
                )
                group[g, (q + Q_JN) * LANES + lane] = cf[m, o + P_JN]
                group[g, (q + Q_JT1) * LANES + lane] = cf[m, o + P_JT1]
                group[g, (q + Q_JT2) * LANES + lane] = cf[m, o + P_JT2]
                group[g, (q + Q_TOTAL) * LANES + lane] = 0.0
            for body in (a, b):
                if inv_mass[body] == 0.0:
                    for k in range(6):
                        if state[body, S_V + k] != 0.0:
                            kinematic[g] = True


@leaf
def _unpack(group: np.ndarray, lanes: np.ndarray, ci: np.ndarray, cf: np.ndarray) -> None:
    """Copy each point's impulses, its total and its masses (:func:`.shared.unpack`), and
    the rolling impulses, back to its contact row."""
    shared.unpack(
        group, lanes, ci, cf, (R_POINT, POINT_ROWS, POINT0, POINT_FLOATS, MAX_POINTS),
        (P_JN, P_JT1, P_JT2, P_TOTAL, P_NMASS, P_T1MASS, P_T2MASS),
        (Q_JN, Q_JT1, Q_JT2, Q_TOTAL, Q_NMASS, Q_T1MASS, Q_T2MASS), False,
    )  # fmt: skip
    for g in range(lanes.shape[0]):
        for lane in range(LANES):
            m = lanes[g, lane]
            if m >= 0:
                cf[m, F_JR1] = group[g, R_JR1 * LANES + lane]
                cf[m, F_JR2] = group[g, R_JR2 * LANES + lane]


@njit(cache=True, inline="always")
def _gather(buf: np.ndarray, pair: np.ndarray, g: int, state: np.ndarray) -> None:
    """Group g's bodies' velocities into its rows ``buf`` (``group[g]``): the passes work on
    the group in place, so only the bodies are copied in and out."""
    for lane in range(LANES):
        a = pair[g, lane]
        b = pair[g, LANES + lane]
        for k in range(3):
            buf[(B_VA + k) * LANES + lane] = state[a, S_V + k]
            buf[(B_WA + k) * LANES + lane] = state[a, S_W + k]
            buf[(B_VB + k) * LANES + lane] = state[b, S_V + k]
            buf[(B_WB + k) * LANES + lane] = state[b, S_W + k]


@njit(cache=True, inline="always")
def _gather_all(buf: np.ndarray, pair: np.ndarray, g: int, state: np.ndarray) -> None:
    """Group g's bodies' velocities, moves and turns since the step began into its rows."""
    _gather(buf, pair, g, state)
    for lane in range(LANES):
        a = pair[g, lane]
        b = pair[g, LANES + lane]
        for k in range(3):
            buf[(B_D + k) * LANES + lane] = state[a, S_D + k] - state[b, S_D + k]
        for k in range(9):
            buf[(B_TA + k) * LANES + lane] = state[a, S_T + k]
            buf[(B_TB + k) * LANES + lane] = state[b, S_T + k]


@njit(cache=True, inline="always")
def _scatter(buf: np.ndarray, pair: np.ndarray, g: int, state: np.ndarray) -> None:
    """The velocities back to group g's bodies. Lanes sharing a body of infinite mass write
    back the value they all read."""
    for lane in range(LANES):
        a = pair[g, lane]
        b = pair[g, LANES + lane]
        for k in range(3):
            state[a, S_V + k] = buf[(B_VA + k) * LANES + lane]
            state[a, S_W + k] = buf[(B_WA + k) * LANES + lane]
            state[b, S_V + k] = buf[(B_VB + k) * LANES + lane]
            state[b, S_W + k] = buf[(B_WB + k) * LANES + lane]


@njit(cache=True, inline="always")
def _impulses(buf: np.ndarray, before: np.ndarray) -> None:
    """Group rows ``buf``'s point impulses (normal, two tangents) into ``before``
    (MAX_POINTS * 3 * LANES), to tell what a pass added."""
    for p in range(MAX_POINTS):
        q = R_POINT + p * POINT_ROWS
        for c in range(3):
            for lane in range(LANES):
                before[(3 * p + c) * LANES + lane] = buf[(q + Q_JN + c) * LANES + lane]


@njit(cache=True, inline="always")
def _spin(
    buf: np.ndarray, lane: int, row: int, jx: float, jy: float, jz: float
) -> tuple[float, float, float]:
    """The world inverse tensor in rows ``row`` to ``row + 8`` (one lane) times (jx, jy, jz)."""
    return (
        buf[row * LANES + lane] * jx + buf[(row + 1) * LANES + lane] * jy
        + buf[(row + 2) * LANES + lane] * jz,
        buf[(row + 3) * LANES + lane] * jx + buf[(row + 4) * LANES + lane] * jy
        + buf[(row + 5) * LANES + lane] * jz,
        buf[(row + 6) * LANES + lane] * jx + buf[(row + 7) * LANES + lane] * jy
        + buf[(row + 8) * LANES + lane] * jz,
    )  # fmt: skip


@njit(cache=True, inline="always")
def _push(buf: np.ndarray, lane: int, q: int, px: float, py: float, pz: float) -> None:
    """Impulse ``P`` on A at point q's ``r_A`` and ``-P`` on B at its ``r_B`` (one lane; as
    :func:`.motion.apply_impulse`)."""
    ma = buf[R_IMA * LANES + lane]
    mb = buf[R_IMB * LANES + lane]
    rax = buf[(q + Q_RA) * LANES + lane]
    ray = buf[(q + Q_RA + 1) * LANES + lane]
    raz = buf[(q + Q_RA + 2) * LANES + lane]
    rbx = buf[(q + Q_RB) * LANES + lane]
    rby = buf[(q + Q_RB + 1) * LANES + lane]
    rbz = buf[(q + Q_RB + 2) * LANES + lane]
    buf[B_VA * LANES + lane] += ma * px
    buf[(B_VA + 1) * LANES + lane] += ma * py
    buf[(B_VA + 2) * LANES + lane] += ma * pz
    dx, dy, dz = _spin(
        buf, lane, R_IWA, ray * pz - raz * py, raz * px - rax * pz, rax * py - ray * px
    )
    buf[B_WA * LANES + lane] += dx
    buf[(B_WA + 1) * LANES + lane] += dy
    buf[(B_WA + 2) * LANES + lane] += dz
    buf[B_VB * LANES + lane] -= mb * px
    buf[(B_VB + 1) * LANES + lane] -= mb * py
    buf[(B_VB + 2) * LANES + lane] -= mb * pz
    dx, dy, dz = _spin(
        buf, lane, R_IWB, rby * pz - rbz * py, rbz * px - rbx * pz, rbx * py - rby * px
    )
    buf[B_WB * LANES + lane] -= dx
    buf[(B_WB + 1) * LANES + lane] -= dy
    buf[(B_WB + 2) * LANES + lane] -= dz


@njit(cache=True, inline="always")
def _point_velocity(
    buf: np.ndarray, lane: int, v: int, w: int, r: int
) -> tuple[float, float, float]:
    """``v + w x r`` of one body (rows ``v``, ``w``) at a point's anchor (rows ``r``)."""
    rx = buf[r * LANES + lane]
    ry = buf[(r + 1) * LANES + lane]
    rz = buf[(r + 2) * LANES + lane]
    wx = buf[w * LANES + lane]
    wy = buf[(w + 1) * LANES + lane]
    wz = buf[(w + 2) * LANES + lane]
    return (
        buf[v * LANES + lane] + wy * rz - wz * ry,
        buf[(v + 1) * LANES + lane] + wz * rx - wx * rz,
        buf[(v + 2) * LANES + lane] + wx * ry - wy * rx,
    )


@njit(cache=True, inline="always")
def _slip(buf: np.ndarray, lane: int, q: int) -> tuple[float, float, float]:
    """Velocity [m/s] of A's point at point q's ``r_A`` less B's at its ``r_B`` (one lane;
    as :func:`.motion.relative_velocity`)."""
    ax, ay, az = _point_velocity(buf, lane, B_VA, B_WA, q + Q_RA)
    bx, by, bz = _point_velocity(buf, lane, B_VB, B_WB, q + Q_RB)
    return ax - bx, ay - by, az - bz


@njit(cache=True, inline="always")
def _impulse(
    buf: np.ndarray, lane: int, jn: float, j1: float, j2: float
) -> tuple[float, float, float]:
    """The impulse ``jn n + j1 t1 + j2 t2`` [N s] of one lane's contact, as a vector."""
    return (
        jn * buf[R_N * LANES + lane] + j1 * buf[R_T1 * LANES + lane]
        + j2 * buf[R_T2 * LANES + lane],
        jn * buf[(R_N + 1) * LANES + lane] + j1 * buf[(R_T1 + 1) * LANES + lane]
        + j2 * buf[(R_T2 + 1) * LANES + lane],
        jn * buf[(R_N + 2) * LANES + lane] + j1 * buf[(R_T1 + 2) * LANES + lane]
        + j2 * buf[(R_T2 + 2) * LANES + lane],
    )  # fmt: skip


@leaf
def _group_work(buf: np.ndarray, before: np.ndarray, warm: bool) -> float:
    """Work [J] done on the group in rows ``buf`` by its bodies of infinite mass, for the
    impulses it holds beyond those in ``before`` (:func:`_impulses`; all of them, if
    ``warm``): the impulse on the other body times the fixed body's velocity at the point
    (:func:`_fixed_work`); such a body's velocity is the same before and after."""
    total = 0.0
    for lane in range(LANES):
        for p in range(MAX_POINTS):
            q = R_POINT + p * POINT_ROWS
            dn = buf[(q + Q_JN) * LANES + lane]
            d1 = buf[(q + Q_JT1) * LANES + lane]
            d2 = buf[(q + Q_JT2) * LANES + lane]
            if not warm:
                dn -= before[3 * p * LANES + lane]
                d1 -= before[(3 * p + 1) * LANES + lane]
                d2 -= before[(3 * p + 2) * LANES + lane]
            px, py, pz = _impulse(buf, lane, dn, d1, d2)
            if buf[R_IMA * LANES + lane] == 0.0:
                ux, uy, uz = _point_velocity(buf, lane, B_VA, B_WA, q + Q_RA)
                total -= px * ux + py * uy + pz * uz
            if buf[R_IMB * LANES + lane] == 0.0:
                ux, uy, uz = _point_velocity(buf, lane, B_VB, B_WB, q + Q_RB)
                total += px * ux + py * uy + pz * uz
    return total


@njit(cache=True, fastmath=LANE_MATH)
def _warm_start(
    group: np.ndarray, pair: np.ndarray, kinematic: np.ndarray, rolling: np.ndarray,
    state: np.ndarray, work: np.ndarray,
) -> None:  # fmt: skip
    """Apply every point's impulse, and each contact's rolling impulse, from the last
    substep (or step) again."""
    before = np.empty(0)
    for g in range(group.shape[0]):
        buf = group[g]
        _gather(buf, pair, g, state)
        for p in range(MAX_POINTS):
            q = R_POINT + p * POINT_ROWS
            for lane in range(LANES):
                jn = buf[(q + Q_JN) * LANES + lane]
                j1 = buf[(q + Q_JT1) * LANES + lane]
                j2 = buf[(q + Q_JT2) * LANES + lane]
                px, py, pz = _impulse(buf, lane, jn, j1, j2)
                buf[(q + Q_TOTAL) * LANES + lane] += jn
                _push(buf, lane, q, px, py, pz)
        if rolling[g]:  # (a group without rolling resistance holds no rolling impulse)
            for lane in range(LANES):
                _roll(buf, lane, buf[R_JR1 * LANES + lane], buf[R_JR2 * LANES + lane])
        if kinematic[g]:
            work[0] += _group_work(buf, before, True)
        _scatter(buf, pair, g, state)


@njit(cache=True, inline="always")
def _roll(buf: np.ndarray, lane: int, d1: float, d2: float) -> None:
    """Angular impulse ``d1 t1 + d2 t2`` on A and its opposite on B (one lane)."""
    jx = d1 * buf[R_T1 * LANES + lane] + d2 * buf[R_T2 * LANES + lane]
    jy = d1 * buf[(R_T1 + 1) * LANES + lane] + d2 * buf[(R_T2 + 1) * LANES + lane]
    jz = d1 * buf[(R_T1 + 2) * LANES + lane] + d2 * buf[(R_T2 + 2) * LANES + lane]
    dx, dy, dz = _spin(buf, lane, R_IWA, jx, jy, jz)
    buf[B_WA * LANES + lane] += dx
    buf[(B_WA + 1) * LANES + lane] += dy
    buf[(B_WA + 2) * LANES + lane] += dz
    dx, dy, dz = _spin(buf, lane, R_IWB, jx, jy, jz)
    buf[B_WB * LANES + lane] -= dx
    buf[(B_WB + 1) * LANES + lane] -= dy
    buf[(B_WB + 2) * LANES + lane] -= dz


@njit(cache=True, fastmath=LANE_MATH)
def _solve(
    group: np.ndarray, pair: np.ndarray, kinematic: np.ndarray, rolling: np.ndarray,
    state: np.ndarray, inv_h: float, use_bias: bool, push_speed: float, work: np.ndarray,
) -> None:  # fmt: skip
    """One Gauss-Seidel pass over the groups: normal impulses, friction, rolling resistance,
    lane by lane. ``state`` (N+1, STATE_COLS: velocity, angular velocity, move and turn since
    the step began) has a row for each body and one for the padding lanes' dummy;
    ``work[0]`` gathers what kinematic bodies do."""
    load = np.empty(LANES)
    before = np.empty(MAX_POINTS * 3 * LANES)
    for g in range(group.shape[0]):
        buf = group[g]
        _gather_all(buf, pair, g, state)
        if kinematic[g]:
            _impulses(buf, before)
        for lane in range(LANES):
            load[lane] = 0.0
        for p in range(MAX_POINTS):
            q = R_POINT + p * POINT_ROWS
            for lane in range(LANES):
                nx = buf[R_N * LANES + lane]
                ny = buf[(R_N + 1) * LANES + lane]
                nz = buf[(R_N + 2) * LANES + lane]
                ka = buf[(q + Q_KA) * LANES + lane]
                kb = buf[(q + Q_KB) * LANES + lane]
                # the separation now: core anchors turned by each body's turn since the step
                # began
                ax = buf[(q + Q_RA) * LANES + lane] + ka * nx
                ay = buf[(q + Q_RA + 1) * LANES + lane] + ka * ny
                az = buf[(q + Q_RA + 2) * LANES + lane] + ka * nz
                bx = buf[(q + Q_RB) * LANES + lane] - kb * nx
                by = buf[(q + Q_RB + 1) * LANES + lane] - kb * ny
                bz = buf[(q + Q_RB + 2) * LANES + lane] - kb * nz
                tax, tay, taz = _spin(buf, lane, B_TA, ax, ay, az)
                tbx, tby, tbz = _spin(buf, lane, B_TB, bx, by, bz)
                sx = buf[B_D * LANES + lane] + tax - tbx
                sy = buf[(B_D + 1) * LANES + lane] + tay - tby
                sz = buf[(B_D + 2) * LANES + lane] + taz - tbz
                s = buf[(q + Q_BASE) * LANES + lane] + sx * nx + sy * ny + sz * nz
                mass_scale, impulse_scale, bias = soft_bias(
                    s, use_bias, inv_h, push_speed, buf[R_RATE * LANES + lane],
                    buf[R_MSCALE * LANES + lane], buf[R_ISCALE * LANES + lane],
                )  # fmt: skip
                ux, uy, uz = _slip(buf, lane, q)
                new, dj = shared.normal_impulse(
                    buf, lane, q + Q_JN, q + Q_NMASS, q + Q_TOTAL, ux * nx + uy * ny + uz * nz,
                    mass_scale, impulse_scale, bias,
                )  # fmt: skip
                load[lane] += new
                _push(buf, lane, q, dj * nx, dj * ny, dj * nz)
        for p in range(MAX_POINTS):
            q = R_POINT + p * POINT_ROWS
            for lane in range(LANES):
                t1x = buf[R_T1 * LANES + lane]
                t1y = buf[(R_T1 + 1) * LANES + lane]
                t1z = buf[(R_T1 + 2) * LANES + lane]
                t2x = buf[R_T2 * LANES + lane]
                t2y = buf[(R_T2 + 1) * LANES + lane]
                t2z = buf[(R_T2 + 2) * LANES + lane]
                ux, uy, uz = _slip(buf, lane, q)
                j1 = buf[(q + Q_JT1) * LANES + lane]
                j2 = buf[(q + Q_JT2) * LANES + lane]
                n1 = j1 - buf[(q + Q_T1MASS) * LANES + lane] * (ux * t1x + uy * t1y + uz * t1z)
                n2 = j2 - buf[(q + Q_T2MASS) * LANES + lane] * (ux * t2x + uy * t2y + uz * t2z)
                limit = buf[R_MU * LANES + lane] * buf[(q + Q_JN) * LANES + lane]
                # back into the cone |j_t| <= limit: scaled by limit / |j_t| beyond it, by
                # exactly 1 within it (no branch: the lanes stay in vector registers)
                size = math.sqrt(n1 * n1 + n2 * n2)
                scale = limit / max(size, limit, 1e-300)
                n1 *= scale
                n2 *= scale
                d1 = n1 - j1
                d2 = n2 - j2
                buf[(q + Q_JT1) * LANES + lane] = n1
                buf[(q + Q_JT2) * LANES + lane] = n2
                _push(buf, lane, q, d1 * t1x + d2 * t2x, d1 * t1y + d2 * t2y, d1 * t1z + d2 * t2z)
        if rolling[g]:  # (a group without rolling resistance keeps zero rolling impulses)
            for lane in range(LANES):
                # rolling resistance, in every lane (no branch: a lane without it has a zero limit
                # and keeps a zero impulse)
                wx = buf[B_WA * LANES + lane] - buf[B_WB * LANES + lane]
                wy = buf[(B_WA + 1) * LANES + lane] - buf[(B_WB + 1) * LANES + lane]
                wz = buf[(B_WA + 2) * LANES + lane] - buf[(B_WB + 2) * LANES + lane]
                t1x = buf[R_T1 * LANES + lane]
                t1y = buf[(R_T1 + 1) * LANES + lane]
                t1z = buf[(R_T1 + 2) * LANES + lane]
                t2x = buf[R_T2 * LANES + lane]
                t2y = buf[(R_T2 + 1) * LANES + lane]
                t2z = buf[(R_T2 + 2) * LANES + lane]
                j1 = buf[R_JR1 * LANES + lane]
                j2 = buf[R_JR2 * LANES + lane]
                n1 = j1 - buf[R_RM1 * LANES + lane] * (wx * t1x + wy * t1y + wz * t1z)
                n2 = j2 - buf[R_RM2 * LANES + lane] * (wx * t2x + wy * t2y + wz * t2z)
                limit = buf[R_ROLL * LANES + lane] * load[lane]
                size = math.sqrt(n1 * n1 + n2 * n2)
                scale = limit / max(size, limit, 1e-300)
                n1 *= scale
                n2 *= scale
                buf[R_JR1 * LANES + lane] = n1
                buf[R_JR2 * LANES + lane] = n2
                _roll(buf, lane, n1 - j1, n2 - j2)
        if kinematic[g]:
            work[0] += _group_work(buf, before, False)
        _scatter(buf, pair, g, state)


@njit(cache=True, inline="always")
def _spin_up(state: np.ndarray, i: int, iw: np.ndarray, t: np.ndarray, h: float) -> None:
    """Body ``i``'s spin in the solver's ``state`` gains ``h I^-1 T`` (``iw`` (9,) its world
    inverse inertia, row by row; ``t`` (3,) the torque [N m]; ``h`` the substep [s])."""
    for a in range(3):
        state[i, S_W + a] += h * (iw[3 * a] * t[0] + iw[3 * a + 1] * t[1] + iw[3 * a + 2] * t[2])


@njit(cache=True)
def solve_step(
    cf: np.ndarray, ci: np.ndarray, nc: int, bodies: np.ndarray, inv_mass: np.ndarray,
    inertia: np.ndarray, inv_inertia: np.ndarray, accel: np.ndarray, torque: np.ndarray,
    movers: np.ndarray, x: np.ndarray, q: np.ndarray, v: np.ndarray, w: np.ndarray,
    knobs: tuple[float, int, float, float, float, float], work: np.ndarray, jf: np.ndarray,
    ji: np.ndarray, active: np.ndarray,
) -> None:  # fmt: skip
    """Advance the ``bodies`` (indices), their contacts and the joints ``active`` (rows of
    ``jf``, ``ji``: :mod:`.joints`) by one step, with ``knobs`` as in 2D
    (:func:`carom.engines.rigid.solver.solve_step`; the joints before the contacts in each
    pass, their reactions written after the last substep).

    Contacts flagged exact are skipped; every other contact must join bodies of ``bodies`` or
    a body that impulses do not move (static, kinematic: infinite mass); the kinematic ones
    among them are ``movers`` (indices), whose steady motion over the substeps counts in the
    contacts' separations (the driver moves them after the step). ``inertia`` and
    ``inv_inertia`` (N, 3, 3) are body-frame tensors; ``accel`` (N, 3) [m/s^2] is each body's
    acceleration (gravity, and the forces given for this step over the mass) and ``torque``
    (N, 3) [N m] the world torque given for this step, both entering the velocities each
    substep as in Box2D; ``work[0]`` gains the work kinematic bodies did on the others, and
    the torques' work on the bodies they turn [J].
    """
    dt, substeps, contact_hertz, damping_ratio, push_speed, restitution_threshold = knobs
    h, soft_moving, soft_fixed = shared.substep_softness(dt, substeps, contact_hertz, damping_ratio)
    n = x.shape[0]
    iw = np.zeros((n, 9))
    world_inverse_inertia(q, inv_inertia, iw)
    # every body's row, and a last one for the padding lanes' dummy (at rest, infinite mass)
    state = np.zeros((n + 1, STATE_COLS))
    for i in range(n):
        for k in range(3):
            state[i, S_V + k] = v[i, k]
            state[i, S_W + k] = w[i, k]
    for i in range(n + 1):
        state[i, S_T] = state[i, S_T + 4] = state[i, S_T + 8] = 1.0
    start = np.empty((n, 9))  # each body's rotation at the step's start
    r = np.empty(9)
    for i in bodies:
        matrix(q, i, r)
        start[i] = r
    lanes, group, pair, kinematic = shared.groups_of(ci, nc, inv_mass, I_FLAGS, BUFFER_ROWS)
    rolling = np.empty(lanes.shape[0], np.bool_)
    _pack(
        cf, ci, lanes, inv_mass, iw, state, soft_moving, soft_fixed, group, pair, kinematic,
        rolling,
    )  # fmt: skip
    turned = np.empty(9)
    elapsed = 0.0
    torqued = np.any(torque != 0.0)
    soft_joint = joint_softness(h, contact_hertz)
    prep, jrows = joints.prepare(jf, ji, active, x, q, inv_mass, iw, h)
    for _ in range(substeps):
        for i in bodies:
            for k in range(3):
                state[i, S_V + k] += h * accel[i, k]
            if torqued:
                _spin_up(state, i, iw[i], torque[i], h)
        joints.warm_start(jf, ji, active, prep, jrows, state)
        _warm_start(group, pair, kinematic, rolling, state, work)
        joints.solve(jf, ji, active, prep, jrows, state, h, soft_joint, True)
        _solve(group, pair, kinematic, rolling, state, 1.0 / h, True, push_speed, work)
        for i in bodies:
            for k in range(3):
                v[i, k] = state[i, S_V + k]
                w[i, k] = state[i, S_W + k]
                x[i, k] += h * v[i, k]
                state[i, S_D + k] += h * v[i, k]
            free_turn(i, h, 1, q, w, inertia, inv_inertia)
            if torqued:  # T . w over the substep, the w that turned the body
                work[0] += h * (
                    torque[i, 0] * w[i, 0] + torque[i, 1] * w[i, 1] + torque[i, 2] * w[i, 2]
                )
            for k in range(3):
                state[i, S_W + k] = w[i, k]  # the spin that carries the angular momentum
            # the turn since the step began: R(q) R(q_start)^T
            matrix(q, i, r)
            s0 = start[i]
            for a in range(3):
                for c in range(3):
                    state[i, S_T + 3 * a + c] = (
                        r[3 * a] * s0[3 * c] + r[3 * a + 1] * s0[3 * c + 1]
                        + r[3 * a + 2] * s0[3 * c + 2]
                    )  # fmt: skip
        elapsed += h
        for i in movers:  # kinematic bodies: their own steady motion (the driver moves them)
            for k in range(3):
                state[i, S_D + k] = elapsed * v[i, k]
            axis_angle_matrix(w[i, 0] * elapsed, w[i, 1] * elapsed, w[i, 2] * elapsed, turned)
            for k in range(9):
                state[i, S_T + k] = turned[k]
        joints.solve(jf, ji, active, prep, jrows, state, h, soft_joint, False)
        _solve(group, pair, kinematic, rolling, state, 1.0 / h, False, push_speed, work)
    joints.reactions(jf, ji, active, prep, jrows, state, h)
    for i in bodies:
        for k in range(3):
            v[i, k] = state[i, S_V + k]
            w[i, k] = state[i, S_W + k]
    _unpack(group, lanes, ci, cf)
    _restitution(cf, ci, nc, restitution_threshold, inv_mass, iw, v, w, work)
