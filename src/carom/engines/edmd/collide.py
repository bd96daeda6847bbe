"""Collisions: what an event between two bodies, or a body and a wall or plane, does to them.

The impulse laws are :mod:`carom.laws.kernels` (PHYSICS.md sections 1 and 3); this module adds
the engine's rules around them: the TC model, rest on a support, the parting-speed floor, the
energy ledger and the log (the module docstring of :mod:`carom.engines.edmd.loop`).
"""

from __future__ import annotations

import math

import numpy as np

from carom.engines.edmd.codes import (
    C_FLOOR,
    C_PAIR,
    C_REST,
    C_TC,
    C_WALL,
    S_KE_GIVEN,
    S_KE_LOST,
    S_VIRIAL,
)
from carom.engines.edmd.hints import unlikely
from carom.engines.edmd.jitflags import njit_inlined
from carom.engines.edmd.predict import face_normal, set_support
from carom.geometry.rotation import turn
from carom.laws.kernels import LAW_SMOOTH, impulse_spheres

#: the log buffer's arrays: times, bodies, partners, impulses, normal speeds, contact points,
#: normals, and the count (State.log_*)
LogBuffer = tuple[
    np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    np.ndarray,
]  # fmt: skip


@njit_inlined
def log_event(
    logbuf: LogBuffer,
    T: float,
    a: int,
    b: int,
    j0: float,
    j1: float,
    j2: float,
    un_before: float,
    un_after: float,
    p0: float,
    p1: float,
    p2: float,
    n0: float,
    n1: float,
    n2: float,
) -> None:
    """Append one collision to the log: time, bodies (or face), impulse on ``a``, normal
    speeds before and after, the contact point ``p`` [m] (with the impulse, the angular
    impulse about any centre: ``(p - x) x J``) and the unit normal ``n`` from ``a`` to its
    partner."""
    log_time, log_a, log_b, log_impulse, log_un, log_point, log_normal, log_n = logbuf
    n = log_n[0]
    log_point[n, 0] = p0
    log_point[n, 1] = p1
    log_point[n, 2] = p2
    log_normal[n, 0] = n0
    log_normal[n, 1] = n1
    log_normal[n, 2] = n2
    log_time[n] = T
    log_a[n] = a
    log_b[n] = b
    log_impulse[n, 0] = j0
    log_impulse[n, 1] = j1
    log_impulse[n, 2] = j2
    log_un[n, 0] = un_before
    log_un[n, 1] = un_after
    log_n[0] = n + 1


