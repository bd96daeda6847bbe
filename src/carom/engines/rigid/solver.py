"""The soft-step contact solver, in named stages (Box2D v3's "solver2d" soft step).

One step of ``dt`` is split into ``n`` substeps of ``h = dt/n``. Each substep integrates
velocities (gravity), warm-starts every contact point with the impulse it ended the last
substep with, solves the contacts once with a soft bias that pushes overlapping bodies apart,
integrates positions, and relaxes once without the bias (so the push leaves no velocity
behind). After the substeps one restitution pass gives contacts that were approaching faster
than the threshold their bounce, and the impulses are stored for the next step.

A contact is a spring-damper of frequency ``f`` and damping ratio ``zeta`` solved implicitly
over the substep (Catto, "Solver2D", 2024): with ``omega = 2 pi f``,
``a1 = 2 zeta + h omega``, ``a2 = h omega a1``, ``a3 = 1/(1 + a2)``, the bias rate is
``omega/a1``, the mass scale ``a2 a3`` and the impulse scale ``a3``. A point still apart
(separation ``s > 0``) is speculative: it only stops the gap from closing faster than
``s/h``. The separation within the step is tracked without new collision tests: the normal
and anchors stay fixed, and ``s = s_0 + (dx_A + R(dtheta_A) r_A - dx_B - R(dtheta_B) r_B) . n
- (r_A - r_B) . n``.

Friction is Coulomb's, ``|j_t| <= mu j_n`` per point, solved after the normal impulse.

**Layout: colours and lanes** (as Box2D v3's graph colouring and wide solver). The contacts
are coloured so that no two of one colour share a body that impulses move (static and
kinematic bodies take no colour: they are only read). Each colour is cut into groups of
``LANES = 16`` contacts, the *lanes*; a group is copied into one small buffer, its body
velocities gathered beside it, and every stage runs over the sixteen lanes at once, which the
compiler turns into vector instructions (two 8-wide registers a row with AVX-512: two
independent chains, which keeps the core busier than one; 8 lanes solve a pass 15% slower).
The lanes of a group are independent, so this is Gauss-Seidel in colour order: the same
arithmetic as one contact after another, in that order. A contact whose bodies have used all
64 colours gets a group to itself. Padding lanes join a dummy body that
nothing moves.

Every buffer is flat: row ``r`` of a group is ``LANES`` numbers from ``r * LANES`` on, with ``r``
a constant, so each row is one vector load; the group's rows (its contacts and both bodies'
inverse masses, fixed for the step) are copied as one run. Each body's velocity, move and turn
since the step began share one row of the solver's state (one cache line), gathered lane by
lane. (Working on the groups in place, as the 3D solver does, was measured: a pass 20% faster
on the large pyramid, whose groups stay in cache, but a step a third slower on many pyramids,
60,000 contacts and 14 MB of groups, whose rows the copy streams from memory where the passes
read in place would fetch them in the arithmetic's order.)
"""

from __future__ import annotations

import numpy as np
from numba import njit

from carom.engines.rigid import joints
from carom.engines.rigid.contacts import (
    F_E,
    F_MU,
    F_NX,
    F_NY,
    I_FLAGS,
    P_BASE,
    P_JN,
    P_JT,
    P_NMASS,
    P_RAX,
    P_RAY,
    P_RBX,
    P_RBY,
    P_TOTAL,
    P_VREL,
    POINT0,
    POINT_FLOATS,
    point_offset,
)
from carom.engines.rigid.motion import apply_impulse, fixed_work, relative_velocity
from carom.engines.stepped import solver as shared
from carom.engines.stepped.joints import joint_softness
from carom.engines.stepped.rows import FLAG_EXACT, FLAG_STRUCK, I_BODY_A, I_BODY_B, I_COUNT
from carom.engines.stepped.solver import LANE_MATH, LANES, soft_bias
from carom.geometry.rotation import cos_sin
from carom.jit import leaf

__all__ = ["solve_step"]

