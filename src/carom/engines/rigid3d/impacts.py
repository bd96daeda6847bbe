"""Isolated impacts in 3D, solved exactly: the step split at the time of impact, as the 2D
engine does (:mod:`carom.engines.rigid.impacts`).

An isolated pair is two bodies (or a body and a static one) joined by one contact and nothing
else, still apart at the start of the step or closing faster than the restitution threshold.
Between impacts both fly freely (:func:`.motion.fly`); the time of impact is found by
conservative advancement (Mirtich 1996): from a gap ``d`` (the exact distance of the two
pieces) the pair cannot touch sooner than ``d / s``, where ``s`` bounds how fast the gap can
close: the centres' relative velocity along the closest points' direction, plus each body's
largest possible spin times its reach (a free body keeps its rotational energy ``E``, so
``|w| <= sqrt(2 E / I_min)``), plus the relative gravity over what is left of the step. A step
that overshoots is bisected back.

At the contact, the impulse is Newton's restitution with the bodies' full inertia tensors:

- one point: :func:`carom.laws.rigid_impact.point_impulse` (Hecker's formula, with Coulomb
  friction: sticking, sliding, or the safe fallback);
- two to four points touching together (an edge or a face landing flat): the normal impulses
  solve the linear complementarity problem of Newton's law at every point exactly (each
  point leaves at ``-e`` times its approach speed, or faster with no impulse), by trying the
  active sets; then friction per point, clamped to its cone.

The pair then flies on to the end of the step, and may meet again within it.

A ball on a level cloth (:mod:`.cloth`) rolls in closed form instead of flying: the time of
impact bounds its acceleration in the cloth's plane by its friction ``mu g``, and two balls on
the cloth meet by :func:`carom.collide`'s law (:func:`.cloth.ball_impact`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.rigid3d.broadphase import sweep_box
from carom.engines.rigid3d.cloth import S_G, S_MU, SUPPORT, ball_impact, roll, seat
from carom.engines.rigid3d.contacts import (
    I_FLAGS,
    collide_pieces,
)
from carom.engines.rigid3d.model import PIECE_POLYTOPE
from carom.engines.rigid3d.motion import (
    apply_impulse,
    fly,
    place_piece,
    relative_velocity,
    spin_energy,
    world_inverse_row,
)
from carom.engines.stepped.impacts import (
    BOUNCED,
    HELD,
    NEW,
    PAIR_LOOKS,
    advance,
    approaching,
    closing_bound,
    earliest,
    gather,
    give_back,
    impact_cap,
    island_candidates,
    keep_island,
    logged_row,
    look_around,
    near_keys,
    search,
    started_sunk,
    statics_in,
    take_isolated,
)
from carom.engines.stepped.rows import I_BODY_A, I_BODY_B
from carom.geometry.manifold3d import MAX_POINTS, OUT_SIZE, closest_hulls
from carom.laws.rigid_impact import collision_matrix, point_impulse

__all__ = ["IMPACT_FIELDS", "cast_shape", "continuous", "exact_impacts", "normal_lcp"]

#: columns of a logged impact: time into the step, body A, body B, impulse on A (x, y, z),
#: normal speeds before and after (the first touching point), the point (x, y, z), energy
#: lost, work done by a kinematic partner, the normal (x, y, z; from B to A)
IMPACT_FIELDS = 16
#: rounds of a shape cast's advancement against one piece (each up to the search's own
#: many steps, then on from the furthest time known safe)
CAST_ROUNDS = 16


@njit(cache=True)
def _flying(n: int) -> tuple[np.ndarray, np.ndarray]:
    """The ``cloth`` of :func:`_move` for ``n`` bodies none of which is on a cloth."""
    return np.zeros((0, SUPPORT)), np.full((n, 2), -1, np.int64)


@njit(cache=True, inline="always")
def _pieces_of(tau: float, h: float) -> int:
    """Free-flight substeps for ``tau`` [s], none longer than ``h``."""
    count: int = max(1, math.ceil(tau / h))
    return count


@njit(cache=True)
def normal_lcp(k: np.ndarray, b: np.ndarray, count: int, out: np.ndarray) -> bool:
    """Normal impulses ``j >= 0`` (``out[:count]``) with ``w = K j + b >= 0`` and
    ``j . w = 0``, for a symmetric positive semi-definite ``K`` (count, count), count <= 4.

    Tries the active sets from the largest down (deterministic order) and keeps the first
    that satisfies the conditions to round-off; an active set whose ``K`` is singular (four
    coplanar points of a face: three degrees of freedom) is solved with the dependent
    impulses at zero. Every solution of a semi-definite problem moves the bodies alike.
    Returns False if none is found (cannot happen for a positive semi-definite ``K`` with a
    solution; the caller then falls back).
    """
    scale = 0.0
    for i in range(count):
        scale = max(scale, abs(k[i, i]))
    bscale = 0.0
    for i in range(count):
        bscale = max(bscale, abs(b[i]))
    tol = 1e-10 * bscale  # on velocities [m/s]
    tol_j = tol / max(scale, 1e-300)  # on impulses [N s]
    a = np.empty((MAX_POINTS, MAX_POINTS + 1))
    idx = np.empty(MAX_POINTS, np.int64)
    x = np.zeros(MAX_POINTS)
    for size in range(count, 0, -1):
        for mask in range(1, 1 << count):
            members = 0
            for i in range(count):
                if (mask >> i) & 1:
                    idx[members] = i
                    members += 1
            if members != size:
                continue
            # Gauss-Jordan on K_SS x = -b_S, partial pivoting; tiny pivots leave x at 0
            for r in range(size):
                for c in range(size):
                    a[r, c] = k[idx[r], idx[c]]
                a[r, size] = -b[idx[r]]
            pivot_of = np.full(MAX_POINTS, -1, np.int64)
            row = 0
            for c in range(size):
                best = row
                for r in range(row + 1, size):
                    if abs(a[r, c]) > abs(a[best, c]):
                        best = r
                if row >= size or abs(a[best, c]) <= 1e-12 * scale:
                    continue
                for cc in range(size + 1):
                    a[row, cc], a[best, cc] = a[best, cc], a[row, cc]
                p = a[row, c]
                for cc in range(size + 1):
                    a[row, cc] /= p
                for r in range(size):
                    if r != row and a[r, c] != 0.0:
                        f = a[r, c]
                        for cc in range(size + 1):
                            a[r, cc] -= f * a[row, cc]
                pivot_of[c] = row
                row += 1
            consistent = True
            for r in range(row, size):
                if abs(a[r, size]) > tol:
                    consistent = False
            if not consistent:
                continue
            for i in range(count):
                x[i] = 0.0
            good = True
            for c in range(size):
                value = a[pivot_of[c], size] if pivot_of[c] >= 0 else 0.0
                if value < -tol_j:
                    good = False
                x[idx[c]] = max(value, 0.0)
            if not good:
                continue
            for i in range(count):
                w = b[i]
                for jj in range(count):
                    w += k[i, jj] * x[jj]
                if w < -tol:
                    good = False
            if good:
                for i in range(count):
                    out[i] = x[i]
                return True
    return False


@njit(cache=True, inline="always")
def _point_speeds(
    a: int, b: int, ra: np.ndarray, rb: np.ndarray, v: np.ndarray, w: np.ndarray
) -> float:
    """A bound on the sizes of both bodies' velocities at a contact point, ``|v| +
    |omega| |r|`` each [m/s]: the scale of the relative velocity's round-off."""
    return float(
        np.linalg.norm(v[a]) + np.linalg.norm(w[a]) * np.linalg.norm(ra)
        + np.linalg.norm(v[b]) + np.linalg.norm(w[b]) * np.linalg.norm(rb)
    )  # fmt: skip


