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
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

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
    MAX_IMPACTS,
    advance,
    approaching,
    search,
    take_isolated,
)
from carom.geometry.manifold3d import MAX_POINTS, OUT_SIZE, closest_hulls
from carom.laws.rigid_impact import collision_matrix, point_impulse

__all__ = ["IMPACT_FIELDS", "exact_impacts", "normal_lcp"]

#: columns of a logged impact: time into the step, body A, body B, impulse on A (x, y, z),
#: normal speeds before and after (the first touching point), the point (x, y, z), energy
#: lost
IMPACT_FIELDS = 13


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
        used += 1
    if not approaching(un, used):
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
) -> tuple[float, float, float, float]:  # fmt: skip
    """Signed gap [m] between pieces pa (of body a) and pb (of b) after both fly ``tau`` [s]
    (in substeps of at most ``h``), and the unit direction from B to A it is measured along:
    their exact distance when apart, the deepest point of their manifold when not."""
    (
        _, piece_kind, piece_vstart, piece_vcount, piece_fstart, piece_fcount,
        piece_cstart, piece_ccount, piece_estart, piece_ecount,
    ) = model_ints  # fmt: skip
    xs = np.empty((1, 3))
    qs = np.empty((1, 4))
    vs = np.empty((1, 3))
    ws = np.empty((1, 3))
    for body, piece in ((a, pa), (b, pb)):
        xs[0] = x[body]
        qs[0] = q[body]
        vs[0] = v[body]
        ws[0] = w[body]
        if tau > 0.0 and np.isfinite(inertia[body, 0, 0]):
            steps = _pieces_of(tau, h)
            fly(
                0, tau, steps, xs, qs, vs, ws, accel[body, 0], accel[body, 1], accel[body, 2],
                inertia[body : body + 1], inv_inertia[body : body + 1],
            )  # fmt: skip
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
    isolated: np.ndarray,
    n_isolated: int,
    closing: np.ndarray,
    ci: np.ndarray,
    x: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    accel: np.ndarray,
    dynamic: np.ndarray,
    inv_mass: np.ndarray,
    inertia: np.ndarray,
    inv_inertia: np.ndarray,
    min_moment: np.ndarray,
    e_pair: np.ndarray,
    mu_pair: np.ndarray,
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
    log: np.ndarray,
) -> int:  # fmt: skip
    """Advance each isolated contact's two bodies through the step, impacts solved exactly.

    ``isolated[:n_isolated]`` are contact rows, ``closing`` every contact's least normal
    speed at the step's start (a pair already separating starts by letting its gap open);
    ``e_pair``, ``mu_pair`` the isolated contacts' coefficients;
    ``accel`` (N, 3) each body's free acceleration (gravity, or zero); ``dynamic[i]`` whether
    body i moves. Flags the contacts exact; returns the number of impacts written to ``log``
    (rows of :data:`IMPACT_FIELDS`; the caller makes room for ``MAX_IMPACTS`` per contact).
    Free flight goes in substeps of at most ``dt / substeps``.
    """
    out = np.empty(OUT_SIZE)
    ids = np.empty(MAX_POINTS, np.int64)
    h = dt / substeps
    iw = np.zeros((x.shape[0], 9))
    logged = 0
    for k in range(n_isolated):
        m = isolated[k]
        a, b, pa, pb = take_isolated(ci, m, I_FLAGS)
        # a plane reaches everywhere (inf) and never turns: it counts for nothing here
        reach_a = piece_reach[pa] if math.isfinite(piece_reach[pa]) else 0.0
        reach_b = piece_reach[pb] if math.isfinite(piece_reach[pb]) else 0.0
        tol = 1e-9 * (reach_a + reach_b)
        now = 0.0
        for impact in range(MAX_IMPACTS):
            for body in (a, b):
                world_inverse_row(body, q, inv_inertia, iw)
            spin = _top_spin(a, w, inv_mass, iw, min_moment) * reach_a
            spin += _top_spin(b, w, inv_mass, iw, min_moment) * reach_b
            hit = _time_of_impact(
                pa, pb, a, b, dt - now, tol, impact > 0 or closing[m] > 0.0, spin, h, x, q, v,
                w, accel, inertia,
                inv_inertia, model_ints, piece_radius, local_vertices, local_normals,
                face_first, face_size, corners, edges, vertices, normals, out, ids,
            )  # fmt: skip
            if hit < 0.0:
                break
            for body in (a, b):
                if dynamic[body]:
                    fly(
                        body, hit, _pieces_of(hit, h), x, q, v, w,
                        accel[body, 0], accel[body, 1], accel[body, 2], inertia, inv_inertia,
                    )  # fmt: skip
            now += hit
            gap = _gap(
                pa, pb, a, b, 0.0, h, x, q, v, w, accel, inertia, inv_inertia, model_ints,
                piece_radius, local_vertices, local_normals, face_first, face_size, corners,
                edges, vertices, normals, out, ids,
            )  # fmt: skip
            (
                _, piece_kind, piece_vstart, piece_vcount, piece_fstart, piece_fcount,
                piece_cstart, piece_ccount, piece_estart, piece_ecount,
            ) = model_ints  # fmt: skip
            count = collide_pieces(
                pa, pb, piece_kind, piece_radius, piece_vstart, piece_vcount, piece_fstart,
                piece_fcount, piece_cstart, piece_ccount, piece_estart, piece_ecount,
                vertices, normals, face_first, face_size, corners, edges,
                max(2.0 * tol, gap[0]) + touch, 0.0, out, ids,
            )  # fmt: skip
            if count == 0:
                break
            for body in (a, b):
                world_inverse_row(body, q, inv_inertia, iw)
            if not _impact(a, b, count, out, touch, e_pair[k], mu_pair[k], x, v, w, inv_mass,
                           iw, log[logged]):  # fmt: skip
                break
            log[logged, 0] = now
            logged += 1
        for body in (a, b):
            if dynamic[body] and dt - now > 0.0:
                fly(
                    body, dt - now, _pieces_of(dt - now, h), x, q, v, w,
                    accel[body, 0], accel[body, 1], accel[body, 2], inertia, inv_inertia,
                )  # fmt: skip
    return logged