# rows of a group (each LANES wide, row r from r * LANES on): the contact ...
R_NX = 0
R_NY = 1
R_MU = 2
R_RATE = 3  # soft bias rate [1/s]
R_MSCALE = 4  # soft mass scale [-]
R_ISCALE = 5  # soft impulse scale [-]
R_IMA = 6  # body A's inverse mass [1/kg]
R_IIA = 7  # body A's inverse moment of inertia [1/(kg m^2)]
R_IMB = 8
R_IIB = 9
R_POINT = 10  # point p's rows start at R_POINT + p * POINT_ROWS
Q_RAX = 0
Q_RAY = 1
Q_RBX = 2
Q_RBY = 3
Q_BASE = 4
Q_NMASS = 5
Q_TMASS = 6
Q_JN = 7
Q_JT = 8
Q_TOTAL = 9
POINT_ROWS = 10
GROUP_ROWS = R_POINT + 2 * POINT_ROWS
# ... then, in the working buffer only, its two bodies' velocities and moves
B_VAX = GROUP_ROWS
B_VAY = GROUP_ROWS + 1
B_WA = GROUP_ROWS + 2
B_VBX = GROUP_ROWS + 3
B_VBY = GROUP_ROWS + 4
B_WB = GROUP_ROWS + 5
B_DX = GROUP_ROWS + 6  # A's move less B's since the step began [m]
B_DY = GROUP_ROWS + 7
B_CA = GROUP_ROWS + 8  # cos and sin of A's turn since the step began
B_SA = GROUP_ROWS + 9
B_CB = GROUP_ROWS + 10
B_SB = GROUP_ROWS + 11
BUFFER_ROWS = GROUP_ROWS + 12
# columns of a body's row in the solver's state (N+1, STATE_COLS): one cache line a body
S_VX = 0
S_VY = 1
S_W = 2
S_DX = 3  # move since the step began [m]
S_DY = 4
S_COS = 5  # cos and sin of the turn since the step began
S_SIN = 6
S_TURN = 7  # the turn since the step began [rad] (for the joints' relative angles)
STATE_COLS = 8


@njit(cache=True)
def _pack(
    cf: np.ndarray,
    ci: np.ndarray,
    lanes: np.ndarray,
    inv_mass: np.ndarray,
    inv_inertia: np.ndarray,
    state: np.ndarray,
    soft_moving: tuple[float, float, float],
    soft_fixed: tuple[float, float, float],
    group: np.ndarray,
    pair: np.ndarray,
    kinematic: np.ndarray,
) -> None:
    """Copy the contacts of ``lanes`` into ``group`` (G, GROUP_ROWS * LANES), with each
    point's effective masses along the normal and the tangent and a zero total, and their
    bodies into ``pair`` (G, 2 * LANES); ``kinematic[g]``: a lane of group g touches a moving
    body of infinite mass (its work is counted)."""
    dummy = state.shape[0] - 1
    for g in range(lanes.shape[0]):
        kinematic[g] = False
        for lane in range(LANES):
            m = lanes[g, lane]
            if m < 0:
                shared.pad_lane(
                    group, pair, g, lane, dummy, GROUP_ROWS, R_POINT, POINT_ROWS, 2, Q_BASE
                )
                continue
            a, b = shared.pack_pair(
                ci, m, group, pair, g, lane, inv_mass, soft_moving, soft_fixed, cf[m, F_MU],
                (R_MU, R_RATE, R_MSCALE, R_ISCALE, R_IMA, R_IMB),
            )  # fmt: skip
            nx = cf[m, F_NX]
            ny = cf[m, F_NY]
            group[g, R_NX * LANES + lane] = nx
            group[g, R_NY * LANES + lane] = ny
            group[g, R_IIA * LANES + lane] = inv_inertia[a]
            group[g, R_IIB * LANES + lane] = inv_inertia[b]
            mass = inv_mass[a] + inv_mass[b]
            ia = inv_inertia[a]
            ib = inv_inertia[b]
            for p in range(2):
                q = R_POINT + p * POINT_ROWS
                if p >= ci[m, I_COUNT]:
                    shared.absent_point(group, g, lane, q, POINT_ROWS, Q_BASE)
                    continue
                o = point_offset(p)
                rax = cf[m, o + P_RAX]
                ray = cf[m, o + P_RAY]
                rbx = cf[m, o + P_RBX]
                rby = cf[m, o + P_RBY]
                rna = rax * ny - ray * nx
                rnb = rbx * ny - rby * nx
                k = mass + ia * rna * rna + ib * rnb * rnb
                # the tangent is (ny, -nx)
                rta = rax * -nx - ray * ny
                rtb = rbx * -nx - rby * ny
                kt = mass + ia * rta * rta + ib * rtb * rtb
                group[g, (q + Q_RAX) * LANES + lane] = rax
                group[g, (q + Q_RAY) * LANES + lane] = ray
                group[g, (q + Q_RBX) * LANES + lane] = rbx
                group[g, (q + Q_RBY) * LANES + lane] = rby
                group[g, (q + Q_BASE) * LANES + lane] = cf[m, o + P_BASE]
                group[g, (q + Q_NMASS) * LANES + lane] = 1.0 / k if k > 0.0 else 0.0
                group[g, (q + Q_TMASS) * LANES + lane] = 1.0 / kt if kt > 0.0 else 0.0
                group[g, (q + Q_JN) * LANES + lane] = cf[m, o + P_JN]
                group[g, (q + Q_JT) * LANES + lane] = cf[m, o + P_JT]
                group[g, (q + Q_TOTAL) * LANES + lane] = 0.0
            for body in (a, b):
                if inv_mass[body] == 0.0 and (
                    state[body, S_VX] != 0.0 or state[body, S_VY] != 0.0 or state[body, S_W] != 0.0
                ):
                    kinematic[g] = True