@njit(cache=True)
def _impact(
    a: int, b: int, count: int, out: np.ndarray, touch: float, e: float, mu: float,
    x: np.ndarray, v: np.ndarray, w: np.ndarray, inv_mass: np.ndarray, iw: np.ndarray,
    record: np.ndarray,
) -> bool:  # fmt: skip
    """Apply the exact impulse of the touching points of manifold ``out`` (normal from A to
    B, as the kernels write it); fill ``record``. Returns False when no touching point
    approaches (nothing done). ``iw`` (N, 9): world inverse inertia tensors."""
    n = np.empty(3)
    n[0], n[1], n[2] = -out[0], -out[1], -out[2]  # from B to A
    deepest = np.inf
    for j in range(count):
        deepest = min(deepest, out[6 + 4 * j])
    ra = np.empty((MAX_POINTS, 3))
    rb = np.empty((MAX_POINTS, 3))
    u = np.empty((MAX_POINTS, 3))
    un = np.empty(MAX_POINTS)
    used = 0
    scale = 0.0  # the largest sum of the two bodies' point speeds [m/s]
    for j in range(count):
        sep = out[6 + 4 * j]
        if sep > deepest + touch:
            continue
        # both bodies at the manifold's point, midway across the gap (at most the time of
        # impact's tolerance): equal and opposite impulses at one point keep the angular
        # momentum exactly
        for c in range(3):
            p = out[3 + 4 * j + c]
            ra[used, c] = p - x[a, c]
            rb[used, c] = p - x[b, c]
        ux, uy, uz = relative_velocity(a, b, ra[used], rb[used], v, w)
        u[used, 0], u[used, 1], u[used, 2] = ux, uy, uz
        un[used] = ux * n[0] + uy * n[1] + uz * n[2]
        scale = max(scale, _point_speeds(a, b, ra[used], rb[used], v, w))
        used += 1
    if not approaching(un, used, scale):
        return False
    ia = iw[a].reshape(3, 3)
    ib = iw[b].reshape(3, 3)
    impulses = np.zeros((MAX_POINTS, 3))
    if used == 1:
        kmat = collision_matrix(inv_mass[a], ia, ra[0], inv_mass[b], ib, rb[0])
        impulses[0] = point_impulse(u[0], n, kmat, e, mu)
    else:
        # the normal block of K between points i and j, and Newton's targets
        kn = np.empty((MAX_POINTS, MAX_POINTS))
        target = np.empty(MAX_POINTS)
        for i in range(used):
            for j in range(used):
                # K_ij n: the velocity change at point i of a unit normal impulse at point j
                cax = ra[j, 1] * n[2] - ra[j, 2] * n[1]
                cay = ra[j, 2] * n[0] - ra[j, 0] * n[2]
                caz = ra[j, 0] * n[1] - ra[j, 1] * n[0]
                cbx = rb[j, 1] * n[2] - rb[j, 2] * n[1]
                cby = rb[j, 2] * n[0] - rb[j, 0] * n[2]
                cbz = rb[j, 0] * n[1] - rb[j, 1] * n[0]
                dax = ia[0, 0] * cax + ia[0, 1] * cay + ia[0, 2] * caz
                day = ia[1, 0] * cax + ia[1, 1] * cay + ia[1, 2] * caz
                daz = ia[2, 0] * cax + ia[2, 1] * cay + ia[2, 2] * caz
                dbx = ib[0, 0] * cbx + ib[0, 1] * cby + ib[0, 2] * cbz
                dby = ib[1, 0] * cbx + ib[1, 1] * cby + ib[1, 2] * cbz
                dbz = ib[2, 0] * cbx + ib[2, 1] * cby + ib[2, 2] * cbz
                # (r_i x n) . I^-1 (r_j x n) for each body
                ea = (
                    (ra[i, 1] * n[2] - ra[i, 2] * n[1]) * dax
                    + (ra[i, 2] * n[0] - ra[i, 0] * n[2]) * day
                    + (ra[i, 0] * n[1] - ra[i, 1] * n[0]) * daz
                )
                eb = (
                    (rb[i, 1] * n[2] - rb[i, 2] * n[1]) * dbx
                    + (rb[i, 2] * n[0] - rb[i, 0] * n[2]) * dby
                    + (rb[i, 0] * n[1] - rb[i, 1] * n[0]) * dbz
                )
                kn[i, j] = inv_mass[a] + inv_mass[b] + ea + eb
            target[i] = un[i] + e * min(un[i], 0.0)
        jn = np.zeros(MAX_POINTS)
        if not normal_lcp(kn, target, used, jn):
            # cannot happen for a valid K; the deepest approaching point alone then
            for i in range(used):
                jn[i] = 0.0
            first = 0
            for i in range(used):
                if un[i] < un[first]:
                    first = i
            jn[first] = -(1.0 + e) * un[first] / kn[first, first]
        for i in range(used):
            for c in range(3):
                impulses[i, c] = jn[i] * n[c]
    energy = _kinetic2(a, b, v, w, inv_mass, iw)
    for i in range(used):
        apply_impulse(
            a, b, impulses[i, 0], impulses[i, 1], impulses[i, 2], ra[i], rb[i], inv_mass, iw, v, w
        )
    if used > 1 and mu > 0.0:
        # friction point by point: the tangent impulse that stops the slip there, in its cone
        for i in range(used):
            jn_i = impulses[i, 0] * n[0] + impulses[i, 1] * n[1] + impulses[i, 2] * n[2]
            if jn_i <= 0.0:
                continue
            kmat = collision_matrix(inv_mass[a], ia, ra[i], inv_mass[b], ib, rb[i])
            ux, uy, uz = relative_velocity(a, b, ra[i], rb[i], v, w)
            s = ux * n[0] + uy * n[1] + uz * n[2]
            tx, ty, tz = ux - s * n[0], uy - s * n[1], uz - s * n[2]
            slip = math.sqrt(tx * tx + ty * ty + tz * tz)
            if slip == 0.0:
                continue
            tx, ty, tz = tx / slip, ty / slip, tz / slip
            ktt = (
                tx * (kmat[0, 0] * tx + kmat[0, 1] * ty + kmat[0, 2] * tz)
                + ty * (kmat[1, 0] * tx + kmat[1, 1] * ty + kmat[1, 2] * tz)
                + tz * (kmat[2, 0] * tx + kmat[2, 1] * ty + kmat[2, 2] * tz)
            )
            jt = min(slip / ktt, mu * jn_i)
            apply_impulse(a, b, -jt * tx, -jt * ty, -jt * tz, ra[i], rb[i], inv_mass, iw, v, w)
            impulses[i, 0] -= jt * tx
            impulses[i, 1] -= jt * ty
            impulses[i, 2] -= jt * tz
    after = _kinetic2(a, b, v, w, inv_mass, iw)
    ux, uy, uz = relative_velocity(a, b, ra[0], rb[0], v, w)
    record[1] = a
    record[2] = b
    for c in range(3):
        total = 0.0
        for i in range(used):
            total += impulses[i, c]
        record[3 + c] = total
        record[8 + c] = x[a, c] + ra[0, c]
    record[6] = un[0]
    record[7] = ux * n[0] + uy * n[1] + uz * n[2]
    record[11] = energy - after
    for c in range(3):
        record[13 + c] = n[c]
    return True


