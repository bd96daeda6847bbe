"""Event-driven dynamics of spheres and disks: the exact engine's main loop.

Bodies fly freely (straight lines, or parabolas under gravity) between events, and each
carries its own clock: it is advanced only when an event involves it (lazy clocks, Lubachevsky
1991). Every moving body has exactly one scheduled event, its earliest of: a collision with a
neighbour, with a wall or plane, or leaving its neighbour shell (Smallenburg 2022). The events
sit in an event calendar (:mod:`carom.core.calendar`, after Paul 2007). A predicted collision
with ``j`` stores ``j``'s collision counter; if ``j`` has collided since, the event is stale
and the body is simply re-predicted (Rapaport 1980).

Dissipation and round-off:

* TC model (Luding & McNamara 1998): a collision within ``t_c`` of the previous collision of
  either body is elastic, which stops inelastic collapse.
* Rest: a body pulled by gravity onto a wall or plane that would leave it again for less than
  ``t_c`` (or that the TC model would bounce elastically) comes to rest on it: its normal
  velocity and normal acceleration are set to zero and it slides until a collision lifts it.
  This ends the Zeno sequence of a settling ball in a finite number of events.
* Overlap by round-off: an approaching pair that already touches collides now; a separating
  one never does (Bannerman et al. 2014). Overlaps therefore cannot grow.

The model ``m`` and state ``s`` are the named tuples of :mod:`carom.model` and
:mod:`carom.state`. :func:`run` unpacks them once: the functions of the hot loop take the
arrays they need one by one, because Numba passes a named tuple of arrays into a call by
reference-counting every array in it (measured: 95 ns a call, against under 1 ns for a few
plain arrays, which LLVM inlines). Nothing is allocated per event, so :func:`run` is compiled
without Numba's reference counting (``_nrt=False``, the remedy Numba's developers give in
numba#2345): every inlined call would otherwise increment and decrement an atomic counter per
array argument, and each such locked instruction stalls the loads around it (measured: the
event loop 1.4x faster without them). A kernel that allocated would fail to compile, loudly.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, TypeVar, cast

import numpy as np
from numba import njit

from carom.core.calendar import calendar_build, calendar_top, calendar_update
from carom.core.laws import LAW_SMOOTH, impulse_spheres
from carom.core.neighbors import FITS, LIST_FULL, build_all, rebuild_shell
from carom.core.prefetch import prefetch_row
from carom.core.toi import (
    INF,
    first_root_quartic,
    shell_exit_time,
    toi_gap,
    toi_sphere_sphere,
)
from carom.state import (
    KIN_R,
    KIN_T,
    KIN_V,
    SCHED_COUNTER,
    SCHED_KIND,
    SCHED_OTHER,
    SCHED_STAMP,
)

# compile without reference counting (see the module docstring); an internal Numba flag
NO_REFCOUNTING: dict[str, Any] = {"_nrt": False}
_F = TypeVar("_F", bound=Callable[..., Any])
_njit_without_refcounting = cast(
    Callable[[_F], _F], njit(cache=True, error_model="numpy", **NO_REFCOUNTING)
)

SHELL_MARGIN = 1.0 - 1e-9  # the fraction of the shell a body may use

EV_NONE = 0
EV_PAIR = 1
EV_WALL = 2  # other = face: 2k lower, 2k + 1 upper wall of axis k; 2 dim + p plane p
EV_SHELL = 3

# why run() returned
DONE = 0
LOG_FULL = 1
MAX_EVENTS = 2
LISTS_FULL = 3  # a neighbour list is full: grow the lists
CELLS_FULL = 4  # a cell row is full: grow the rows

# counts[]
C_EVENTS = 0
C_PAIR = 1
C_WALL = 2
C_SHELL = 3
C_STALE = 4
C_TC = 5  # collisions made elastic by the TC model
C_REST = 6  # bodies brought to rest on a wall or plane
# sums[]
S_VIRIAL = 0  # sum over collisions of J . r  [J s] (pairs: r = x1 - x2; walls: r = x)
S_KE_LOST = 1  # kinetic energy dissipated [J]


@njit(cache=True, error_model="numpy", inline="always")
def face_normal(plane_normal: np.ndarray, dim: int, face: int, k: int) -> float:
    """Component ``k`` of the inward unit normal of wall face or plane ``face``."""
    if face < 2 * dim:
        if k != face // 2:
            return 0.0
        return 1.0 if face % 2 == 0 else -1.0
    return float(plane_normal[face - 2 * dim, k])


@njit(cache=True, error_model="numpy", inline="always")
def set_support(
    gravity: np.ndarray,
    plane_normal: np.ndarray,
    support: np.ndarray,
    acc: np.ndarray,
    i: int,
    face: int,
) -> None:
    """Rest body ``i`` on ``face`` (or lift it off, ``face = -1``) and update its acceleration."""
    dim = gravity.shape[0]
    support[i] = face
    g_n = 0.0
    if face >= 0:
        for k in range(dim):
            g_n += gravity[k] * face_normal(plane_normal, dim, face, k)
    for k in range(dim):
        nk = face_normal(plane_normal, dim, face, k) if face >= 0 else 0.0
        acc[i, k] = gravity[k] - g_n * nk


@njit(cache=True, error_model="numpy", inline="always")
def kinematic_views(kin: np.ndarray, dim: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions (N, dim), velocities (N, dim) and clocks (N,): views into ``kin``."""
    return kin[:, :dim], kin[:, KIN_V : KIN_V + dim], kin[:, KIN_T]