@njit_inlined
def contact_velocity(
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


@njit_inlined
def collide_pair(
    i: int,
    j: int,
    T: float,
    log_on: bool,
    x: np.ndarray,
    v: np.ndarray,
    acc: np.ndarray,
    rot: tuple[np.ndarray, np.ndarray, np.ndarray],
    counter: np.ndarray,
    last_coll: np.ndarray,
    support: np.ndarray,
    radius: np.ndarray,
    mass: np.ndarray,
    inv_mass: np.ndarray,
    q: np.ndarray | None,
    material: np.ndarray,
    pair_table: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    face_e: np.ndarray,
    pull: np.ndarray | None,
    plane_normal: np.ndarray,
    box: np.ndarray,
    periodic: bool,
    t_c: float,
    counts: np.ndarray,
    sums: np.ndarray,
    logbuf: LogBuffer,
) -> None:
    """Bodies ``i`` and ``j`` (both at time ``T``) meet: the impulse law, then the engine's
    rules. ``rot`` is (spins (N, 3), orientations (N, 4), their clocks (N,)): three Nones,
    with ``q`` None, when no body spins (every law is smooth). The branches on ``q is None``
    are pruned before typing then (Numba prunes on an argument that is None, not on a tuple's
    item), and the code that turns bodies is not compiled."""
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
    inv_i = inv_mass[i]
    inv_j = inv_mass[j]
    if q is None:  # no spins: every law is smooth, which needs only dv (contact_velocity)
        g0, g1, g2 = dv0, dv1, dv2
        inv_qi = inv_qj = 0.0
    else:
        g0, g1, g2 = contact_velocity(dv0, dv1, dv2, rot[0], i, j, a_i, a_j, n0, n1, n2, law)
        smooth = law == LAW_SMOOTH  # (spins do not enter the smooth law)
        inv_qi = 0.0 if smooth else 1.0 / q[i]
        inv_qj = 0.0 if smooth else 1.0 / q[j]
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
        inv_qi,
        inv_qj,
    )
    # They must part: else the next prediction finds them meeting now again, a loop of
    # events at one time. The impulse law makes them part at e times the approach speed,
    # which is zero, or round-off, when they meet at a grazing angle, in a plastic impact
    # (e = 0), or when gravity presses them together (one rests on a support or is static,
    # the other is pulled onto it: a resting contact, which hard spheres do not have). The
    # parting speed is raised, when below it, to
    #     u_min = 2^-48 |g| + max(0, -a_n) t_c / 4,
    # 16 ulps of the relative speed, above the round-off of the approach test and below any
    # measurement; under a pull a_n, the speed that brings them back after t_c / 2, within
    # the TC model's window: the next touch is elastic, and they leave at u_min again with
    # nothing more given (energy given once: m a_n^2 t_c^2 / 32, 1e-12 J for 1 kg at
    # t_c = 1e-6 s). The extra impulse is an impulse like any other, in the log; the energy it
    # gives is booked apart from the law's dissipation (S_KE_GIVEN).
    u = g0 * n0 + g1 * n1 + g2 * n2
    u_pull = 0.0
    if pull is not None:
        a_n = 0.0
        for k in range(dim):
            nk = n0 if k == 0 else (n1 if k == 1 else n2)
            a_n += (acc[i, k] - acc[j, k]) * nk
        u_pull = max(0.0, -a_n) * t_c * 0.25
    gg = g0 * g0 + g1 * g1 + g2 * g2
    jn = j0 * n0 + j1 * n1 + j2 * n2  # the impulse on i along n [N s]
    inv_sum = inv_i + inv_j
    extra, given = parting_floor(u, jn, inv_sum, u_pull, gg)
    # A body resting on a support and pressed gently into it (gently: the support would hold
    # it, by support_reaction's rule) does not move along the support's normal f: the support
    # takes that part of the load, as a resting contact does, and the pair meets an inverse
    # mass (1 - c^2) / m along n for it (c = n . f). Without this, a ball hopping on one that
    # rests on the floor left at half the parting speed (the lower ball took the rest into
    # the floor, which stopped it), was back too slowly, and was given that speed again at
    # every hop: galton-board gained 0.21 J that way. (Smooth law: the impulse is along n.)
    held_i = held_j = False
    # (supports exist only under gravity; without it, this code is pruned before typing)
    if pull is not None and unlikely(support[i] >= 0 or support[j] >= 0) and law == LAW_SMOOTH:
        push = jn + extra
        ci = held_cosine(i, push, n0, n1, n2, support, inv_i, face_e, pull, plane_normal, t_c)
        cj = held_cosine(j, -push, n0, n1, n2, support, inv_j, face_e, pull, plane_normal, t_c)
        held_i = ci != 0.0
        held_j = cj != 0.0
        k_held = inv_i * (1.0 - ci * ci) + inv_j * (1.0 - cj * cj)
        if (held_i or held_j) and k_held > 2.0**-20 * inv_sum:
            scale = inv_sum / k_held
            j0 *= scale
            j1 *= scale
            j2 *= scale
            inv_sum = k_held
            extra, given = parting_floor(u, jn * scale, inv_sum, u_pull, gg)
        else:  # nothing held, or wedged between two supports along n: free masses
            held_i = held_j = False
    if extra > 0.0:
        j0 += extra * n0
        j1 += extra * n1
        j2 += extra * n2
        counts[C_FLOOR] += 1
        sums[S_KE_GIVEN] += given
    if j0 == 0.0 and j1 == 0.0 and j2 == 0.0:
        return  # at rest relative to each other, and nothing pulls them together
    un_before = dv0 * n0 + dv1 * n1 + dv2 * n2
    for k in range(dim):
        jk = j0 if k == 0 else (j1 if k == 1 else j2)
        v[i, k] += jk * inv_i
        v[j, k] -= jk * inv_j
    if pull is not None and held_i:
        hold_on_support(i, v, support, plane_normal)
    if pull is not None and held_j:
        hold_on_support(j, v, support, plane_normal)
    if q is not None and unlikely(law != LAW_SMOOTH):
        # the spins change: first turn both bodies to now at their old spins
        w, orient, orient_t = rot
        turn(orient, i, w[i, 0], w[i, 1], w[i, 2], T - orient_t[i], dim)
        turn(orient, j, w[j, 0], w[j, 1], w[j, 2], T - orient_t[j], dim)
        orient_t[i] = T
        orient_t[j] = T
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
    if q is None:
        h0, h1, h2 = u0, u1, u2
    else:
        h0, h1, h2 = contact_velocity(u0, u1, u2, rot[0], i, j, a_i, a_j, n0, n1, n2, law)
    # energy dissipated = minus the impulse's work, J . (g_before + g_after) / 2 for rigid
    # bodies (exact, and free of the cancellation of KE_before - KE_after); the law's part
    # is that plus what the floor gave
    sums[S_KE_LOST] += given - 0.5 * (j0 * (g0 + h0) + j1 * (g1 + h1) + j2 * (g2 + h2))
    counter[i] += 1
    counter[j] += 1
    last_coll[i] = T
    last_coll[j] = T
    counts[C_PAIR] += 1
    sums[S_VIRIAL] += j0 * r0 + j1 * r1 + j2 * r2
    # a body resting on a support: lifted off, or pushed into it (the support pushes back)
    if pull is not None and support[i] >= 0:
        support_reaction(i, v, acc, support, face_e, pull, plane_normal, mass, t_c, sums)
    if pull is not None and support[j] >= 0:
        support_reaction(j, v, acc, support, face_e, pull, plane_normal, mass, t_c, sums)
    if log_on:
        # the contact point: on j's surface towards i (raw coordinates; periodic boxes wrap
        # it when the log is read)
        log_event(
            logbuf,
            T,
            i,
            j,
            j0,
            j1,
            j2,
            un_before,
            un_after,
            x[j, 0] + a_j * n0,
            x[j, 1] + a_j * n1,
            x[j, 2] + a_j * n2 if dim == 3 else 0.0,
            -n0,  # (n points from j to i)
            -n1,
            -n2 if dim == 3 else 0.0,
        )