@njit(cache=True, inline="always")
def _gather(
    buf: np.ndarray, group: np.ndarray, pair: np.ndarray, g: int, state: np.ndarray
) -> None:
    """Group g and its bodies' velocities into the working buffer (BUFFER_ROWS * LANES)."""
    for k in range(GROUP_ROWS * LANES):  # one flat run: the compiler moves it in vectors
        buf[k] = group[g, k]
    for lane in range(LANES):
        a = pair[g, lane]
        b = pair[g, LANES + lane]
        buf[B_VAX * LANES + lane] = state[a, S_VX]
        buf[B_VAY * LANES + lane] = state[a, S_VY]
        buf[B_WA * LANES + lane] = state[a, S_W]
        buf[B_VBX * LANES + lane] = state[b, S_VX]
        buf[B_VBY * LANES + lane] = state[b, S_VY]
        buf[B_WB * LANES + lane] = state[b, S_W]


@njit(cache=True, inline="always")
def _gather_all(
    buf: np.ndarray, group: np.ndarray, pair: np.ndarray, g: int, state: np.ndarray
) -> None:
    """Group g and its bodies' velocities, moves and turns since the step began into the
    working buffer."""
    _gather(buf, group, pair, g, state)
    for lane in range(LANES):
        a = pair[g, lane]
        b = pair[g, LANES + lane]
        buf[B_DX * LANES + lane] = state[a, S_DX] - state[b, S_DX]
        buf[B_DY * LANES + lane] = state[a, S_DY] - state[b, S_DY]
        buf[B_CA * LANES + lane] = state[a, S_COS]
        buf[B_SA * LANES + lane] = state[a, S_SIN]
        buf[B_CB * LANES + lane] = state[b, S_COS]
        buf[B_SB * LANES + lane] = state[b, S_SIN]


@njit(cache=True, inline="always")
def _scatter(
    buf: np.ndarray, group: np.ndarray, pair: np.ndarray, g: int, state: np.ndarray
) -> None:
    """The impulses back to group g, the velocities back to its bodies. Lanes sharing a body
    of infinite mass write back the value they all read."""
    for p in range(2):
        q = R_POINT + p * POINT_ROWS
        for lane in range(LANES):
            group[g, (q + Q_JN) * LANES + lane] = buf[(q + Q_JN) * LANES + lane]
            group[g, (q + Q_JT) * LANES + lane] = buf[(q + Q_JT) * LANES + lane]
            group[g, (q + Q_TOTAL) * LANES + lane] = buf[(q + Q_TOTAL) * LANES + lane]
    for lane in range(LANES):
        a = pair[g, lane]
        b = pair[g, LANES + lane]
        state[a, S_VX] = buf[B_VAX * LANES + lane]
        state[a, S_VY] = buf[B_VAY * LANES + lane]
        state[a, S_W] = buf[B_WA * LANES + lane]
        state[b, S_VX] = buf[B_VBX * LANES + lane]
        state[b, S_VY] = buf[B_VBY * LANES + lane]
        state[b, S_W] = buf[B_WB * LANES + lane]


@njit(cache=True, inline="always")
def _push(buf: np.ndarray, lane: int, q: int, px: float, py: float) -> None:
    """Impulse ``P`` on A at point q's ``r_A`` and ``-P`` on B at its ``r_B`` (one lane; as
    :func:`.motion.apply_impulse`)."""
    ma = buf[R_IMA * LANES + lane]
    mb = buf[R_IMB * LANES + lane]
    buf[B_VAX * LANES + lane] += ma * px
    buf[B_VAY * LANES + lane] += ma * py
    buf[B_WA * LANES + lane] += buf[R_IIA * LANES + lane] * (
        buf[(q + Q_RAX) * LANES + lane] * py - buf[(q + Q_RAY) * LANES + lane] * px
    )
    buf[B_VBX * LANES + lane] -= mb * px
    buf[B_VBY * LANES + lane] -= mb * py
    buf[B_WB * LANES + lane] -= buf[R_IIB * LANES + lane] * (
        buf[(q + Q_RBX) * LANES + lane] * py - buf[(q + Q_RBY) * LANES + lane] * px
    )


@njit(cache=True, inline="always")
def _slip(buf: np.ndarray, lane: int, q: int) -> tuple[float, float]:
    """Velocity [m/s] of A's point at point q's ``r_A`` less B's at its ``r_B`` (one lane;
    as :func:`.motion.relative_velocity`)."""
    wa = buf[B_WA * LANES + lane]
    wb = buf[B_WB * LANES + lane]
    ux = (buf[B_VAX * LANES + lane] - wa * buf[(q + Q_RAY) * LANES + lane]) - (
        buf[B_VBX * LANES + lane] - wb * buf[(q + Q_RBY) * LANES + lane]
    )
    uy = (buf[B_VAY * LANES + lane] + wa * buf[(q + Q_RAX) * LANES + lane]) - (
        buf[B_VBY * LANES + lane] + wb * buf[(q + Q_RBX) * LANES + lane]
    )
    return ux, uy