@njit(cache=True, error_model="numpy", inline="always")
def schedule_views(
    sched: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Event kinds, partners, stamps and collision counters, (N,) each: views into ``sched``."""
    return (
        sched[:, SCHED_KIND],
        sched[:, SCHED_OTHER],
        sched[:, SCHED_STAMP],
        sched[:, SCHED_COUNTER],
    )


@njit(cache=True, error_model="numpy", inline="always")
def calendar_of(s):  # type: ignore[no-untyped-def]
    """The event calendar's arrays of state ``s``, as :mod:`carom.core.calendar` takes them."""
    return (
        s.cal_head,
        s.cal_next,
        s.cal_prev,
        s.cal_loc,
        s.cur_heap,
        s.cur_key,
        s.cur_where,
        s.cal_f,
        s.cal_i,
    )


@njit(cache=True, error_model="numpy", inline="always")
def advance(x: np.ndarray, v: np.ndarray, acc: np.ndarray, t: np.ndarray, i: int, T: float) -> None:
    """Move body ``i`` along its free flight to time ``T`` and set its clock."""
    dt = T - t[i]
    if dt != 0.0:
        for k in range(x.shape[1]):
            a = acc[i, k]
            x[i, k] += (v[i, k] + 0.5 * a * dt) * dt
            v[i, k] += a * dt
    t[i] = T


@njit(cache=True, error_model="numpy", inline="always")
def _first_pair_straight(
    i: int,
    T: float,
    best: float,
    kin: np.ndarray,
    nbr: np.ndarray,
    nbr_count: np.ndarray,
    box: np.ndarray,
    periodic: bool,
) -> tuple[float, int]:
    """Body ``i``'s first collision with a neighbour before ``best`` when nothing accelerates.

    Returns ``(time from T, neighbour)``, or ``(best, -1)``. The same arithmetic as
    :func:`carom.core.toi.toi_sphere_sphere`, written out per component and without branches
    on the neighbour (the hot loop of the engine: a mispredicted branch costs more than the
    square root and division it would skip). Each neighbour's data is one record of ``kin``
    (z is zero in 2D, so three components serve both).
    """
    xi0, xi1, xi2 = kin[i, 0], kin[i, 1], kin[i, 2]
    vi0, vi1, vi2 = kin[i, KIN_V], kin[i, KIN_V + 1], kin[i, KIN_V + 2]
    L0, L1 = box[0], box[1]
    L2 = box[2] if box.shape[0] == 3 else 1.0
    inv0, inv1, inv2 = 1.0 / L0, 1.0 / L1, 1.0 / L2
    rad = kin[i, KIN_R]
    other = -1
    for slot in range(nbr_count[i]):
        prefetch_row(kin, nbr[i, slot])
    for slot in range(nbr_count[i]):
        j = nbr[i, slot]
        dtj = T - kin[j, KIN_T]
        vj0, vj1, vj2 = kin[j, KIN_V], kin[j, KIN_V + 1], kin[j, KIN_V + 2]
        r0 = xi0 - (kin[j, 0] + vj0 * dtj)
        r1 = xi1 - (kin[j, 1] + vj1 * dtj)
        r2 = xi2 - (kin[j, 2] + vj2 * dtj)
        if periodic:
            r0 -= L0 * np.floor(r0 * inv0 + 0.5)
            r1 -= L1 * np.floor(r1 * inv1 + 0.5)
            r2 -= L2 * np.floor(r2 * inv2 + 0.5)
        dv0 = vi0 - vj0
        dv1 = vi1 - vj1
        dv2 = vi2 - vj2
        rr = r0 * r0 + r1 * r1 + r2 * r2
        rv = r0 * dv0 + r1 * dv1 + r2 * dv2
        vv = dv0 * dv0 + dv1 * dv1 + dv2 * dv2
        reach = rad + kin[j, KIN_R]
        c = rr - reach * reach
        disc = rv * rv - vv * c
        # the smaller root of vv t^2 + 2 rv t + c, cancellation-free (rv < 0); 0 when already
        # touching and approaching; none when separating or passing by
        # (a select, not a branch; the denominator is never zero, even where discarded)
        tp = max(c / (math.sqrt(max(disc, 0.0)) - rv if rv < 0.0 else 1.0), 0.0)
        tp = tp if (rv < 0.0 and disc >= 0.0) else INF
        if tp < best:
            best = tp
            other = j
    return best, other


@njit(cache=True, error_model="numpy", inline="always")
def predict(
    i: int,
    T: float,
    kin: np.ndarray,
    x: np.ndarray,
    v: np.ndarray,
    acc: np.ndarray,
    accelerated: bool,
    t: np.ndarray,
    shell: np.ndarray,
    support: np.ndarray,
    nbr: np.ndarray,
    nbr_count: np.ndarray,
    counter: np.ndarray,
    radius: np.ndarray,
    mobile: np.ndarray,
    box: np.ndarray,
    inv_box: np.ndarray,
    periodic: bool,
    delta: float,
    plane_point: np.ndarray,
    plane_normal: np.ndarray,
    ev_time: np.ndarray,
    ev_kind: np.ndarray,
    ev_other: np.ndarray,
    ev_stamp: np.ndarray,
) -> None:
    """Schedule body ``i``'s next event; ``i`` must be at time ``T``."""
    dim = x.shape[1]
    if not mobile[i]:
        ev_time[i] = INF
        ev_kind[i] = EV_NONE
        return
    rad = radius[i]
    off2 = 0.0
    off_v = 0.0
    speed2 = 0.0
    acc2 = 0.0
    for k in range(dim):
        d = x[i, k] - shell[i, k]
        off2 += d * d
        off_v += d * v[i, k]
        speed2 += v[i, k] * v[i, k]
        acc2 += acc[i, k] * acc[i, k]
    # leave the shell a hair early, so that round-off in the exit time never lets a body
    # stray beyond delta from its centre
    best = shell_exit_time(off2, off_v, speed2, math.sqrt(acc2), delta * SHELL_MARGIN)
    kind = EV_SHELL
    other = -1

    # walls (faces 0 .. 2 dim - 1, none when periodic) and planes (faces 2 dim + p): the gap
    # d(t) = d0 + u t + acc t^2 / 2 along each inward normal
    first_face = 2 * dim if periodic else 0
    for face in range(first_face, 2 * dim + plane_normal.shape[0]):
        if face == support[i]:
            continue
        if face < 2 * dim:
            k = face // 2
            if face % 2 == 0:
                d0 = x[i, k] - rad
                u = v[i, k]
                a_n = acc[i, k]
            else:
                d0 = box[k] - x[i, k] - rad
                u = -v[i, k]
                a_n = -acc[i, k]
        else:
            p = face - 2 * dim
            d0 = -rad
            u = 0.0
            a_n = 0.0
            for q in range(dim):
                nq = plane_normal[p, q]
                d0 += nq * (x[i, q] - plane_point[p, q])
                u += nq * v[i, q]
                a_n += nq * acc[i, q]
        tf = toi_gap(d0, u, a_n)
        if tf < best:
            best = tf
            kind = EV_WALL
            other = face

    # neighbours: relative motion r + v t + da t^2 / 2, j extrapolated to T on the fly
    if not accelerated:
        tp, j = _first_pair_straight(i, T, best, kin, nbr, nbr_count, box, periodic)
        if j >= 0:
            best = tp
            kind = EV_PAIR
            other = j
    for slot in range(nbr_count[i] if accelerated else 0):
        j = nbr[i, slot]
        dtj = T - t[j]
        rr = 0.0
        rv = 0.0
        vv = 0.0
        rda = 0.0
        vda = 0.0
        dada = 0.0
        for k in range(dim):
            aj = acc[j, k]
            r = x[i, k] - (x[j, k] + (v[j, k] + 0.5 * aj * dtj) * dtj)
            dv = v[i, k] - (v[j, k] + aj * dtj)
            da = acc[i, k] - aj
            if periodic:
                r -= box[k] * np.floor(r * inv_box[k] + 0.5)
            rr += r * r
            rv += r * dv
            vv += dv * dv
            rda += r * da
            vda += dv * da
            dada += da * da
        reach = rad + radius[j]
        if dada == 0.0:
            tp = toi_sphere_sphere(rr - reach * reach, rv, vv)
        else:
            tp = first_root_quartic(0.25 * dada, vda, vv + rda, 2.0 * rv, rr - reach * reach, best)
        if tp < best:
            best = tp
            kind = EV_PAIR
            other = j

    ev_time[i] = T + best
    ev_kind[i] = kind
    ev_other[i] = other
    if kind == EV_PAIR:
        ev_stamp[i] = counter[other]


@njit(cache=True, error_model="numpy", inline="always")
def _log(
    logbuf: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    T: float,
    a: int,
    b: int,
    j0: float,
    j1: float,
    j2: float,
    un_before: float,
    un_after: float,
) -> None:
    log_time, log_a, log_b, log_impulse, log_un, log_n = logbuf
    n = log_n[0]
    log_time[n] = T
    log_a[n] = a
    log_b[n] = b
    log_impulse[n, 0] = j0
    log_impulse[n, 1] = j1
    log_impulse[n, 2] = j2
    log_un[n, 0] = un_before
    log_un[n, 1] = un_after
    log_n[0] = n + 1


@njit(cache=True, error_model="numpy", inline="always")
def _contact_velocity(
    dv0: float,
    dv1: float,
    dv2: float,
    w: np.ndarray,
    i: int,
    j: int,
    a_i: float,
    a_j: float,
    n0: float,
    n1: float,
    n2: float,
    law: int,
) -> tuple[float, float, float]:
    """Contact-point relative velocity ``g = v_i - v_j - (a_i w_i + a_j w_j) x n`` [m/s] from
    ``dv = v_i - v_j``; the smooth law needs only ``dv`` (spin adds nothing along ``n``)."""
    if law == LAW_SMOOTH:
        return dv0, dv1, dv2
    s0 = a_i * w[i, 0] + a_j * w[j, 0]
    s1 = a_i * w[i, 1] + a_j * w[j, 1]
    s2 = a_i * w[i, 2] + a_j * w[j, 2]
    return dv0 - (s1 * n2 - s2 * n1), dv1 - (s2 * n0 - s0 * n2), dv2 - (s0 * n1 - s1 * n0)


@njit(cache=True, error_model="numpy", inline="always")
def _collide_pair(
    i: int,
    j: int,
    T: float,
    log_on: bool,
    x: np.ndarray,
    v: np.ndarray,
    acc: np.ndarray,
    w: np.ndarray,
    counter: np.ndarray,
    last_coll: np.ndarray,
    support: np.ndarray,
    radius: np.ndarray,
    mass: np.ndarray,
    inv_mass: np.ndarray,
    q: np.ndarray,
    material: np.ndarray,
    pair_table: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    face_e: np.ndarray,
    gravity: np.ndarray,
    accelerated: bool,
    plane_normal: np.ndarray,
    box: np.ndarray,
    periodic: bool,
    t_c: float,
    counts: np.ndarray,
    sums: np.ndarray,
    logbuf: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> None:
    dim = x.shape[1]
    # separation r = x_i - x_j (nearest image) and relative velocity, as three components
    r0 = r1 = r2 = 0.0
    dv0 = dv1 = dv2 = 0.0
    for k in range(dim):
        d = x[i, k] - x[j, k]
        if periodic:
            d -= box[k] * np.floor(d / box[k] + 0.5)
        dv = v[i, k] - v[j, k]
        if k == 0:
            r0, dv0 = d, dv
        elif k == 1:
            r1, dv1 = d, dv
        else:
            r2, dv2 = d, dv
    dist = math.sqrt(r0 * r0 + r1 * r1 + r2 * r2)
    n0, n1, n2 = r0 / dist, r1 / dist, r2 / dist
    pair_law, pair_e, pair_beta, pair_friction = pair_table
    mat_i = material[i]
    mat_j = material[j]
    law = pair_law[mat_i, mat_j]
    e = pair_e[mat_i, mat_j]
    if T - last_coll[i] < t_c or T - last_coll[j] < t_c:
        if e < 1.0:
            counts[C_TC] += 1
        e = 1.0
    a_i = radius[i]
    a_j = radius[j]
    g0, g1, g2 = _contact_velocity(dv0, dv1, dv2, w, i, j, a_i, a_j, n0, n1, n2, law)
    inv_i = inv_mass[i]
    inv_j = inv_mass[j]
    j0, j1, j2 = impulse_spheres(
        n0,
        n1,
        n2,
        g0,
        g1,
        g2,
        inv_i,
        inv_j,
        e,
        law,
        pair_beta[mat_i, mat_j],
        pair_friction[mat_i, mat_j],
        1.0 / q[i] if law != LAW_SMOOTH else 0.0,  # (spins do not enter the smooth law)
        1.0 / q[j] if law != LAW_SMOOTH else 0.0,
    )
    # They must part: else the next prediction finds them meeting now again, a loop of
    # events at one time. The impulse law makes them part at e times the approach speed,
    # which is zero, or round-off, when they meet at a grazing angle, in a plastic impact
    # (e = 0), or when gravity presses them together (one rests on a support or is static,
    # the other is pulled onto it: a resting contact, which hard spheres do not have). The
    # parting speed is raised, when below it, to
    #     u_min = 2^-48 |g| + max(0, -a_n) t_c / 4,
    # 16 ulps of the relative speed, above the round-off of the approach test and below any
    # measurement; under a pull a_n, the speed that brings them back after t_c / 2, as the TC
    # model would (energy given: m a_n^2 t_c^2 / 32, 1e-12 J for 1 kg at t_c = 1e-6 s). The
    # extra impulse is an impulse like any other, in the energy ledger and the log.
    # (the hot path: acc is read only under gravity, and the square root taken only when
    # the floor applies, u_out < u_pull + 2^-48 |g| tested as d < 0 or d^2 < 2^-96 |g|^2)
    u = g0 * n0 + g1 * n1 + g2 * n2
    u_pull = 0.0
    if accelerated:
        a_n = 0.0
        for k in range(dim):
            nk = n0 if k == 0 else (n1 if k == 1 else n2)
            a_n += (acc[i, k] - acc[j, k]) * nk
        u_pull = max(0.0, -a_n) * t_c * 0.25
    inv_sum = inv_i + inv_j
    u_out = u + (j0 * n0 + j1 * n1 + j2 * n2) * inv_sum
    gg = g0 * g0 + g1 * g1 + g2 * g2
    d = u_out - u_pull
    if d < 0.0 or d * d < 2.0**-96 * gg:
        u_min = 2.0**-48 * math.sqrt(gg) + u_pull
        extra = (u_min - u_out) / inv_sum
        j0 += extra * n0
        j1 += extra * n1
        j2 += extra * n2
    if j0 == 0.0 and j1 == 0.0 and j2 == 0.0:
        return  # at rest relative to each other, and nothing pulls them together
    un_before = dv0 * n0 + dv1 * n1 + dv2 * n2
    for k in range(dim):
        jk = j0 if k == 0 else (j1 if k == 1 else j2)
        v[i, k] += jk * inv_i
        v[j, k] -= jk * inv_j
    if law != LAW_SMOOTH:
        # w_i' = w_i - (n x J) / (q_i m_i a_i), the same sign for both bodies
        c0 = n1 * j2 - n2 * j1
        c1 = n2 * j0 - n0 * j2
        c2 = n0 * j1 - n1 * j0
        f_i = inv_i / (q[i] * a_i)
        f_j = inv_j / (q[j] * a_j)
        w[i, 0] -= c0 * f_i
        w[i, 1] -= c1 * f_i
        w[i, 2] -= c2 * f_i
        w[j, 0] -= c0 * f_j
        w[j, 1] -= c1 * f_j
        w[j, 2] -= c2 * f_j
    # contact-point relative velocity after the impulse, as g before it
    u0 = v[i, 0] - v[j, 0]
    u1 = v[i, 1] - v[j, 1]
    u2 = v[i, 2] - v[j, 2] if dim == 3 else 0.0
    un_after = u0 * n0 + u1 * n1 + u2 * n2
    h0, h1, h2 = _contact_velocity(u0, u1, u2, w, i, j, a_i, a_j, n0, n1, n2, law)
    # energy dissipated = minus the impulse's work, J . (g_before + g_after) / 2 for rigid
    # bodies (exact, and free of the cancellation of KE_before - KE_after)
    sums[S_KE_LOST] -= 0.5 * (j0 * (g0 + h0) + j1 * (g1 + h1) + j2 * (g2 + h2))
    counter[i] += 1
    counter[j] += 1
    last_coll[i] = T
    last_coll[j] = T
    counts[C_PAIR] += 1
    sums[S_VIRIAL] += j0 * r0 + j1 * r1 + j2 * r2
    # a body resting on a support: lifted off, or pushed into it (the support pushes back)
    if support[i] >= 0:
        _support_reaction(i, v, acc, support, face_e, gravity, plane_normal, mass, t_c, sums)
    if support[j] >= 0:
        _support_reaction(j, v, acc, support, face_e, gravity, plane_normal, mass, t_c, sums)
    if log_on:
        _log(
            logbuf,
            T,
            i,
            j,
            j0,
            j1,
            j2,
            un_before,
            un_after,
        )


@njit(cache=True, error_model="numpy", inline="always")
def _support_reaction(
    b: int,
    v: np.ndarray,
    acc: np.ndarray,
    support: np.ndarray,
    face_e: np.ndarray,
    gravity: np.ndarray,
    plane_normal: np.ndarray,
    mass: np.ndarray,
    t_c: float,
    sums: np.ndarray,
) -> None:
    """Body ``b`` rests on a support and was just hit: it lifts off, or the support pushes
    back (an impact with the support's restitution) and then it flies; unless it would be
    back within t_c (a push along the support, as from a neighbour resting beside it, leaves
    it round-off off the face): then it stays, as the rule for impacts on faces says."""
    dim = v.shape[1]
    face = support[b]
    un = 0.0
    g_n = 0.0
    for k in range(dim):
        nk = face_normal(plane_normal, dim, face, k)
        un += v[b, k] * nk
        g_n += gravity[k] * nk
    if un < 0.0:
        e_w = face_e[face]
        for k in range(dim):
            v[b, k] -= (1.0 + e_w) * un * face_normal(plane_normal, dim, face, k)
        sums[S_KE_LOST] += 0.5 * mass[b] * (1.0 - e_w * e_w) * un * un
        un = -e_w * un
    if un > 0.0 and 2.0 * un < -g_n * t_c:
        for k in range(dim):
            v[b, k] -= un * face_normal(plane_normal, dim, face, k)
        sums[S_KE_LOST] += 0.5 * mass[b] * un * un
        return
    if un != 0.0:
        set_support(gravity, plane_normal, support, acc, b, -1)


@njit(cache=True, error_model="numpy", inline="always")
def _collide_face(
    i: int,
    face: int,
    T: float,
    log_on: bool,
    x: np.ndarray,
    v: np.ndarray,
    acc: np.ndarray,
    counter: np.ndarray,
    last_coll: np.ndarray,
    support: np.ndarray,
    mass: np.ndarray,
    face_e: np.ndarray,
    gravity: np.ndarray,
    plane_normal: np.ndarray,
    t_c: float,
    counts: np.ndarray,
    sums: np.ndarray,
    logbuf: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
) -> None:
    """Body ``i`` (at time ``T``) meets wall or plane ``face`` (smooth: spins are kept)."""
    dim = x.shape[1]
    un = 0.0
    acc_n = 0.0
    for k in range(dim):
        nk = face_normal(plane_normal, dim, face, k)
        un += v[i, k] * nk
        acc_n += acc[i, k] * nk
    # Leaving (un > 0) flies off, unless so slowly that gravity brings it back within t_c
    # (the gap reopens for 2 u / |a_n|, which can be below the clock's resolution: a loop of
    # events at one time); then it rests, by the rule for impacts below.
    approaching = un < 0.0 or (un == 0.0 and acc_n < 0.0)
    if not approaching and not (acc_n < 0.0 and 2.0 * un < -acc_n * t_c):
        return
    e = face_e[face]
    tc = T - last_coll[i] < t_c
    if tc and acc_n >= 0.0:
        if e < 1.0:
            counts[C_TC] += 1
        e = 1.0
    u_out = -e * un
    # rest: pulled onto the face, and would leave it for less than t_c (or TC applies)
    rest = acc_n < 0.0 and (tc or 2.0 * u_out < -acc_n * t_c)
    if rest:
        e = 0.0
        u_out = 0.0
        counts[C_REST] += 1
    jn = -(1.0 + e) * un * mass[i]
    x_dot_j = 0.0
    for k in range(dim):
        nk = face_normal(plane_normal, dim, face, k)
        v[i, k] -= (1.0 + e) * un * nk
        x_dot_j += x[i, k] * jn * nk
    if rest:
        set_support(gravity, plane_normal, support, acc, i, face)
    counter[i] += 1
    last_coll[i] = T
    counts[C_WALL] += 1
    sums[S_VIRIAL] += x_dot_j
    sums[S_KE_LOST] += 0.5 * mass[i] * (1.0 - e * e) * un * un  # walls are smooth
    if log_on:
        _log(
            logbuf,
            T,
            i,
            -1 - face,
            jn * face_normal(plane_normal, dim, face, 0),
            jn * face_normal(plane_normal, dim, face, 1),
            jn * face_normal(plane_normal, dim, face, 2) if dim == 3 else 0.0,
            un,
            u_out,
        )


@njit(cache=True, error_model="numpy")
def initialise(m, s) -> int:  # type: ignore[no-untyped-def]
    """Build every shell and neighbour list and schedule every body.

    Returns ``DONE``, or ``LISTS_FULL`` / ``CELLS_FULL`` when the arrays need to grow.
    """
    x, v, t = kinematic_views(s.kin, m.box.shape[0])
    ev_kind, ev_other, ev_stamp, counter = schedule_views(s.sched)
    for i in range(x.shape[0]):
        for k in range(m.box.shape[0]):
            s.shell[i, k] = x[i, k]
    status = build_all(
        s.shell,
        m.mobile,
        s.nbr,
        s.nbr_count,
        s.cell_count,
        s.cell_body,
        s.slot,
        s.cell,
        m.box,
        m.periodic,
        m.delta,
        m.cell_size,
        m.ncell,
        s.nbr_mark,
    )
    if status != FITS:
        return LISTS_FULL if status == LIST_FULL else CELLS_FULL
    T = s.clock[0]
    for i in range(x.shape[0]):
        advance(x, v, s.acc, t, i, T)
        predict(
            i,
            T,
            s.kin,
            x,
            v,
            s.acc,
            m.accelerated,
            t,
            s.shell,
            s.support,
            s.nbr,
            s.nbr_count,
            counter,
            m.radius,
            m.mobile,
            m.box,
            m.inv_box,
            m.periodic,
            m.delta,
            m.plane_point,
            m.plane_normal,
            s.ev_time,
            ev_kind,
            ev_other,
            ev_stamp,
        )
    calendar_build(s.ev_time, calendar_of(s))
    return DONE


@_njit_without_refcounting
def run(m, s, t_stop: float, max_events: int, log_on: bool) -> int:  # type: ignore[no-untyped-def]
    """Process events in time order up to ``t_stop``; return why it stopped.

    ``DONE``: the next event is after ``t_stop`` (the clock is set to ``t_stop``);
    ``LOG_FULL``: the event log needs emptying; ``MAX_EVENTS``: ``max_events`` processed;
    ``LISTS_FULL`` / ``CELLS_FULL``: a neighbour list or a cell row is full (grow them and
    rebuild them all; the schedule stays valid, and the event that overflowed runs again).
    """
    # unpack once: the hot functions take plain arrays (see the module docstring)
    kin = s.kin
    x, v, t = kinematic_views(kin, m.box.shape[0])
    acc, w = s.acc, s.w
    shell, support, last_coll = s.shell, s.support, s.last_coll
    nbr, nbr_count, nbr_mark, nbr_old = s.nbr, s.nbr_count, s.nbr_mark, s.nbr_old
    ev_time = s.ev_time
    sched = s.sched
    ev_kind, ev_other, ev_stamp, counter = schedule_views(sched)
    cal = calendar_of(s)
    counts, sums = s.counts, s.sums
    # grouped as tuples for the inlined callees (a call takes at most 30 arguments there)
    logbuf = (s.log_time, s.log_a, s.log_b, s.log_impulse, s.log_un, s.log_n)
    log_time, log_n = s.log_time, s.log_n
    cell, slot, cell_count, cell_body = s.cell, s.slot, s.cell_count, s.cell_body
    radius, mass, inv_mass, q, mobile = m.radius, m.mass, m.inv_mass, m.q, m.mobile
    material, face_e = m.material, m.face_e
    pair_table = (m.pair_law, m.pair_e, m.pair_beta, m.pair_friction)
    gravity, box, periodic, delta, t_c = m.gravity, m.box, m.periodic, m.delta, m.t_c
    accelerated = m.accelerated
    inv_box = m.inv_box
    plane_point, plane_normal = m.plane_point, m.plane_normal
    cell_size, ncell = m.cell_size, m.ncell

    dim = x.shape[1]
    processed = 0
    log_cap = log_time.shape[0]
    while True:
        i = calendar_top(ev_time, cal)
        T = ev_time[i] if i >= 0 else INF
        if t_stop < T or math.isinf(T):
            if t_stop < INF:
                s.clock[0] = t_stop
            return DONE
        if processed >= max_events:
            return MAX_EVENTS
        if log_on and log_n[0] + 1 > log_cap:
            return LOG_FULL
        processed += 1
        # what this event will read, asked for at once rather than miss by miss
        prefetch_row(sched, i)
        prefetch_row(kin, i)
        prefetch_row(nbr, i)
        s.clock[0] = T
        counts[C_EVENTS] += 1
        kind = ev_kind[i]
        j = -1
        advance(x, v, acc, t, i, T)  # every event moves its own body to now
        if kind == EV_PAIR:
            j = ev_other[i]
            prefetch_row(kin, j)
            prefetch_row(nbr, j)
            if counter[j] != ev_stamp[i]:
                counts[C_STALE] += 1
                j = -1  # stale: the partner collided since; just re-predict
            else:
                advance(x, v, acc, t, j, T)
                _collide_pair(
                    i,
                    j,
                    T,
                    log_on,
                    x,
                    v,
                    acc,
                    w,
                    counter,
                    last_coll,
                    support,
                    radius,
                    mass,
                    inv_mass,
                    q,
                    material,
                    pair_table,
                    face_e,
                    gravity,
                    accelerated,
                    plane_normal,
                    box,
                    periodic,
                    t_c,
                    counts,
                    sums,
                    logbuf,
                )
        elif kind == EV_WALL:
            _collide_face(
                i,
                ev_other[i],
                T,
                log_on,
                x,
                v,
                acc,
                counter,
                last_coll,
                support,
                mass,
                face_e,
                gravity,
                plane_normal,
                t_c,
                counts,
                sums,
                logbuf,
            )
        else:  # EV_SHELL
            counts[C_SHELL] += 1
            for k in range(dim):
                if periodic:
                    x[i, k] -= box[k] * np.floor(x[i, k] / box[k])
                shell[i, k] = x[i, k]
            status = rebuild_shell(
                i,
                shell,
                mobile,
                nbr,
                nbr_count,
                cell_count,
                cell_body,
                slot,
                cell,
                box,
                periodic,
                delta,
                cell_size,
                ncell,
                nbr_mark,
                nbr_old,
                counts[C_SHELL],  # a stamp no earlier rebuild used
            )
            if status != FITS:
                return LISTS_FULL if status == LIST_FULL else CELLS_FULL
        # re-schedule the bodies whose motion changed: i, and its partner j if it had one
        for body in (i, j):
            if body < 0:
                continue
            predict(
                body, T, kin, x, v, acc, accelerated, t, shell, support, nbr, nbr_count, counter,
                radius, mobile, box, inv_box, periodic, delta, plane_point, plane_normal,
                ev_time, ev_kind, ev_other, ev_stamp,
            )  # fmt: skip
            calendar_update(ev_time, body, cal)


@njit(cache=True, error_model="numpy")
def positions_at(m, s, T: float, x_out: np.ndarray, v_out: np.ndarray) -> None:  # type: ignore[no-untyped-def]
    """Every body's position and velocity at time ``T`` (periodic: wrapped into the box)."""
    dim = m.box.shape[0]
    x, v, t = kinematic_views(s.kin, dim)
    for i in range(x.shape[0]):
        dt = T - t[i]
        for k in range(dim):
            a = s.acc[i, k]
            x_out[i, k] = x[i, k] + (v[i, k] + 0.5 * a * dt) * dt
            v_out[i, k] = v[i, k] + a * dt
            if m.periodic:
                x_out[i, k] -= m.box[k] * np.floor(x_out[i, k] / m.box[k])