@njit_inlined
def parting_floor(
    u: float, jn: float, inv_sum: float, u_pull: float, gg: float
) -> tuple[float, float]:
    """The extra normal impulse [N s] that raises a pair's parting speed to the floor
    ``u_min = 2^-48 |g| + u_pull`` (collide_pair says why), and the energy it gives [J]; zeros
    when the law's impulse ``jn`` already parts them. ``u`` is the normal contact speed
    before [m/s], ``inv_sum`` the pair's inverse mass along n [1/kg], ``gg = |g|^2``."""
    u_out = u + jn * inv_sum
    d = u_out - u_pull
    if d < 0.0 or d * d < 2.0**-96 * gg:
        u_min = 2.0**-48 * math.sqrt(gg) + u_pull
        extra = (u_min - u_out) / inv_sum
        # its work, (1/2) mu (u_min^2 - u_out^2) with mu = 1 / inv_sum (a normal impulse
        # turns no spin: n x n = 0)
        return extra, 0.5 * extra * (u_min + u_out)
    return 0.0, 0.0


@njit_inlined
def held_cosine(
    b: int,
    push: float,
    n0: float,
    n1: float,
    n2: float,
    support: np.ndarray,
    inv_b: float,
    face_e: np.ndarray,
    pull: np.ndarray,
    plane_normal: np.ndarray,
    t_c: float,
) -> float:
    """Whether body ``b``'s support holds it against an impulse ``push n`` on it [N s]: the
    cosine ``n . f`` of ``n`` and the support's normal ``f`` if ``b`` rests on a support, the
    impulse presses it in, and bounced off with the support's restitution it would be back
    within ``t_c`` (support_reaction keeps it resting); 0 otherwise (a held body's cosine is
    never 0: an impulse along the face presses nothing in)."""
    face = support[b]
    if face < 0:
        return 0.0
    dim = pull.shape[1]
    c = 0.0
    g_n = 0.0
    for k in range(dim):
        fk = face_normal(plane_normal, dim, face, k)
        c += (n0 if k == 0 else (n1 if k == 1 else n2)) * fk
        g_n += pull[b, k] * fk
    un = push * c * inv_b  # its speed along f after the impulse (it rests: zero before)
    if un < 0.0 and -2.0 * face_e[face] * un < -g_n * t_c:
        return c
    return 0.0