@leaf
def _group_work(buf: np.ndarray, group: np.ndarray, g: int, warm: bool) -> float:
    """Work [J] done on group g's lanes by their bodies of infinite mass, for the impulses
    the buffer holds beyond what ``group`` held (all of them, if ``warm``): the impulse on
    the other body times the fixed body's velocity at the point (:func:`.motion.fixed_work`);
    such a body's velocity is the same before and after."""
    total = 0.0
    for lane in range(LANES):
        nx = buf[R_NX * LANES + lane]
        ny = buf[R_NY * LANES + lane]
        for p in range(2):
            q = R_POINT + p * POINT_ROWS
            dn = buf[(q + Q_JN) * LANES + lane]
            dt = buf[(q + Q_JT) * LANES + lane]
            if not warm:
                dn -= group[g, (q + Q_JN) * LANES + lane]
                dt -= group[g, (q + Q_JT) * LANES + lane]
            px = dn * nx + dt * ny
            py = dn * ny - dt * nx
            if buf[R_IMA * LANES + lane] == 0.0:
                wa = buf[B_WA * LANES + lane]
                ux = buf[B_VAX * LANES + lane] - wa * buf[(q + Q_RAY) * LANES + lane]
                uy = buf[B_VAY * LANES + lane] + wa * buf[(q + Q_RAX) * LANES + lane]
                total -= px * ux + py * uy
            if buf[R_IMB * LANES + lane] == 0.0:
                wb = buf[B_WB * LANES + lane]
                ux = buf[B_VBX * LANES + lane] - wb * buf[(q + Q_RBY) * LANES + lane]
                uy = buf[B_VBY * LANES + lane] + wb * buf[(q + Q_RBX) * LANES + lane]
                total += px * ux + py * uy
    return total


@leaf(fastmath=LANE_MATH)
def _warm_start(
    group: np.ndarray,
    pair: np.ndarray,
    kinematic: np.ndarray,
    state: np.ndarray,
    work: np.ndarray,
    buf: np.ndarray,
) -> None:
    """Apply every point's impulse from the last substep (or step) again (``buf``: room for
    one group, ``BUFFER_ROWS * LANES``)."""
    for g in range(group.shape[0]):
        _gather(buf, group, pair, g, state)
        for p in range(2):
            q = R_POINT + p * POINT_ROWS
            for lane in range(LANES):
                nx = buf[R_NX * LANES + lane]
                ny = buf[R_NY * LANES + lane]
                jn = buf[(q + Q_JN) * LANES + lane]
                jt = buf[(q + Q_JT) * LANES + lane]
                buf[(q + Q_TOTAL) * LANES + lane] += jn
                _push(buf, lane, q, jn * nx + jt * ny, jn * ny - jt * nx)
        if kinematic[g]:
            work[0] += _group_work(buf, group, g, True)
        _scatter(buf, group, pair, g, state)


@leaf(fastmath=LANE_MATH)
def _solve(
    group: np.ndarray,
    pair: np.ndarray,
    kinematic: np.ndarray,
    state: np.ndarray,
    inv_h: float,
    use_bias: bool,
    push_speed: float,
    work: np.ndarray,
    buf: np.ndarray,
) -> None:
    """One Gauss-Seidel pass over the groups: normal impulses, then friction, lane by lane.
    ``state`` (N+1, STATE_COLS: velocity, angular velocity, move and the cos and sin of the
    turn since the step began) has a row for each body and one for the padding lanes' dummy;
    ``work[0]`` gathers what kinematic bodies do; ``buf`` as :func:`_warm_start`'s."""
    for g in range(group.shape[0]):
        _gather_all(buf, group, pair, g, state)
        for p in range(2):
            q = R_POINT + p * POINT_ROWS
            for lane in range(LANES):
                nx = buf[R_NX * LANES + lane]
                ny = buf[R_NY * LANES + lane]
                rax = buf[(q + Q_RAX) * LANES + lane]
                ray = buf[(q + Q_RAY) * LANES + lane]
                rbx = buf[(q + Q_RBX) * LANES + lane]
                rby = buf[(q + Q_RBY) * LANES + lane]
                ca = buf[B_CA * LANES + lane]
                sa = buf[B_SA * LANES + lane]
                cb = buf[B_CB * LANES + lane]
                sb = buf[B_SB * LANES + lane]
                # the separation now: anchors turned by each body's turn since the step began
                sx = buf[B_DX * LANES + lane] + (ca * rax - sa * ray) - (cb * rbx - sb * rby)
                sy = buf[B_DY * LANES + lane] + (sa * rax + ca * ray) - (sb * rbx + cb * rby)
                s = buf[(q + Q_BASE) * LANES + lane] + sx * nx + sy * ny
                mass_scale, impulse_scale, bias = soft_bias(
                    s, use_bias, inv_h, push_speed, buf[R_RATE * LANES + lane],
                    buf[R_MSCALE * LANES + lane], buf[R_ISCALE * LANES + lane],
                )  # fmt: skip
                ux, uy = _slip(buf, lane, q)
                _, dj = shared.normal_impulse(
                    buf, lane, q + Q_JN, q + Q_NMASS, q + Q_TOTAL, ux * nx + uy * ny, mass_scale,
                    impulse_scale, bias,
                )  # fmt: skip
                _push(buf, lane, q, dj * nx, dj * ny)
        for p in range(2):
            q = R_POINT + p * POINT_ROWS
            for lane in range(LANES):
                tx = buf[R_NY * LANES + lane]
                ty = -buf[R_NX * LANES + lane]
                ux, uy = _slip(buf, lane, q)
                ut = ux * tx + uy * ty
                jt = buf[(q + Q_JT) * LANES + lane]
                limit = buf[R_MU * LANES + lane] * buf[(q + Q_JN) * LANES + lane]
                new = min(max(jt - buf[(q + Q_TMASS) * LANES + lane] * ut, -limit), limit)
                dj = new - jt
                buf[(q + Q_JT) * LANES + lane] = new
                _push(buf, lane, q, dj * tx, dj * ty)
        if kinematic[g]:
            work[0] += _group_work(buf, group, g, False)
        _scatter(buf, group, pair, g, state)