@njit(cache=True, inline="always")
def _kinetic2(
    a: int, b: int, v: np.ndarray, w: np.ndarray, inv_mass: np.ndarray, iw: np.ndarray
) -> float:
    """Kinetic energy of bodies a and b [J], those that move: ``m v^2/2 + w . I w/2``."""
    energy = 0.0
    for body in (a, b):
        if inv_mass[body] > 0.0:
            energy += 0.5 * (v[body, 0] ** 2 + v[body, 1] ** 2 + v[body, 2] ** 2) / inv_mass[body]
            energy += 0.5 * spin_energy(iw, body, w)
    return energy


@njit(cache=True)
def _gap(
    pa: int, pb: int, a: int, b: int, tau: float, h: float, x: np.ndarray, q: np.ndarray,
    v: np.ndarray, w: np.ndarray, accel: np.ndarray, inertia: np.ndarray,
    inv_inertia: np.ndarray, model_ints: tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    ],
    piece_radius: np.ndarray, local_vertices: np.ndarray, local_normals: np.ndarray,
    face_first: np.ndarray, face_size: np.ndarray, corners: np.ndarray, edges: np.ndarray,
    vertices: np.ndarray, normals: np.ndarray, out: np.ndarray, ids: np.ndarray,
    cloth: tuple[np.ndarray, np.ndarray], seen: np.ndarray,
) -> tuple[float, float, float, float]:  # fmt: skip
    """Signed gap [m] between pieces pa (of body a) and pb (of b) after both move ``tau``
    [s] (:func:`_move`, in substeps of at most ``h``), and the unit direction from B to A it
    is measured along: their exact distance when apart, the deepest point of their manifold
    when not. ``seen`` (2, 3) gets the two bodies' velocities then [m/s]."""
    (
        _, piece_kind, piece_vstart, piece_vcount, piece_fstart, piece_fcount,
        piece_cstart, piece_ccount, piece_estart, piece_ecount,
    ) = model_ints  # fmt: skip
    xs = np.empty((1, 3))
    qs = np.empty((1, 4))
    vs = np.empty((1, 3))
    ws = np.empty((1, 3))
    for j, (body, piece) in enumerate(((a, pa), (b, pb))):
        xs[0] = x[body]
        qs[0] = q[body]
        vs[0] = v[body]
        ws[0] = w[body]
        if tau > 0.0 and np.isfinite(inertia[body, 0, 0]):
            _move(
                0, body, tau, _pieces_of(tau, h), xs, qs, vs, ws, accel,
                inertia[body : body + 1], inv_inertia[body : body + 1], cloth,
            )  # fmt: skip
        seen[j] = vs[0]
        place_piece(
            piece, xs, qs, 0, piece_vstart, piece_vcount, piece_fstart, piece_fcount,
            local_vertices, local_normals, vertices, normals,
        )  # fmt: skip
    count = collide_pieces(
        pa, pb, piece_kind, piece_radius, piece_vstart, piece_vcount, piece_fstart,
        piece_fcount, piece_cstart, piece_ccount, piece_estart, piece_ecount, vertices,
        normals, face_first, face_size, corners, edges, np.inf, 0.0, out, ids,
    )  # fmt: skip
    if count == 0:
        return np.inf, 0.0, 0.0, 1.0
    deepest = np.inf
    for j in range(count):
        deepest = min(deepest, out[6 + 4 * j])
    if deepest > 0.0 and piece_kind[pa] == PIECE_POLYTOPE and piece_kind[pb] == PIECE_POLYTOPE:
        # apart: face clipping may keep only points beside the closest ones; the exact
        # distance of the two polytopes decides
        vs_, vc_ = piece_vstart[pa], piece_vcount[pa]
        fs, fc = piece_fstart[pa], piece_fcount[pa]
        cs, cc = piece_cstart[pa], piece_ccount[pa]
        es, ec = piece_estart[pa], piece_ecount[pa]
        vt, vtc = piece_vstart[pb], piece_vcount[pb]
        ft, ftc = piece_fstart[pb], piece_fcount[pb]
        ct, ctc = piece_cstart[pb], piece_ccount[pb]
        et, etc = piece_estart[pb], piece_ecount[pb]
        if closest_hulls(
            vertices[vs_ : vs_ + vc_], normals[fs : fs + fc], face_first[fs : fs + fc],
            face_size[fs : fs + fc], corners[cs : cs + cc], edges[es : es + ec],
            vertices[vt : vt + vtc], normals[ft : ft + ftc], face_first[ft : ft + ftc],
            face_size[ft : ft + ftc], corners[ct : ct + ctc], edges[et : et + etc],
            np.inf, out, ids,
        ) == 0:  # fmt: skip
            return 0.0, -out[0], -out[1], -out[2]
        deepest = out[6]
    return deepest, -out[0], -out[1], -out[2]