@njit_inlined
def hold_on_support(b: int, v: np.ndarray, support: np.ndarray, plane_normal: np.ndarray) -> None:
    """Body ``b`` stays on its support: its velocity along the support's normal is zero."""
    dim = v.shape[1]
    face = support[b]
    un = 0.0
    for k in range(dim):
        un += v[b, k] * face_normal(plane_normal, dim, face, k)
    for k in range(dim):
        v[b, k] -= un * face_normal(plane_normal, dim, face, k)


@njit_inlined
def support_reaction(
    b: int,
    v: np.ndarray,
    acc: np.ndarray,
    support: np.ndarray,
    face_e: np.ndarray,
    pull: np.ndarray,
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
        g_n += pull[b, k] * nk
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
        # -1 typed, not a literal (a literal argument compiles a second copy of the helper)
        set_support(pull, plane_normal, support, acc, b, np.int64(-1))  # type: ignore[arg-type]


@njit_inlined
def collide_face(
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
    radius: np.ndarray,
    mass: np.ndarray,
    face_e: np.ndarray,
    pull: np.ndarray | None,
    plane_normal: np.ndarray,
    t_c: float,
    counts: np.ndarray,
    sums: np.ndarray,
    logbuf: LogBuffer,
) -> None:
    """Body ``i`` (at time ``T``) meets wall or plane ``face`` (smooth: spins are kept)."""
    dim = x.shape[1]
    un = 0.0
    acc_n = 0.0
    for k in range(dim):
        nk = face_normal(plane_normal, dim, face, k)
        un += v[i, k] * nk
        if pull is not None:  # (else acc is None: no acceleration)
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
    if pull is not None and rest:  # (rest needs a pull: never without gravity)
        set_support(pull, plane_normal, support, acc, i, face)
    counter[i] += 1
    last_coll[i] = T
    counts[C_WALL] += 1
    sums[S_VIRIAL] += x_dot_j
    sums[S_KE_LOST] += 0.5 * mass[i] * (1.0 - e * e) * un * un  # walls are smooth
    if log_on:
        log_event(
            logbuf,
            T,
            i,
            -1 - face,
            jn * face_normal(plane_normal, dim, face, 0),
            jn * face_normal(plane_normal, dim, face, 1),
            jn * face_normal(plane_normal, dim, face, 2) if dim == 3 else 0.0,
            un,
            u_out,
            x[i, 0] - radius[i] * face_normal(plane_normal, dim, face, 0),
            x[i, 1] - radius[i] * face_normal(plane_normal, dim, face, 1),
            x[i, 2] - radius[i] * face_normal(plane_normal, dim, face, 2) if dim == 3 else 0.0,
            -face_normal(plane_normal, dim, face, 0),  # (the face's normal points inward)
            -face_normal(plane_normal, dim, face, 1),
            -face_normal(plane_normal, dim, face, 2) if dim == 3 else 0.0,
        )