@njit(cache=True)
def _restitution(
    cf: np.ndarray,
    ci: np.ndarray,
    nc: int,
    threshold: float,
    inv_mass: np.ndarray,
    inv_inertia: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    work: np.ndarray,
) -> None:
    """Points that approached faster than ``threshold`` and were pushed leave at ``-e`` times
    their approach speed (Newton's restitution, per point, in order)."""
    todo = shared.bouncing(
        cf, ci, nc, threshold, I_FLAGS, F_E, (POINT0, POINT_FLOATS, P_VREL, P_TOTAL)
    )
    for k in range(todo.shape[0]):
        m, o = todo[k, 0], todo[k, 1]
        a, b = ci[m, I_BODY_A], ci[m, I_BODY_B]
        nx, ny = cf[m, F_NX], cf[m, F_NY]
        rax, ray, rbx, rby = cf[m, o + P_RAX], cf[m, o + P_RAY], cf[m, o + P_RBX], cf[m, o + P_RBY]
        ux, uy = relative_velocity(a, b, rax, ray, rbx, rby, v, omega)
        dj = shared.restitution_impulse(
            cf, m, o, ux * nx + uy * ny, cf[m, F_E], P_JN, P_NMASS, P_VREL, P_TOTAL
        )
        work[0] += fixed_work(a, b, dj * nx, dj * ny, rax, ray, rbx, rby, inv_mass, v, omega)
        apply_impulse(a, b, dj * nx, dj * ny, rax, ray, rbx, rby, inv_mass, inv_inertia, v, omega)