@njit(cache=True, inline="always")
def _top_spin(
    body: int, w: np.ndarray, inv_mass: np.ndarray, iw: np.ndarray, min_moment: np.ndarray
) -> float:
    """The largest spin [rad/s] body ``body`` can reach in free flight: its rotational energy
    over its least moment, ``sqrt(2 E / I_min)`` (its own spin if it cannot move)."""
    spin = math.sqrt(w[body, 0] ** 2 + w[body, 1] ** 2 + w[body, 2] ** 2)
    if inv_mass[body] == 0.0 or spin == 0.0:
        return spin
    twice_energy = spin_energy(iw, body, w)
    # a sliver of margin for the round-off of the adjugate
    return max(spin, math.sqrt(max(twice_energy, 0.0) / min_moment[body]) * (1.0 + 1e-12))


@njit(cache=True)
def exact_impacts(
    islands: tuple[np.ndarray, np.ndarray, int, np.ndarray],
    pairs: np.ndarray,
    n_pairs: int,
    boxes: np.ndarray,
    reach: tuple[
        tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        np.ndarray,
        np.ndarray,
        np.ndarray,
    ],
    ci: np.ndarray,
    x: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    accel: np.ndarray,
    kind: np.ndarray,
    dynamic: np.ndarray,
    inv_mass: np.ndarray,
    inertia: np.ndarray,
    inv_inertia: np.ndarray,
    min_moment: np.ndarray,
    coefficients: tuple[np.ndarray, np.ndarray, np.ndarray],
    body_pieces: np.ndarray,
    model_ints: tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    ],
    piece_radius: np.ndarray,
    piece_reach: np.ndarray,
    local_vertices: np.ndarray,
    local_normals: np.ndarray,
    face_first: np.ndarray,
    face_size: np.ndarray,
    corners: np.ndarray,
    edges: np.ndarray,
    vertices: np.ndarray,
    normals: np.ndarray,
    dt: float,
    substeps: int,
    touch: float,
    margin: float,
    slow: float,
    cloth: tuple[np.ndarray, np.ndarray],
    mass: np.ndarray,
) -> tuple[np.ndarray, int]:  # fmt: skip
    """Advance each island solved exactly through the step, its impacts taken in the order
    they happen (:mod:`carom.engines.stepped.impacts`), as the 2D engine's
    (:func:`carom.engines.rigid.impacts.exact_impacts`: ``islands``, ``pairs``, ``boxes``,
    ``reach``, ``margin``, ``slow`` alike); ``coefficients``: each body's material, the restitution
    and friction tables. Free flight goes in substeps of at most ``dt / substeps``. Returns
    the impacts' log (rows of :data:`IMPACT_FIELDS`) and how many rows it holds.

    Balls on a level cloth (``cloth``: their ``support`` and ``held``,
    :func:`.cloth.candidates`) are set on it and roll in closed form between impacts
    (:func:`.cloth.roll`); two of them meet by :func:`carom.collide`'s law
    (:func:`.cloth.ball_impact`, with the bodies' ``mass`` (N,) [kg]).
    """
    isolated, island_first, n_islands, island_of = islands
    material, e_table, mu_table = coefficients
    piece_body = model_ints[0]
    out = np.empty(OUT_SIZE)
    ids = np.empty(MAX_POINTS, np.int64)
    seen = np.empty((2, 3))
    h = dt / substeps
    iw = np.zeros((x.shape[0], 9))
    cand_first, cand, watch_first, watch = gather(
        pairs, n_pairs, piece_body, kind, island_of, n_islands
    )
    clock = np.zeros(x.shape[0])  # each island body's own time into the step [s]
    log = np.zeros((max(16, 2 * island_first[n_islands]), IMPACT_FIELDS))
    logged = 0
    for k in range(n_islands):
        lo, hi = island_first[k], island_first[k + 1]
        for r in range(lo, hi):
            take_isolated(ci, isolated[r], I_FLAGS)
        kept = keep_island(ci, isolated, lo, hi, island_of, x, q, v, w)
        for body in kept[0]:
            if cloth[1][body, 0] >= 0:
                seat(body, cloth[0][body], x)
        logged_before = logged
        cp, n = island_candidates(cand, cand_first[k], cand_first[k + 1], pairs)
        hit = np.empty(cp.shape[0])  # each candidate's time of impact into the step [s]
        parting = np.full(cp.shape[0], NEW)
        # how deep a pair that stopped approaching while overlapping already was [m]: only
        # sinking deeper is an impact (a pair met late by a search, or left by the solver)
        sunk = np.zeros(cp.shape[0])
        # each candidate's turns as the earliest that met no impact or a slow one
        looks = np.zeros(cp.shape[0], np.int64)
        for c in range(n):
            hit[c] = _next_impact(
                cp[c, 0], cp[c, 1], 0.0, dt, NEW, h, clock, island_of, x, q, v, w, accel,
                inv_mass, inertia, inv_inertia, min_moment, iw, model_ints, piece_radius,
                piece_reach, local_vertices, local_normals, face_first, face_size, corners,
                edges, vertices, normals, out, ids, cloth,
            )  # fmt: skip
        now = 0.0
        taken = 0
        cap = impact_cap(n)
        stopped = False
        for _ in range(2 * cap):
            c = earliest(hit, 0, n)
            if c < 0:
                break
            now = hit[c]
            if looks[c] == PAIR_LOOKS:  # a pair held in contact, not meeting in impacts
                stopped = True
                break
            pa, pb = cp[c, 0], cp[c, 1]
            a, b = piece_body[pa], piece_body[pb]
            _sync(a, now, h, clock, island_of, x, q, v, w, accel, inertia, inv_inertia, cloth)
            _sync(b, now, h, clock, island_of, x, q, v, w, accel, inertia, inv_inertia, cloth)
            gap = _gap(
                pa, pb, a, b, 0.0, h, x, q, v, w, accel, inertia, inv_inertia, model_ints,
                piece_radius, local_vertices, local_normals, face_first, face_size, corners,
                edges, vertices, normals, out, ids, cloth, seen,
            )  # fmt: skip
            (
                _, piece_kind, piece_vstart, piece_vcount, piece_fstart, piece_fcount,
                piece_cstart, piece_ccount, piece_estart, piece_ecount,
            ) = model_ints  # fmt: skip
            tol = _tolerance(pa, pb, piece_reach)
            count = collide_pieces(
                pa, pb, piece_kind, piece_radius, piece_vstart, piece_vcount, piece_fstart,
                piece_fcount, piece_cstart, piece_ccount, piece_estart, piece_ecount,
                vertices, normals, face_first, face_size, corners, edges,
                max(2.0 * tol, gap[0]) + touch, 0.0, out, ids,
            )  # fmt: skip
            log = logged_row(log, logged)
            ma, mb = material[a], material[b]
            parting[c] = HELD
            for body in (a, b):
                world_inverse_row(body, q, inv_inertia, iw)
            if cloth[1][a, 0] >= 0 and cloth[1][b, 0] >= 0:
                met = ball_impact(
                    a, b, cloth[0], e_table[ma, mb], mu_table[ma, mb], x, v, w, mass,
                    log[logged],
                )  # fmt: skip
            else:
                met = count > 0 and _impact(
                    a, b, count, out, touch, e_table[ma, mb], mu_table[ma, mb], x, v, w,
                    inv_mass, iw, log[logged],
                )  # fmt: skip
            if not met:
                # touching, not approaching: wait for the gap to open (or close past touch)
                looks[c] += 1
                sunk[c] = max(sunk[c], -gap[0])
                hit[c] = _next_impact(
                    pa, pb, now, dt, HELD, h, clock, island_of, x, q, v, w, accel, inv_mass,
                    inertia, inv_inertia, min_moment, iw, model_ints, piece_radius,
                    piece_reach, local_vertices, local_normals, face_first, face_size,
                    corners, edges, vertices, normals, out, ids, cloth, sunk[c],
                )  # fmt: skip
                continue
            sunk[c] = 0.0
            if -log[logged, 6] < slow:  # met again slowly: perhaps held in contact
                looks[c] += 1
            elif e_table[ma, mb] > 0.0:  # hit apart at speed: the search waits for it to part
                parting[c] = BOUNCED
            log[logged, 0] = now
            logged += 1
            taken += 1
            stopped = taken == cap
            for body in (a, b):
                if not stopped and island_of[body] >= 0:
                    cp, n, stopped = _reach(
                        body, k, now, dt, cp, n, island_of, pairs, boxes, reach, watch,
                        watch_first, body_pieces, model_ints, x, q, v, w, accel, dynamic,
                        piece_radius, piece_reach, local_vertices, local_normals, vertices,
                        normals, margin, cloth,
                    )  # fmt: skip
            if stopped:
                break
            if hit.shape[0] < cp.shape[0]:  # candidates were added: room for their times
                more = cp.shape[0] - hit.shape[0]
                hit = np.concatenate((hit, np.empty(more)))
                parting = np.concatenate((parting, np.full(more, NEW)))
                sunk = np.concatenate((sunk, np.zeros(more)))
                looks = np.concatenate((looks, np.zeros(more, np.int64)))
            for d in range(n):
                da, db = piece_body[cp[d, 0]], piece_body[cp[d, 1]]
                if da in (a, b) or db in (a, b):
                    hit[d] = _next_impact(
                        cp[d, 0], cp[d, 1], now, dt, parting[d], h, clock, island_of, x, q,
                        v, w, accel, inv_mass, inertia, inv_inertia, min_moment, iw,
                        model_ints, piece_radius, piece_reach, local_vertices, local_normals,
                        face_first, face_size, corners, edges, vertices, normals, out, ids,
                        cloth, sunk[d],
                    )  # fmt: skip
        else:
            stopped = True  # (as many looks as impacts allowed, twice over)
        if stopped and logged == logged_before:  # no impact yet: the solver's whole step
            give_back(kept, ci, isolated, lo, hi, I_FLAGS, island_of, x, q, v, w)
            continue
        # the island's bodies to the end of the step, or to its last impact (the solver
        # takes them from there in the next step: they lose the rest of this one)
        end = now if stopped else dt
        for r in range(lo, hi):
            for body in (ci[isolated[r], I_BODY_A], ci[isolated[r], I_BODY_B]):
                _sync(
                    body, end, h, clock, island_of, x, q, v, w, accel, inertia, inv_inertia,
                    cloth,
                )  # fmt: skip
    return log, logged


