"""Prediction: a body's next event (a collision with a neighbour, a wall or a plane, or leaving
its neighbour shell), and the free flight between events.

Bodies fly on straight lines, or parabolas under gravity. Times of impact use the
cancellation-free forms of :mod:`carom.geometry.toi` (PHYSICS.md section 4).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.edmd.calendar import calendar_views
from carom.engines.edmd.codes import EV_NONE, EV_PAIR, EV_SHELL, EV_WALL, SHELL_MARGIN
from carom.engines.edmd.jitflags import njit_inlined
from carom.engines.edmd.prefetch import prefetch_row
from carom.engines.edmd.state import (
    KIN_R,
    KIN_T,
    KIN_V,
    KIN_WIDTH,
    SCHED_KIND,
    SCHED_OTHER,
    SCHED_STAMP,
)
from carom.geometry.toi import (
    INF,
    first_root_quartic,
    shell_exit_time,
    toi_gap,
    toi_sphere_sphere,
)


@njit_inlined
def face_normal(plane_normal: np.ndarray, dim: int, face: int, k: int) -> float:
    """Component ``k`` of the inward unit normal of wall face or plane ``face``."""
    if face < 2 * dim:
        if k != face // 2:
            return 0.0
        return 1.0 if face % 2 == 0 else -1.0
    return float(plane_normal[face - 2 * dim, k])


@njit_inlined
def set_support(
    pull: np.ndarray,
    plane_normal: np.ndarray,
    support: np.ndarray,
    acc: np.ndarray,
    i: int,
    face: int,
) -> None:
    """Rest body ``i`` on ``face`` (or lift it off, ``face = -1``) and update its acceleration:
    its pull (gravity, and a force's over its mass through a step that has one), less the
    normal part the face bears."""
    dim = pull.shape[1]
    support[i] = face
    g_n = 0.0
    if face >= 0:
        for k in range(dim):
            g_n += pull[i, k] * face_normal(plane_normal, dim, face, k)
    for k in range(dim):
        nk = face_normal(plane_normal, dim, face, k) if face >= 0 else 0.0
        acc[i, k] = pull[i, k] - g_n * nk


@njit(cache=True, error_model="numpy", inline="always")
def kinematic_views(kin: np.ndarray, dim: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Positions (N, dim), velocities (N, dim) and clocks (N,): views into ``kin``."""
    return kin[:, :dim], kin[:, KIN_V : KIN_V + dim], kin[:, KIN_T]


@njit(cache=True, error_model="numpy", inline="always")
def schedule_views(sched: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Event kinds, partners and stamps, (N,) each: views into ``sched``."""
    return sched[:, SCHED_KIND], sched[:, SCHED_OTHER], sched[:, SCHED_STAMP]


@njit(cache=True, error_model="numpy", inline="always")
def calendar_of(s):  # type: ignore[no-untyped-def]
    """The event calendar's arrays of state ``s``, as :mod:`carom.engines.edmd.calendar`
    takes them."""
    cal_next, cal_prev, cal_loc, cur_where = calendar_views(s.cal_body)
    return (
        s.cal_head,
        cal_next,
        cal_prev,
        cal_loc,
        s.cur_heap,
        s.cur_key,
        cur_where,
        s.cal_f,
        s.cal_i,
    )


@njit_inlined
def free_flight(
    x: np.ndarray,
    v: np.ndarray,
    acc: np.ndarray,
    gravity: np.ndarray | None,
    t: np.ndarray,
    i: int,
    T: float,
) -> None:
    """Move body ``i`` along its free flight to time ``T`` and set its clock. Without gravity
    (``gravity`` None) every acceleration is +0.0 and is not read (a cache miss saved at
    large N; the same arithmetic)."""
    dt = T - t[i]
    if dt != 0.0:
        for k in range(x.shape[1]):
            a = 0.0 if gravity is None else acc[i, k]
            x[i, k] += (v[i, k] + 0.5 * a * dt) * dt
            v[i, k] += a * dt
    t[i] = T


@njit_inlined
def _first_pair_2d(
    i: int,
    T: float,
    best: float,
    kin: np.ndarray,
    nbr: np.ndarray,
    count: int,
    periodic: bool,
    xi0: float,
    xi1: float,
    vi0: float,
    vi1: float,
    rad: float,
    L0: float,
    L1: float,
    inv0: float,
    inv1: float,
) -> tuple[float, int]:
    """:func:`_first_pair_straight` in 2D: one pass, a neighbour at a time, reading each
    record in place. With eight or so neighbours a disk, the copy into columns and the
    vector pass of 3D cost more than they save: interleaved A/B against them, the same at
    10^4 disks (0.985 to 1.031) and 1.03 to 1.11x at 10^6. The same arithmetic without the z
    terms, which are zeros in 2D (adding zero changes no sum): the same times, bit for bit."""
    other = -1
    for slot in range(count):
        j = nbr[i, slot]
        dtj = T - kin[j, KIN_T]
        vj0, vj1 = kin[j, KIN_V], kin[j, KIN_V + 1]
        r0 = xi0 - (kin[j, 0] + vj0 * dtj)
        r1 = xi1 - (kin[j, 1] + vj1 * dtj)
        if periodic:
            r0 -= L0 * np.floor(r0 * inv0 + 0.5)
            r1 -= L1 * np.floor(r1 * inv1 + 0.5)
        dv0 = vi0 - vj0
        dv1 = vi1 - vj1
        rr = r0 * r0 + r1 * r1
        rv = r0 * dv0 + r1 * dv1
        vv = dv0 * dv0 + dv1 * dv1
        reach = rad + kin[j, KIN_R]
        c = rr - reach * reach
        disc = rv * rv - vv * c
        tp = max(c / (math.sqrt(max(disc, 0.0)) - rv if rv < 0.0 else 1.0), 0.0)
        tp = tp if (rv < 0.0 and disc >= 0.0) else INF
        if tp < best:
            best = tp
            other = j
    return best, other


@njit_inlined
def _first_pair_straight(
    i: int,
    T: float,
    best: float,
    kin: np.ndarray,
    nbr: np.ndarray,
    nbr_count: np.ndarray,
    near: np.ndarray,
    box: np.ndarray,
    periodic: bool,
) -> tuple[float, int]:
    """Body ``i``'s first collision with a neighbour before ``best`` when nothing accelerates.

    Returns ``(time from T, neighbour)``, or ``(best, -1)``; of equal times, the first in
    ``i``'s list. The same arithmetic as :func:`carom.geometry.toi.toi_sphere_sphere`, written
    out per component. The hot loop of the engine: every neighbour's record is asked for first
    (:func:`prefetch_row`), so that the misses overlap; in 2D one pass follows
    (:func:`_first_pair_2d`); in 3D three, so that the middle one runs four neighbours per
    instruction (AVX2; in 3D measured 2x faster than one neighbour at a time with branches, and
    1.2x at 10^4 spheres than the 2D pass with z terms added): copy each neighbour's record of
    ``kin`` (one cache line) into column ``slot`` of the scratch ``near`` (``KIN_WIDTH + 1``,
    K) float64; compute every time of impact into its last row, without branches (a select per
    neighbour, where a mispredicted branch would cost more than the square root and division it
    skips); then take the first smallest. Vector square roots and divisions are
    IEEE-exact like scalar ones and nothing is reordered, so the times are the same bits.
    """
    xi0, xi1, xi2 = kin[i, 0], kin[i, 1], kin[i, 2]
    vi0, vi1, vi2 = kin[i, KIN_V], kin[i, KIN_V + 1], kin[i, KIN_V + 2]
    L0, L1 = box[0], box[1]
    L2 = box[2] if box.shape[0] == 3 else 1.0
    inv0, inv1, inv2 = 1.0 / L0, 1.0 / L1, 1.0 / L2
    rad = kin[i, KIN_R]
    count = nbr_count[i]
    for slot in range(count):
        prefetch_row(kin, nbr[i, slot])
    if box.shape[0] == 2:
        return _first_pair_2d(
            i, T, best, kin, nbr, count, periodic, xi0, xi1, vi0, vi1, rad, L0, L1, inv0, inv1
        )
    for slot in range(count):
        j = nbr[i, slot]
        for k in range(KIN_WIDTH):
            near[k, slot] = kin[j, k]
    for slot in range(count):
        dtj = T - near[KIN_T, slot]
        vj0, vj1, vj2 = near[KIN_V, slot], near[KIN_V + 1, slot], near[KIN_V + 2, slot]
        r0 = xi0 - (near[0, slot] + vj0 * dtj)
        r1 = xi1 - (near[1, slot] + vj1 * dtj)
        r2 = xi2 - (near[2, slot] + vj2 * dtj)
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
        reach = rad + near[KIN_R, slot]
        c = rr - reach * reach
        disc = rv * rv - vv * c
        # the smaller root of vv t^2 + 2 rv t + c, cancellation-free (rv < 0); 0 when already
        # touching and approaching; none when separating or passing by (the denominator is
        # never zero, even where discarded)
        tp = max(c / (math.sqrt(max(disc, 0.0)) - rv if rv < 0.0 else 1.0), 0.0)
        near[KIN_WIDTH, slot] = tp if (rv < 0.0 and disc >= 0.0) else INF
    other = -1
    for slot in range(count):
        tp = near[KIN_WIDTH, slot]
        if tp < best:
            best = tp
            other = nbr[i, slot]
    return best, other


@njit_inlined
def predict(
    i: int,
    T: float,
    kin: np.ndarray,
    x: np.ndarray,
    v: np.ndarray,
    acc: np.ndarray,
    gravity: np.ndarray | None,
    t: np.ndarray,
    shell: np.ndarray,
    support: np.ndarray,
    nbr: np.ndarray,
    nbr_count: np.ndarray,
    near: np.ndarray,
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
    rad = kin[i, KIN_R]  # radius[i], in the line already read
    off2 = 0.0
    off_v = 0.0
    speed2 = 0.0
    acc2 = 0.0
    for k in range(dim):
        d = x[i, k] - shell[i, k]
        off2 += d * d
        off_v += d * v[i, k]
        speed2 += v[i, k] * v[i, k]
        a = 0.0 if gravity is None else acc[i, k]  # all +0.0 without gravity: not read
        acc2 += a * a
    # leave the shell a hair early, so that round-off in the exit time never lets a body
    # stray beyond delta from its centre
    best = shell_exit_time(off2, off_v, speed2, math.sqrt(acc2), delta * SHELL_MARGIN)
    kind = EV_SHELL
    other = -1

    # walls (faces 0 .. 2 dim - 1, none when periodic) and planes (faces 2 dim + p): the gap
    # d(t) = d0 + u t + acc t^2 / 2 along each inward normal
    first_face = 2 * dim if periodic else 0
    # (without gravity, acc and support are None: every acceleration is +0.0, nothing rests)
    for face in range(first_face, 2 * dim + plane_normal.shape[0]):
        if gravity is not None and face == support[i]:
            continue
        if face < 2 * dim:
            k = face // 2
            if face % 2 == 0:
                d0 = x[i, k] - rad
                u = v[i, k]
                a_n = 0.0 if gravity is None else acc[i, k]
            else:
                d0 = box[k] - x[i, k] - rad
                u = -v[i, k]
                a_n = -(0.0 if gravity is None else acc[i, k])
        else:
            p = face - 2 * dim
            d0 = -rad
            u = 0.0
            a_n = 0.0
            for q in range(dim):
                nq = plane_normal[p, q]
                d0 += nq * (x[i, q] - plane_point[p, q])
                u += nq * v[i, q]
                if gravity is not None:
                    a_n += nq * acc[i, q]
        tf = toi_gap(d0, u, a_n)
        if tf < best:
            best = tf
            kind = EV_WALL
            other = face

    # neighbours: relative motion r + v t + da t^2 / 2, j extrapolated to T on the fly
    if gravity is None:
        tp, j = _first_pair_straight(i, T, best, kin, nbr, nbr_count, near, box, periodic)
        if j >= 0:
            best = tp
            kind = EV_PAIR
            other = j
    else:  # parabolas: pruned before typing when gravity is None (see Model.gravity)
        for slot in range(nbr_count[i]):
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
                tp = first_root_quartic(
                    0.25 * dada, vda, vv + rda, 2.0 * rv, rr - reach * reach, best
                )
            if tp < best:
                best = tp
                kind = EV_PAIR
                other = j

    ev_time[i] = T + best
    ev_kind[i] = kind
    ev_other[i] = other
    if kind == EV_PAIR:
        ev_stamp[i] = counter[other]