@njit(cache=True)
def _impacts_first(
    cf: np.ndarray,
    ci: np.ndarray,
    rows: np.ndarray,
    inv_mass: np.ndarray,
    inv_inertia: np.ndarray,
    state: np.ndarray,
    h: float,
    threshold: float,
    shift: np.ndarray,
    struck: np.ndarray,
    work: np.ndarray,
    joined: tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray
    ],
) -> None:
    """Take the impacts of the contact ``rows`` (those of islands with joints) in this
    substep, each at its own time, before the soft step sees them, where no joint holds
    their bodies along the impact (``joined``: the joints' rows, the active ones, their
    prepared rows and bodies, and each body's, :func:`.joints.resists`).

    A point closing faster than ``threshold`` [m/s] (or at all, once one of its bodies was
    struck in this substep: an impact is one event) whose gap closes within the substep gets
    Newton's impulse between its two bodies alone (``-(1 + e)`` times its approach speed
    over its effective mass; a joint's impulse along the impact is nil when the joint is
    across it, as a pendulum's string at the bottom of its swing) at the fraction ``tau``
    of the substep where the gap closes, in row order, sweep after sweep until none closes
    (256 sweeps at the most).
    So an impact passes along a row of touching bodies one pair at a time, as the exact path
    and the event-driven engine pass it (Newton's cradle), where the soft step would share
    it among them all. A body's velocity changes at ``tau``: ``shift`` (N+1, 3) gains what
    its move and turn over the substep lose to the change (``(v_before - v_after) tau h``),
    added when the positions are integrated, and the gap of a later impact is measured with
    it. Such points are flagged :data:`FLAG_STRUCK` (the restitution pass leaves them) and
    their impulses added to ``struck`` (nc, 2) [N s]; ``work[0]`` gains what kinematic
    bodies did."""
    hit = np.zeros(state.shape[0], np.bool_)
    for _ in range(256):
        fired = False
        for m in rows:
            a, b = ci[m, I_BODY_A], ci[m, I_BODY_B]
            nx, ny = cf[m, F_NX], cf[m, F_NY]
            # an impact starts closing faster than the threshold; once a body is struck, its
            # contacts pass the impact on at any speed (an impact is one event)
            least = 0.0 if hit[a] or hit[b] else threshold
            for p in range(ci[m, I_COUNT]):
                vn, gap, rax, ray, rbx, rby = _closing(cf, m, point_offset(p), a, b, state, shift)
                if vn >= -least:
                    continue
                # the fraction of the substep where the gap closes, -gap / (vn h), in [0, 1];
                # compared before dividing (a speed of 1e-310 m/s closes in no substep, and
                # its vn h may round to zero)
                closes = -vn * h
                if gap > closes:
                    continue
                tau = gap / closes if gap > 0.0 else 0.0
                if _held(joined, state, a, b, nx, ny):
                    continue  # the soft step solves it with the joints
                rna = rax * ny - ray * nx
                rnb = rbx * ny - rby * nx
                ma, mb = inv_mass[a], inv_mass[b]
                ia, ib = inv_inertia[a], inv_inertia[b]
                k = ma + mb + ia * rna * rna + ib * rnb * rnb
                if k <= 0.0:
                    continue
                dj = -(1.0 + cf[m, F_E]) * vn / k
                px, py = dj * nx, dj * ny
                for body, sign, rx, ry, im, ii in (
                    (a, 1.0, rax, ray, ma, ia),
                    (b, -1.0, rbx, rby, mb, ib),
                ):
                    dvx, dvy = sign * im * px, sign * im * py
                    dw = sign * ii * (rx * py - ry * px)
                    if im == 0.0:  # a kinematic body's work: its velocity at the point
                        vx = state[body, S_VX] - state[body, S_W] * ry
                        vy = state[body, S_VY] + state[body, S_W] * rx
                        work[0] -= sign * (px * vx + py * vy)
                    state[body, S_VX] += dvx
                    state[body, S_VY] += dvy
                    state[body, S_W] += dw
                    shift[body, 0] -= dvx * tau * h
                    shift[body, 1] -= dvy * tau * h
                    shift[body, 2] -= dw * tau * h
                struck[m, p] += dj
                ci[m, I_FLAGS] |= FLAG_STRUCK
                hit[a] = True
                hit[b] = True
                fired = True
        if not fired:
            return


@njit(cache=True, inline="always")
def _closing(
    cf: np.ndarray, m: int, o: int, a: int, b: int, state: np.ndarray, shift: np.ndarray
) -> tuple[float, float, float, float, float, float]:
    """Point ``o`` of contact ``m`` (bodies ``a``, ``b``) now: its normal relative speed
    [m/s], its gap [m] (with what ``shift`` (N+1, 3) holds of the moves still to come), and
    its anchors turned with their bodies (as the soft step turns them)."""
    nx, ny = cf[m, F_NX], cf[m, F_NY]
    ca, sa, cb, sb = state[a, S_COS], state[a, S_SIN], state[b, S_COS], state[b, S_SIN]
    rax = ca * cf[m, o + P_RAX] - sa * cf[m, o + P_RAY]
    ray = sa * cf[m, o + P_RAX] + ca * cf[m, o + P_RAY]
    rbx = cb * cf[m, o + P_RBX] - sb * cf[m, o + P_RBY]
    rby = sb * cf[m, o + P_RBX] + cb * cf[m, o + P_RBY]
    ux = (state[a, S_VX] - state[a, S_W] * ray) - (state[b, S_VX] - state[b, S_W] * rby)
    uy = (state[a, S_VY] + state[a, S_W] * rax) - (state[b, S_VY] + state[b, S_W] * rbx)
    gx = state[a, S_DX] - state[b, S_DX] + rax - rbx
    gy = state[a, S_DY] - state[b, S_DY] + ray - rby
    gx += (shift[a, 0] - shift[a, 2] * ray) - (shift[b, 0] - shift[b, 2] * rby)
    gy += (shift[a, 1] + shift[a, 2] * rax) - (shift[b, 1] + shift[b, 2] * rbx)
    gap = cf[m, o + P_BASE] + gx * nx + gy * ny
    return ux * nx + uy * ny, gap, rax, ray, rbx, rby


@njit(cache=True, inline="always")
def _held(
    joined: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                  np.ndarray],
    state: np.ndarray, a: int, b: int, nx: float, ny: float,
) -> bool:  # fmt: skip
    """Whether a joint holds body ``a`` or ``b`` along ``(nx, ny)`` (:func:`.joints.resists`;
    ``joined`` as :func:`_impacts_first` takes it)."""
    jf, ji, active, prep, jrows, start, members = joined
    return joints.resists(
        jf, ji, active, prep, jrows, start, members, state, a, nx, ny
    ) or joints.resists(jf, ji, active, prep, jrows, start, members, state, b, nx, ny)