@njit(cache=True, inline="always")
def _tolerance(pa: int, pb: int, piece_reach: np.ndarray) -> float:
    """How near two pieces count as touching [m]: a billionth of their reaches (a plane
    reaches everywhere (inf) and never turns: it counts for nothing here)."""
    reach_a = piece_reach[pa] if math.isfinite(piece_reach[pa]) else 0.0
    reach_b = piece_reach[pb] if math.isfinite(piece_reach[pb]) else 0.0
    return 1e-9 * (reach_a + reach_b)


@njit(cache=True, inline="always")
def _sync(
    body: int, t: float, h: float, clock: np.ndarray, island_of: np.ndarray, x: np.ndarray,
    q: np.ndarray, v: np.ndarray, w: np.ndarray, accel: np.ndarray, inertia: np.ndarray,
    inv_inertia: np.ndarray, cloth: tuple[np.ndarray, np.ndarray],
) -> None:  # fmt: skip
    """Move a body of an island from its own clock to ``t`` [s] into the step, in substeps
    of at most ``h``: in free flight, or rolling on its cloth (``cloth``: the balls'
    ``support`` and ``held``, :func:`.cloth.candidates`); a static body stays."""
    if island_of[body] >= 0 and t > clock[body]:
        tau = t - clock[body]
        _move(body, body, tau, _pieces_of(tau, h), x, q, v, w, accel, inertia, inv_inertia, cloth)
        clock[body] = t