@njit(cache=True)
def _time_of_impact(
    pa: int, pb: int, a: int, b: int, horizon: float, tol: float, parting: bool,
    spin: float, h: float, x: np.ndarray, q: np.ndarray, v: np.ndarray, w: np.ndarray,
    accel: np.ndarray, inertia: np.ndarray, inv_inertia: np.ndarray, model_ints: tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    ],
    piece_radius: np.ndarray, local_vertices: np.ndarray, local_normals: np.ndarray,
    face_first: np.ndarray, face_size: np.ndarray, corners: np.ndarray, edges: np.ndarray,
    vertices: np.ndarray, normals: np.ndarray, out: np.ndarray, ids: np.ndarray,
) -> float:  # fmt: skip
    """First time in ``[0, horizon]`` [s] at which the pieces come within ``tol`` [m] of
    touching, by conservative advancement; -1 if they do not (or it fails to converge).
    ``spin`` bounds how fast turning can close the gap [m/s]; ``parting``: the pair has just
    been hit apart, so the search first lets the gap open beyond ``tol``."""
    gx = accel[a, 0] - accel[b, 0]
    gy = accel[a, 1] - accel[b, 1]
    gz = accel[a, 2] - accel[b, 2]
    g_rel = math.sqrt(gx * gx + gy * gy + gz * gz)
    state = search(parting)
    t = 0.0
    while True:
        d, wx, wy, wz = _gap(
            pa, pb, a, b, t, h, x, q, v, w, accel, inertia, inv_inertia, model_ints,
            piece_radius, local_vertices, local_normals, face_first, face_size, corners,
            edges, vertices, normals, out, ids,
        )  # fmt: skip
        # how fast the gap can close from now to the horizon
        ux = (v[a, 0] + accel[a, 0] * t) - (v[b, 0] + accel[b, 0] * t)
        uy = (v[a, 1] + accel[a, 1] * t) - (v[b, 1] + accel[b, 1] * t)
        uz = (v[a, 2] + accel[a, 2] * t) - (v[b, 2] + accel[b, 2] * t)
        closing = -(ux * wx + uy * wy + uz * wz) + spin + g_rel * (horizon - t)
        done, t, state = advance(state, t, d, closing, tol, horizon)
        if done:
            return t