@njit(cache=True)
def _slots(lanes: np.ndarray, nc: int) -> np.ndarray:
    """Each contact's place in the groups, ``g * LANES + lane`` (nc,)."""
    slots = np.full(max(nc, 1), -1, np.int64)
    for g in range(lanes.shape[0]):
        for lane in range(LANES):
            if lanes[g, lane] >= 0:
                slots[lanes[g, lane]] = g * LANES + lane
    return slots


@njit(cache=True)
def _hold_back(
    cf: np.ndarray, ci: np.ndarray, first: np.ndarray, slots: np.ndarray, group: np.ndarray,
    state: np.ndarray, shift: np.ndarray, h: float, threshold: float, held: np.ndarray,
    joined: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                  np.ndarray],
) -> int:  # fmt: skip
    """Before a relax pass: leave out of it the points of the contacts ``first`` that close
    faster than ``threshold`` and would touch within the next substep (their base in the
    groups set to ``ABSENT_BASE``, the old one kept in ``held`` (K, 2): where, what), so that
    the next substep takes their impacts first instead of the relax pass slowing the
    approach (those no joint holds: ``joined``, :func:`_held`); return how many.
    :func:`_give_back` puts them back."""
    k = 0
    for m in first:
        slot = slots[m]
        if slot < 0:
            continue
        g, lane = slot // LANES, slot % LANES
        a, b = ci[m, I_BODY_A], ci[m, I_BODY_B]
        for p in range(ci[m, I_COUNT]):
            vn, gap, _, _, _, _ = _closing(cf, m, point_offset(p), a, b, state, shift)
            if (
                vn < -threshold
                and gap + vn * h < 0.0
                and not _held(joined, state, a, b, cf[m, F_NX], cf[m, F_NY])
            ):
                at = (R_POINT + p * POINT_ROWS + Q_BASE) * LANES + lane
                held[k, 0] = g * group.shape[1] + at
                held[k, 1] = group[g, at]
                group[g, at] = shared.ABSENT_BASE
                k += 1
    return k


@njit(cache=True)
def _give_back(group: np.ndarray, held: np.ndarray, k: int) -> None:
    """The bases :func:`_hold_back` took, back in the groups."""
    flat = group.reshape(-1)
    for i in range(k):
        flat[int(held[i, 0])] = held[i, 1]


@njit(cache=True)
def _jointed_rows(ci: np.ndarray, nc: int, jointed: np.ndarray) -> np.ndarray:
    """The contacts (rows) not solved exactly with a body ``jointed`` (N,) bool."""
    out = np.empty(nc, np.int64)
    k = 0
    for m in range(nc):
        if not ci[m, I_FLAGS] & FLAG_EXACT and (
            jointed[ci[m, I_BODY_A]] or jointed[ci[m, I_BODY_B]]
        ):
            out[k] = m
            k += 1
    return out[:k]


@leaf
def _unshift(shift: np.ndarray, bodies: np.ndarray) -> None:
    """Nothing shifted for the next substep (the bodies' rows only: others never are)."""
    for i in bodies:
        shift[i, 0] = 0.0
        shift[i, 1] = 0.0
        shift[i, 2] = 0.0