@njit(cache=True, inline="always")
def _move(
    row: int, body: int, tau: float, steps: int, x: np.ndarray, q: np.ndarray, v: np.ndarray,
    w: np.ndarray, accel: np.ndarray, inertia: np.ndarray, inv_inertia: np.ndarray,
    cloth: tuple[np.ndarray, np.ndarray],
) -> None:  # fmt: skip
    """Body ``body`` on for ``tau`` [s] in ``steps`` substeps, its state in row ``row`` of
    ``x``, ``q``, ``v``, ``w``, ``inertia`` and ``inv_inertia``: rolling on its cloth
    (:func:`.cloth.roll`) or in free flight (:func:`.motion.fly`). ``accel`` and the balls'
    ``cloth`` rows are the body's."""
    support, held = cloth
    if held[body, 0] >= 0:
        roll(row, tau, steps, support[body], x, q, v, w, inertia, inv_inertia)
    else:
        fly(
            row, tau, steps, x, q, v, w, accel[body, 0], accel[body, 1], accel[body, 2],
            inertia, inv_inertia,
        )  # fmt: skip


@njit(cache=True)
def _next_impact(
    pa: int, pb: int, now: float, dt: float, parting: int, h: float, clock: np.ndarray,
    island_of: np.ndarray, x: np.ndarray, q: np.ndarray, v: np.ndarray, w: np.ndarray,
    accel: np.ndarray, inv_mass: np.ndarray, inertia: np.ndarray, inv_inertia: np.ndarray,
    min_moment: np.ndarray, iw: np.ndarray, model_ints: tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    ],
    piece_radius: np.ndarray, piece_reach: np.ndarray, local_vertices: np.ndarray,
    local_normals: np.ndarray, face_first: np.ndarray, face_size: np.ndarray,
    corners: np.ndarray, edges: np.ndarray, vertices: np.ndarray, normals: np.ndarray,
    out: np.ndarray, ids: np.ndarray, cloth: tuple[np.ndarray, np.ndarray],
    allow: float = 0.0,
) -> float:  # fmt: skip
    """Time into the step [s] of pieces pa and pb's next impact after ``now`` (their
    overlapping by more than ``allow`` [m]), before the step's end ``dt``; inf if none, and
    for a ball and the cloth that holds it (``cloth``: the balls' ``support`` and ``held``).
    Their bodies are moved to ``now`` first."""
    piece_body = model_ints[0]
    a, b = piece_body[pa], piece_body[pb]
    held = cloth[1]
    if (a >= 0 and held[a, 1] == pb) or (b >= 0 and held[b, 1] == pa):
        return np.inf
    _sync(a, now, h, clock, island_of, x, q, v, w, accel, inertia, inv_inertia, cloth)
    _sync(b, now, h, clock, island_of, x, q, v, w, accel, inertia, inv_inertia, cloth)
    for body in (a, b):
        world_inverse_row(body, q, inv_inertia, iw)
    # (a ball's turn about its centre does not move its surface; a ball on the cloth is not
    # free, and its spin is not bounded by its energy)
    reach_a = piece_reach[pa] if math.isfinite(piece_reach[pa]) and held[a, 0] < 0 else 0.0
    reach_b = piece_reach[pb] if math.isfinite(piece_reach[pb]) and held[b, 0] < 0 else 0.0
    spin = _top_spin(a, w, inv_mass, iw, min_moment) * reach_a
    spin += _top_spin(b, w, inv_mass, iw, min_moment) * reach_b
    t = _time_of_impact(
        pa, pb, a, b, dt - now, _tolerance(pa, pb, piece_reach), parting, spin, h, x, q, v,
        w, accel, inertia, inv_inertia, model_ints, piece_radius, local_vertices,
        local_normals, face_first, face_size, corners, edges, vertices, normals, out, ids,
        cloth, allow,
    )  # fmt: skip
    return now + t if t >= 0.0 else np.inf


@njit(cache=True)
def _reach(
    body: int, k: int, now: float, dt: float, cp: np.ndarray, n: int,
    island_of: np.ndarray, pairs: np.ndarray, boxes: np.ndarray, reach: tuple[
        tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        np.ndarray, np.ndarray, np.ndarray,
    ], watch: np.ndarray, watch_first: np.ndarray, body_pieces: np.ndarray,
    model_ints: tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    ],
    x: np.ndarray, q: np.ndarray, v: np.ndarray, w: np.ndarray, accel: np.ndarray,
    dynamic: np.ndarray, piece_radius: np.ndarray, piece_reach: np.ndarray,
    local_vertices: np.ndarray, local_normals: np.ndarray, vertices: np.ndarray,
    normals: np.ndarray, margin: float, cloth: tuple[np.ndarray, np.ndarray],
) -> tuple[np.ndarray, int, bool]:  # fmt: skip
    """After an impact turned ``body`` (of island ``k``, at ``now``): each of its pieces'
    swept box from now to the step's end ``dt``; beyond the box its pairs were found in, the
    statics there join the candidates ``cp[:n]``
    (:func:`carom.engines.stepped.impacts.look_around`). Returns the candidates, their
    count, and whether the island must stop (a body moving otherwise in reach). A ball on
    the cloth (``cloth``: the balls' ``support`` and ``held``) has no gravity across it, and
    at most its friction ``mu g`` in it."""
    piece_body, piece_kind, piece_vstart, piece_vcount, piece_fstart, piece_fcount = model_ints[:6]
    support, held = cloth
    box = np.empty(6)
    pull = 0.0
    g = accel[body]
    if held[body, 0] >= 0:
        pull = support[body, S_MU] * support[body, S_G]
        g = np.zeros(3)
    for p in range(body_pieces[body], body_pieces[body + 1]):
        place_piece(
            p, x, q, body, piece_vstart, piece_vcount, piece_fstart, piece_fcount,
            local_vertices, local_normals, vertices, normals,
        )  # fmt: skip
        sweep_box(
            p, body, vertices, normals, piece_kind, piece_vstart, piece_vcount, piece_fstart,
            piece_radius, piece_reach, v, w, dynamic, g, pull, dt - now, margin, box,
        )  # fmt: skip
        cp, n, stop = look_around(
            p, k, box, boxes, island_of, piece_body, reach, (pairs, watch, watch_first), cp, n
        )
        if stop:
            return cp, n, True
    return cp, n, False


@njit(cache=True)
def _time_of_impact(
    pa: int, pb: int, a: int, b: int, horizon: float, tol: float, parting: int,
    spin: float, h: float, x: np.ndarray, q: np.ndarray, v: np.ndarray, w: np.ndarray,
    accel: np.ndarray, inertia: np.ndarray, inv_inertia: np.ndarray, model_ints: tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    ],
    piece_radius: np.ndarray, local_vertices: np.ndarray, local_normals: np.ndarray,
    face_first: np.ndarray, face_size: np.ndarray, corners: np.ndarray, edges: np.ndarray,
    vertices: np.ndarray, normals: np.ndarray, out: np.ndarray, ids: np.ndarray,
    cloth: tuple[np.ndarray, np.ndarray], allow: float = 0.0,
) -> float:  # fmt: skip
    """First time in ``[0, horizon]`` [s] at which the pieces come within ``tol`` [m] of
    touching (of overlapping by ``allow`` [m], if given), by conservative advancement; -1 if
    they do not (after many steps, the furthest time known safe: the caller looks again).
    ``spin`` bounds how fast turning can close the gap [m/s]; ``parting``: how the pair
    was left at its last meeting (``NEW``, ``HELD`` or ``BOUNCED`` of
    :mod:`carom.engines.stepped.impacts`); unless ``NEW``, the search first lets the gap open
    beyond ``tol``.

    A ball on the cloth (``cloth``: the balls' ``support`` and ``held``) moves by its closed
    form (:func:`.cloth.roll`): its velocity at ``t`` is the look-ahead's, it has no gravity
    across the cloth, and its acceleration in it is at most its friction ``mu g`` (rolling
    resistance is less, :func:`.cloth.candidates`): the relative acceleration along any
    direction is bounded below by the others' gravity less both balls' friction."""
    support, held = cloth
    rolled = (held[a, 0] >= 0, held[b, 0] >= 0)
    ga = np.zeros(3) if rolled[0] else accel[a]
    gb = np.zeros(3) if rolled[1] else accel[b]
    gx, gy, gz = ga[0] - gb[0], ga[1] - gb[1], ga[2] - gb[2]
    friction = 0.0
    for body, on in ((a, rolled[0]), (b, rolled[1])):
        if on:
            friction += support[body, S_MU] * support[body, S_G]
    seen = np.empty((2, 3))
    state = search(parting)
    t = 0.0
    while True:
        d, wx, wy, wz = _gap(
            pa, pb, a, b, t, h, x, q, v, w, accel, inertia, inv_inertia, model_ints,
            piece_radius, local_vertices, local_normals, face_first, face_size, corners,
            edges, vertices, normals, out, ids, cloth, seen,
        )  # fmt: skip
        # how fast the gap can close until it could first be closed
        ux = (v[a, 0] + accel[a, 0] * t) - (v[b, 0] + accel[b, 0] * t)
        uy = (v[a, 1] + accel[a, 1] * t) - (v[b, 1] + accel[b, 1] * t)
        uz = (v[a, 2] + accel[a, 2] * t) - (v[b, 2] + accel[b, 2] * t)
        if rolled[0] or rolled[1]:
            ux = seen[0, 0] - seen[1, 0]
            uy = seen[0, 1] - seen[1, 1]
            uz = seen[0, 2] - seen[1, 2]
        closing = closing_bound(
            max(d + allow, tol),
            ux * wx + uy * wy + uz * wz,
            gx * wx + gy * wy + gz * wz - friction,
            spin,
        )
        done, t, state = advance(state, t, d + allow, closing, tol, horizon)
        if done:
            return t