@njit(cache=True)
def solve_step(
    cf: np.ndarray,
    ci: np.ndarray,
    nc: int,
    bodies: np.ndarray,
    inv_mass: np.ndarray,
    inv_inertia: np.ndarray,
    accel: np.ndarray,
    alpha: np.ndarray,
    x: np.ndarray,
    angle: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    knobs: tuple[float, int, float, float, float, float],
    work: np.ndarray,
    jf: np.ndarray,
    ji: np.ndarray,
    active: np.ndarray,
    jointed: np.ndarray,
    impact_speed: float,
) -> None:
    """Advance the ``bodies`` (indices), their contacts and joints by one step.

    ``knobs``: the step ``dt`` [s], the substeps, the contact stiffness [Hz] and damping
    ratio [-], the most a pass pushes overlapping bodies apart [m/s], and the restitution
    threshold [m/s] (:meth:`carom.engines.stepped.driver.SteppedEngine._knobs`).

    Contacts flagged exact are skipped; every other contact must join bodies of ``bodies``
    or a body that does not move under impulses (static, kinematic: infinite mass).
    ``accel`` (N, 2) [m/s^2] is each body's acceleration (gravity, and the forces given for
    this step over the mass), ``alpha`` (N,) [rad/s^2] its angular acceleration (the torques
    given over the moment of inertia); both enter the velocities each substep, as in Box2D.
    ``work[0]`` gains the work kinematic bodies did on the others [J].

    The joints ``active`` (k,) of the rows ``jf``, ``ji`` (:mod:`.joints`) join bodies of
    ``bodies`` or bodies that do not move under impulses; they are solved before the contacts
    in each pass (Box2D v3's order), and their reactions written after the last substep. The
    contacts of bodies ``jointed`` (N,) bool (in an island with a joint) take their impacts
    first (:func:`_impacts_first`): those closing faster than ``impact_speed`` [m/s].
    """
    dt, substeps, contact_hertz, damping_ratio, push_speed, restitution_threshold = knobs
    h, soft_moving, soft_fixed = shared.substep_softness(dt, substeps, contact_hertz, damping_ratio)
    n = x.shape[0]
    jointed_step = active.shape[0] > 0  # (what the joints need, made only when there are any)
    struck = np.zeros((max(nc, 1) if jointed_step else 1, 2))
    shift = np.zeros((n + 1, 3))  # (read for every body as the positions are integrated)
    first = _jointed_rows(ci, nc, jointed) if jointed_step else np.zeros(0, np.int64)
    soft_joint = joint_softness(h, contact_hertz)
    prep, rows = joints.prepare(jf, ji, active, x, angle, inv_mass, inv_inertia, h)
    start, members = joints.by_body(rows, n)
    joined = (jf, ji, active, prep, rows, start, members)
    # every body's row, and a last one for the padding lanes' dummy (at rest, infinite mass)
    state = np.zeros((n + 1, STATE_COLS))
    state[:n, S_VX] = v[:, 0]
    state[:n, S_VY] = v[:, 1]
    state[:n, S_W] = omega
    state[:, S_COS] = 1.0
    lanes, group, pair, kinematic = shared.groups_of(ci, nc, inv_mass, I_FLAGS, GROUP_ROWS)
    _pack(
        cf, ci, lanes, inv_mass, inv_inertia, state, soft_moving, soft_fixed, group, pair, kinematic
    )
    slots = _slots(lanes, nc) if first.shape[0] else np.zeros(1, np.int64)
    spared = np.empty((2 * first.shape[0], 2))
    buf = np.empty(BUFFER_ROWS * LANES)  # (room for one group, for the leaf kernels)
    for _ in range(substeps):
        for i in bodies:
            state[i, S_VX] += h * accel[i, 0]
            state[i, S_VY] += h * accel[i, 1]
            state[i, S_W] += h * alpha[i]
        if first.shape[0]:
            _impacts_first(
                cf, ci, first, inv_mass, inv_inertia, state, h, impact_speed, shift, struck, work,
                joined,
            )  # fmt: skip
        joints.warm_start(jf, ji, active, prep, rows, state)
        _warm_start(group, pair, kinematic, state, work, buf)
        joints.solve(jf, ji, active, prep, rows, state, h, soft_joint, True)
        _solve(group, pair, kinematic, state, 1.0 / h, True, push_speed, work, buf)
        for i in bodies:
            # (shift: what an impact taken first within the substep took from the move)
            mx = h * state[i, S_VX] + shift[i, 0]
            my = h * state[i, S_VY] + shift[i, 1]
            turn = h * state[i, S_W] + shift[i, 2]
            x[i, 0] += mx
            x[i, 1] += my
            angle[i] += turn
            state[i, S_DX] += mx
            state[i, S_DY] += my
            state[i, S_TURN] += turn
            # each body's turn since the step began, once per substep (not per contact):
            # the last turn composed with this substep's
            c, s = cos_sin(turn)
            cos0 = state[i, S_COS]
            sin0 = state[i, S_SIN]
            state[i, S_COS] = cos0 * c - sin0 * s
            state[i, S_SIN] = sin0 * c + cos0 * s
        held = 0
        if first.shape[0]:
            _unshift(shift, bodies)
            held = _hold_back(
                cf, ci, first, slots, group, state, shift, h, impact_speed, spared, joined
            )
        joints.solve(jf, ji, active, prep, rows, state, h, soft_joint, False)
        _solve(group, pair, kinematic, state, 1.0 / h, False, push_speed, work, buf)
        if held:
            _give_back(group, spared, held)
    joints.reactions(jf, ji, active, prep, rows, state, h)
    for i in bodies:
        v[i, 0] = state[i, S_VX]
        v[i, 1] = state[i, S_VY]
        omega[i] = state[i, S_W]
    shared.unpack(
        group, lanes, ci, cf, (R_POINT, POINT_ROWS, POINT0, POINT_FLOATS, 2),
        (P_JN, P_JT, P_TOTAL, P_NMASS), (Q_JN, Q_JT, Q_TOTAL, Q_NMASS), True,
    )  # fmt: skip
    if jointed_step:  # the impacts taken first count in the points' impulse of the step
        for m in range(nc):
            if ci[m, I_FLAGS] & FLAG_STRUCK:
                for p in range(ci[m, I_COUNT]):
                    cf[m, point_offset(p) + P_TOTAL] += struck[m, p]
    _restitution(cf, ci, nc, restitution_threshold, inv_mass, inv_inertia, v, omega, work)