@njit(cache=True)
def continuous(
    bodies: np.ndarray, x0: np.ndarray, x: np.ndarray, q: np.ndarray, v: np.ndarray,
    w: np.ndarray, ci: np.ndarray, nc: int, closest: np.ndarray, reach: tuple[
        tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        np.ndarray, np.ndarray, np.ndarray,
    ], dynamic: np.ndarray, inertia: np.ndarray, inv_inertia: np.ndarray,
    body_pieces: np.ndarray, model_ints: tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    ],
    piece_radius: np.ndarray, piece_reach: np.ndarray, local_vertices: np.ndarray,
    local_normals: np.ndarray, face_first: np.ndarray, face_size: np.ndarray,
    corners: np.ndarray, edges: np.ndarray, vertices: np.ndarray, normals: np.ndarray,
    dt: float, speculative: float, slop: float,
) -> int:  # fmt: skip
    """Continuous collision of the solver's bodies against static geometry, as the 2D
    engine's (:func:`carom.engines.rigid.impacts.continuous`), on the step's translation:
    each dynamic body of ``bodies`` that moved further than the speculative distance [m]
    from ``x0`` is swept from there to ``x`` at its orientation now (a turn within the step
    is not swept); at the first touch it is put back there, its velocity kept. Returns how
    many bodies were put back."""
    tree, open_statics, _, filters = reach
    piece_body, piece_kind, piece_vstart, piece_vcount, piece_fstart, piece_fcount = model_ints[:6]
    n_pieces = piece_body.shape[0]
    flying = _flying(x.shape[0])
    # (made at the first body that moved far: most steps have none)
    keys = np.empty(0, np.int64)
    still = np.zeros((0, 3))
    out = np.empty(OUT_SIZE)
    ids = np.empty(MAX_POINTS, np.int64)
    box = np.empty(6)
    found = np.empty(64, np.int64)
    put_back = 0
    for b in bodies:
        if not dynamic[b]:
            continue
        dx, dy, dz = x[b, 0] - x0[b, 0], x[b, 1] - x0[b, 1], x[b, 2] - x0[b, 2]
        if math.sqrt(dx * dx + dy * dy + dz * dz) <= speculative:
            continue
        if still.shape[0] == 0:
            keys = near_keys(ci, nc, closest, speculative, n_pieces)
            still = np.zeros((x.shape[0], 3))
        end = x[b].copy()
        vel = v[b].copy()
        spin = w[b].copy()
        x[b] = x0[b]
        v[b, 0], v[b, 1], v[b, 2] = dx / dt, dy / dt, dz / dt
        w[b] = 0.0
        touch = np.inf
        for p in range(body_pieces[b], body_pieces[b + 1]):
            place_piece(
                p, x, q, b, piece_vstart, piece_vcount, piece_fstart, piece_fcount,
                local_vertices, local_normals, vertices, normals,
            )  # fmt: skip
            sweep_box(
                p, b, vertices, normals, piece_kind, piece_vstart, piece_vcount, piece_fstart,
                piece_radius, piece_reach, v, w, dynamic, still[b], 0.0, dt, 0.0, box,
            )  # fmt: skip
            found, total = statics_in(box, tree, open_statics, found, filters, p, piece_body)
            for j in range(total):
                other = found[j]
                # a contact near at the start is the solver's: only sinking into it by more
                # than the slop beyond where it began is a touch, put back where it was as
                # deep as at the start
                near, depth = started_sunk(keys, closest, p, other, n_pieces)
                for allow in (depth + slop, depth):
                    t = _time_of_impact(
                        p, other, b, piece_body[other], dt, _tolerance(p, other, piece_reach),
                        NEW, 0.0, dt, x, q, v, w, still, inertia, inv_inertia, model_ints,
                        piece_radius, local_vertices, local_normals, face_first, face_size,
                        corners, edges, vertices, normals, out, ids, flying, allow,
                    )  # fmt: skip
                    if t <= 0.0 or not near:
                        break
                # (touching at once: the body's orientation now, at where the step began,
                # is not a pose it had; the solver holds that pair)
                if 0.0 < t < touch:
                    touch = t
        if touch < dt:
            for k in range(3):
                x[b, k] = x0[b, k] + v[b, k] * touch
            put_back += 1
        else:
            x[b] = end
        v[b] = vel
        w[b] = spin
    return put_back


@njit(cache=True)
def cast_shape(
    candidates: np.ndarray, cast_pieces: np.ndarray, x: np.ndarray, q: np.ndarray,
    v: np.ndarray, w: np.ndarray, accel: np.ndarray, inertia: np.ndarray,
    inv_inertia: np.ndarray, model_ints: tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    ],
    piece_radius: np.ndarray, piece_reach: np.ndarray, local_vertices: np.ndarray,
    local_normals: np.ndarray, face_first: np.ndarray, face_size: np.ndarray,
    corners: np.ndarray, edges: np.ndarray, vertices: np.ndarray, normals: np.ndarray,
    categories: np.ndarray, mask: int, hit: np.ndarray,
) -> int:  # fmt: skip
    """The first of the pieces ``candidates`` (K,) that a shape moving without turning
    would touch: the shape is the body of ``cast_pieces`` (its last row in ``x``, ``q``; its
    velocity ``v`` the whole move [m], so time is the fraction of the move), every other body
    held still (zero ``v``, ``w``, ``accel``). By the exact path's conservative advancement
    (:func:`_time_of_impact`, in rounds from where the last stopped safe), to a billionth of
    the two pieces' reach. Returns the piece hit (-1: none) and writes ``hit``: the fraction,
    the point (3) and the piece's outward normal there (3). A piece whose ``categories`` (P,)
    bits hold none of ``mask`` is not seen."""
    piece_body = model_ints[0]
    out = np.empty(OUT_SIZE)
    ids = np.empty(MAX_POINTS, np.int64)
    cb = piece_body[cast_pieces[0]]
    flying = _flying(x.shape[0])
    seen = np.empty((2, 3))
    start = x[cb].copy()
    best = 1.0
    found = -1
    for j in range(candidates.shape[0]):
        p = candidates[j]
        b = piece_body[p]
        if categories[p] & mask == 0:
            continue
        for c in cast_pieces:
            tol = _tolerance(c, p, piece_reach)
            done = 0.0
            x[cb] = start
            for _ in range(CAST_ROUNDS):
                t = _time_of_impact(
                    c, p, cb, b, best - done, tol, NEW, 0.0, 1.0, x, q, v, w, accel,
                    inertia, inv_inertia, model_ints, piece_radius, local_vertices,
                    local_normals, face_first, face_size, corners, edges, vertices, normals,
                    out, ids, flying,
                )  # fmt: skip
                if t < 0.0:
                    break
                d, nx, ny, nz = _gap(
                    c, p, cb, b, t, 1.0, x, q, v, w, accel, inertia, inv_inertia, model_ints,
                    piece_radius, local_vertices, local_normals, face_first, face_size,
                    corners, edges, vertices, normals, out, ids, flying, seen,
                )  # fmt: skip
                if d <= tol:
                    if done + t < best or found < 0:
                        best = done + t
                        found = p
                        hit[0] = best
                        count = collide_pieces(
                            c, p, model_ints[1], piece_radius, model_ints[2], model_ints[3],
                            model_ints[4], model_ints[5], model_ints[6], model_ints[7],
                            model_ints[8], model_ints[9], vertices, normals, face_first,
                            face_size, corners, edges, np.inf, 0.0, out, ids,
                        )  # fmt: skip
                        deepest = 0
                        for k in range(1, count):
                            if out[6 + 4 * k] < out[6 + 4 * deepest]:
                                deepest = k
                        for a in range(3):
                            hit[1 + a] = out[3 + 4 * deepest + a]
                        hit[4], hit[5], hit[6] = nx, ny, nz
                    break
                done += t  # safe so far: on from there
                for a in range(3):
                    x[cb, a] = start[a] + done * v[cb, a]
    x[cb] = start
    return found
