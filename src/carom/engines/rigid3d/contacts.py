"""Narrow phase in 3D: the contact manifold of every candidate pair, kept as rows of two arrays,
as the 2D engine's (:mod:`carom.engines.rigid.contacts`).

A contact joins piece ``a`` of body A and piece ``b`` of body B (``a < b``); its normal points
from B to A (A is pushed along ``+n``), with two unit tangents ``t1 = n x ...`` and
``t2 = n x t1`` completing a right-handed frame. Each of its one to four points keeps its
anchors ``r_A = p - x_A`` and ``r_B = p - x_B`` (fixed in the world frame over the step, where
impulses act), its separation at the start of the step, and the solver's impulses, which
warm-start the same point (same pieces, same feature id) at the next step; the tangent impulse
is kept as a world vector, so a turning normal carries it over.

The separation within the step is tracked at the *core anchors*: the point of each body's core
(a ball's centre, a capsule's segment, a polytope's surface) behind the contact point along the
normal, ``c_A = r_A + (s/2 + R_A) n`` and ``c_B = r_B - (s/2 + R_B) n`` for radii ``R``. A ball's
core does not move when it turns, so a rolling ball keeps its separation; the contact point
itself would rise by ``R (1 - cos phi)`` as it turned by ``phi`` and let the ball sink.

Which points are kept: those within the speculative distance, plus how far the pair can close
along the normal during the step.

**Manifolds are kept from step to step** (as Rapier and Bullet keep theirs): each pair's
manifold is stored with the pose of one body in the other's frame when it was made, its points
as material points of each body (in each body's frame) and its normal in the frame body's
frame. While the pair's relative pose stays within ``reuse`` [m] of that pose (the farthest any
point of the moving piece can have gone: the centre's shift plus its reach times the change
of the rotation matrix), the manifold is rebuilt from those points at the bodies' new poses,
with each point's separation measured anew along the normal, instead of running the
separating-axis test and the clipping again; a manifold made apart is made again once a point
touches. A pair found apart with a known lower bound of the gap (a separating axis) is not
tested again until it has moved enough to come within the margin. A resting stack is then
tested once, not every step; anything that moves more than ``reuse`` in a step is tested
every step as before.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.rigid3d.model import (
    M_COUNT,
    M_GAP,
    M_ID0,
    M_N,
    M_POINT,
    M_R,
    M_SEP,
    M_T,
    PIECE_PLANE,
    PIECE_POLYTOPE,
)
from carom.engines.rigid3d.motion import relative_velocity
from carom.engines.stepped import contacts as shared
from carom.engines.stepped.rows import I_COUNT, I_ID0, flags_column, point_layout
from carom.geometry.manifold3d import (
    MAX_POINTS,
    OUT_SIZE,
    contact_capsule_capsule,
    contact_capsule_sphere,
    contact_hull_capsule,
    contact_hull_hull,
    contact_hull_plane,
    contact_hull_sphere,
    contact_segments_plane,
    contact_sphere_sphere,
)
from carom.geometry.rotation import matrix
from carom.jit import leaf

__all__ = [
    "CONTACT_FLOATS",
    "CONTACT_INTS",
    "collide_pieces",
    "narrow_phase",
    "point_offset",
    "store_tangents",
    "tangents",
]

# float columns of a contact row
F_NX = 0  # normal, from B to A
F_NY = 1
F_NZ = 2
F_T1X = 3  # first tangent
F_T1Y = 4
F_T1Z = 5
F_T2X = 6  # second tangent, n x t1
F_T2Y = 7
F_T2Z = 8
F_MU = 9  # friction coefficient [-]
F_E = 10  # restitution [-]
F_ROLL = 11  # rolling resistance [m]
F_JR1 = 12  # rolling-resistance angular impulse about t1 and t2 [N m s]
F_JR2 = 13
POINT0 = 14  # first point's columns; a point has POINT_FLOATS of them
# a point's columns, from its offset: the shared ones (carom.engines.stepped.rows.point_layout;
# its base here is the separation less (c_A - c_B) . n, c the core anchors), then 3D's own
_POINT = point_layout(3)
P_RAX, P_RAY, P_RAZ = _POINT.ra, _POINT.ra + 1, _POINT.ra + 2
P_RBX, P_RBY, P_RBZ = _POINT.rb, _POINT.rb + 1, _POINT.rb + 2
P_BASE, P_NMASS, P_JN, P_JT1, P_JT2 = (
    _POINT.base, _POINT.nmass, _POINT.jn, _POINT.jt, _POINT.jt + 1
)  # fmt: skip
P_TOTAL, P_VREL, P_SEP = _POINT.total, _POINT.vrel, _POINT.sep
P_X, P_Y, P_Z = _POINT.at, _POINT.at + 1, _POINT.at + 2
P_T1MASS = _POINT.size  # effective masses along t1, t2 [kg]
P_T2MASS = _POINT.size + 1
P_KA = _POINT.size + 2  # A's core anchor is c_A = r_A + k_A n [m], B's c_B = r_B - k_B n
P_KB = _POINT.size + 3
P_LAX = _POINT.size + 4  # the point in A's body frame, relative to A's centre [m]
POINT_FLOATS = _POINT.size + 7
CONTACT_FLOATS = POINT0 + MAX_POINTS * POINT_FLOATS
#: a cached contact's points: per point the normal impulse, the tangent one as a world vector,
#: and where the point was in A's body frame (a point whose feature id changed is matched by it)
CACHE_IMPULSES = (MAX_POINTS, 7)

# int columns of a contact row
# the declared integer columns (carom.engines.stepped.rows): bodies, pieces, points (1 to
# 4), their feature ids, then the flags
I_FLAGS = flags_column(MAX_POINTS)
CONTACT_INTS = I_FLAGS + 1


@njit(cache=True, inline="always")
def point_offset(j: int) -> int:
    """Column of point ``j``'s first float."""
    return POINT0 + POINT_FLOATS * j


@njit(cache=True, inline="always")
def tangents(nx: float, ny: float, nz: float) -> tuple[float, float, float, float, float, float]:
    """Two unit tangents ``t1, t2`` with ``(n, t1, t2)`` right-handed: ``t1`` is ``n`` crossed
    with the axis it is least aligned with (a continuous choice away from the switch)."""
    if abs(nx) < 0.57735:  # |n_x| below 1/sqrt(3): the x axis is far enough from n
        # t1 = x_hat x n, normalised
        ax, ay, az = 0.0, -nz, ny
    else:
        # t1 = y_hat x n
        ax, ay, az = nz, 0.0, -nx
    norm = math.sqrt(ax * ax + ay * ay + az * az)
    ax /= norm
    ay /= norm
    az /= norm
    bx = ny * az - nz * ay
    by = nz * ax - nx * az
    bz = nx * ay - ny * ax
    return ax, ay, az, bx, by, bz


@njit(cache=True)
def collide_pieces(
    pa: int,
    pb: int,
    piece_kind: np.ndarray,
    piece_radius: np.ndarray,
    piece_vstart: np.ndarray,
    piece_vcount: np.ndarray,
    piece_fstart: np.ndarray,
    piece_fcount: np.ndarray,
    piece_cstart: np.ndarray,
    piece_ccount: np.ndarray,
    piece_estart: np.ndarray,
    piece_ecount: np.ndarray,
    vertices: np.ndarray,
    normals: np.ndarray,
    face_first: np.ndarray,
    face_size: np.ndarray,
    corners: np.ndarray,
    edges: np.ndarray,
    margin: float,
    slop: float,
    out: np.ndarray,
    ids: np.ndarray,
) -> int:
    """The manifold of placed pieces ``pa`` and ``pb`` (:mod:`carom.geometry.manifold3d`), with
    its normal from A to B whichever order the kernel takes them in; return the points' count.

    Kernels take the richer shape first (polytope, then capsule, then ball; a plane last);
    when ``pb`` is the richer one the pieces go in swapped and the normal is turned back.
    """
    ka = piece_kind[pa]
    kb = piece_kind[pb]
    # rank: plane 0, ball 1, capsule 2, polytope 3; the higher one goes first (planes last)
    rank_a = 0 if ka == PIECE_PLANE else (3 if ka == PIECE_POLYTOPE else piece_vcount[pa])
    rank_b = 0 if kb == PIECE_PLANE else (3 if kb == PIECE_POLYTOPE else piece_vcount[pb])
    swap = rank_b > rank_a
    p, o = (pb, pa) if swap else (pa, pb)
    rp = rank_b if swap else rank_a
    ro = rank_a if swap else rank_b
    vp = vertices[piece_vstart[p] : piece_vstart[p] + piece_vcount[p]]
    vo = vertices[piece_vstart[o] : piece_vstart[o] + piece_vcount[o]]
    count = 0
    if ro == 0:  # against a plane
        n = normals[piece_fstart[o]]
        offset = n[0] * vo[0, 0] + n[1] * vo[0, 1] + n[2] * vo[0, 2]
        if rp == 3:
            count = contact_hull_plane(vp, n, offset, margin, out, ids)
        elif rp > 0:
            count = contact_segments_plane(vp, piece_radius[p], n, offset, margin, out, ids)
    elif rp == 3:
        fs, fc = piece_fstart[p], piece_fcount[p]
        cs, cc = piece_cstart[p], piece_ccount[p]
        es, ec = piece_estart[p], piece_ecount[p]
        np_ = normals[fs : fs + fc]
        sp = face_first[fs : fs + fc]
        zp = face_size[fs : fs + fc]
        cp = corners[cs : cs + cc]
        ep = edges[es : es + ec]
        if ro == 3:
            fs, fc = piece_fstart[o], piece_fcount[o]
            cs, cc = piece_cstart[o], piece_ccount[o]
            es, ec = piece_estart[o], piece_ecount[o]
            count = contact_hull_hull(
                vp, np_, sp, zp, cp, ep,
                vo, normals[fs : fs + fc], face_first[fs : fs + fc], face_size[fs : fs + fc],
                corners[cs : cs + cc], edges[es : es + ec],
                margin, slop, out, ids,
            )  # fmt: skip
        elif ro == 2:
            count = contact_hull_capsule(
                vp, np_, sp, zp, cp, ep, vo[0], vo[1], piece_radius[o], margin, slop, out, ids
            )
        else:
            count = contact_hull_sphere(
                vp, np_, sp, zp, cp, ep, vo[0], piece_radius[o], margin, out, ids
            )
    elif rp == 2:
        if ro == 2:
            count = contact_capsule_capsule(
                vp[0], vp[1], piece_radius[p], vo[0], vo[1], piece_radius[o], margin, out, ids
            )
        else:
            count = contact_capsule_sphere(
                vp[0], vp[1], piece_radius[p], vo[0], piece_radius[o], margin, out, ids
            )
    else:
        count = contact_sphere_sphere(
            vp[0], piece_radius[p], vo[0], piece_radius[o], margin, out, ids
        )
    if swap and count > 0:
        out[0] = -out[0]
        out[1] = -out[1]
        out[2] = -out[2]
    return count


@njit(cache=True, inline="always")
def _relative_pose(f: int, o: int, x: np.ndarray, rot: np.ndarray, pose: np.ndarray) -> None:
    """Body ``o``'s centre and rotation in body ``f``'s frame into ``pose`` (12,):
    ``R_f^T (x_o - x_f)`` and ``R_f^T R_o`` row-major (``rot`` (N, 9): each body's rotation)."""
    dx = x[o, 0] - x[f, 0]
    dy = x[o, 1] - x[f, 1]
    dz = x[o, 2] - x[f, 2]
    for i in range(3):
        pose[M_T + i] = rot[f, i] * dx + rot[f, 3 + i] * dy + rot[f, 6 + i] * dz
        for j in range(3):
            pose[M_R + 3 * i + j] = (
                rot[f, i] * rot[o, j] + rot[f, 3 + i] * rot[o, 3 + j]
                + rot[f, 6 + i] * rot[o, 6 + j]
            )  # fmt: skip


@njit(cache=True, inline="always")
def _moved(pose: np.ndarray, kept: np.ndarray, reach: float) -> float:
    """How far [m] any point within ``reach`` of the other body's centre can have gone, in the
    frame body's frame, between the pose ``kept`` was made at and ``pose``: the centre's shift
    plus ``reach`` times the change of the rotation matrix (its Frobenius norm bounds its
    2-norm)."""
    shift = 0.0
    for i in range(3):
        shift += (pose[M_T + i] - kept[M_T + i]) ** 2
    turn = 0.0
    for i in range(9):
        turn += (pose[M_R + i] - kept[M_R + i]) ** 2
    return math.sqrt(shift) + reach * math.sqrt(turn)


@njit(cache=True)
def _keep(
    row: np.ndarray, ints: np.ndarray, pose: np.ndarray, count: int, out: np.ndarray,
    ids: np.ndarray, a: int, b: int, f: int, x: np.ndarray, rot: np.ndarray,
) -> None:  # fmt: skip
    """A manifold just made (``count`` points in ``out``, ``ids``, normal from A to B) into a
    kept row (``row`` MANIFOLD_FLOATS, ``ints`` MANIFOLD_INTS) at ``pose``: each point's
    places on the two surfaces, ``p -/+ (s/2) n``, in A's and B's frames; the normal in
    frame body ``f``'s. With no points, ``out[6]`` is the lower bound of the gap."""
    for i in range(12):
        row[i] = pose[i]
    ints[M_COUNT] = count
    if count == 0:
        row[M_GAP] = out[6]
        return
    nx, ny, nz = out[0], out[1], out[2]
    for i in range(3):
        row[M_N + i] = rot[f, i] * nx + rot[f, 3 + i] * ny + rot[f, 6 + i] * nz
    for j in range(count):
        half = 0.5 * out[6 + 4 * j]
        row[M_SEP + j] = out[6 + 4 * j]
        ints[M_ID0 + j] = ids[j]
        ax = out[3 + 4 * j] - half * nx - x[a, 0]
        ay = out[4 + 4 * j] - half * ny - x[a, 1]
        az = out[5 + 4 * j] - half * nz - x[a, 2]
        bx = out[3 + 4 * j] + half * nx - x[b, 0]
        by = out[4 + 4 * j] + half * ny - x[b, 1]
        bz = out[5 + 4 * j] + half * nz - x[b, 2]
        o = M_POINT + 6 * j
        for i in range(3):
            row[o + i] = rot[a, i] * ax + rot[a, 3 + i] * ay + rot[a, 6 + i] * az
            row[o + 3 + i] = rot[b, i] * bx + rot[b, 3 + i] * by + rot[b, 6 + i] * bz


@njit(cache=True)
def _rebuild(
    row: np.ndarray, ints: np.ndarray, a: int, b: int, f: int, x: np.ndarray, rot: np.ndarray,
    out: np.ndarray, ids: np.ndarray,
) -> bool:  # fmt: skip
    """The kept manifold ``row`` at the bodies' poses now into ``out`` and ``ids``: its
    normal turned with frame body ``f``, each point midway between its two material points,
    its separation their gap along the normal. False (nothing to keep) if it was made apart
    and a point now touches: the features that touch are then found again."""
    count = ints[M_COUNT]
    nx = rot[f, 0] * row[M_N] + rot[f, 1] * row[M_N + 1] + rot[f, 2] * row[M_N + 2]
    ny = rot[f, 3] * row[M_N] + rot[f, 4] * row[M_N + 1] + rot[f, 5] * row[M_N + 2]
    nz = rot[f, 6] * row[M_N] + rot[f, 7] * row[M_N + 1] + rot[f, 8] * row[M_N + 2]
    apart = True
    touches = False
    for j in range(count):
        o = M_POINT + 6 * j
        la0, la1, la2 = row[o], row[o + 1], row[o + 2]
        lb0, lb1, lb2 = row[o + 3], row[o + 4], row[o + 5]
        ax = x[a, 0] + rot[a, 0] * la0 + rot[a, 1] * la1 + rot[a, 2] * la2
        ay = x[a, 1] + rot[a, 3] * la0 + rot[a, 4] * la1 + rot[a, 5] * la2
        az = x[a, 2] + rot[a, 6] * la0 + rot[a, 7] * la1 + rot[a, 8] * la2
        bx = x[b, 0] + rot[b, 0] * lb0 + rot[b, 1] * lb1 + rot[b, 2] * lb2
        by = x[b, 1] + rot[b, 3] * lb0 + rot[b, 4] * lb1 + rot[b, 5] * lb2
        bz = x[b, 2] + rot[b, 6] * lb0 + rot[b, 7] * lb1 + rot[b, 8] * lb2
        sep = (bx - ax) * nx + (by - ay) * ny + (bz - az) * nz
        apart = apart and row[M_SEP + j] > 0.0
        touches = touches or sep <= 0.0
        out[3 + 4 * j] = 0.5 * (ax + bx)
        out[4 + 4 * j] = 0.5 * (ay + by)
        out[5 + 4 * j] = 0.5 * (az + bz)
        out[6 + 4 * j] = sep
        ids[j] = ints[M_ID0 + j]
    out[0], out[1], out[2] = nx, ny, nz
    return not (apart and touches)


@njit(cache=True)
def narrow_phase(
    pairs: np.ndarray,
    n_pairs: int,
    model_ints: tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    ],
    piece_radius: np.ndarray,
    piece_reach: np.ndarray,
    vertices: np.ndarray,
    normals: np.ndarray,
    face_first: np.ndarray,
    face_size: np.ndarray,
    corners: np.ndarray,
    edges: np.ndarray,
    material: np.ndarray,
    e_table: np.ndarray,
    mu_table: np.ndarray,
    rolling_table: np.ndarray,
    x: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    gravity_on: np.ndarray,
    g: float,
    pull: np.ndarray,
    dt: float,
    speculative: float,
    slop: float,
    reuse: float,
    cache_keys: np.ndarray,
    cache_ids: np.ndarray,
    cache_impulses: np.ndarray,
    n_cache: int,
    previous: tuple[np.ndarray, np.ndarray, np.ndarray, int],
    made: tuple[np.ndarray, np.ndarray, np.ndarray],
    cf: np.ndarray,
    ci: np.ndarray,
) -> int:  # fmt: skip
    """Manifolds of the candidate ``pairs`` into contact rows ``cf`` (floats) and ``ci`` (ints).

    ``model_ints`` holds the pieces' ``piece_body, piece_kind, piece_vstart, piece_vcount,
    piece_fstart, piece_fcount, piece_cstart, piece_ccount, piece_estart, piece_ecount``
    (:class:`.model.Model3D`). Returns the number of contacts, or
    minus the number of pairs when the rows may not suffice (the caller grows them and calls
    again). Impulses found in the cache warm-start the points with the same feature ids.

    ``previous`` holds the manifolds of the last step (keys (K,) sorted, ints (K, MANIFOLD_INTS),
    floats (K, MANIFOLD_FLOATS), rows used), reused while a pair has moved less than ``reuse``
    [m] (module docstring; 0: never); ``made`` receives this step's, one row per pair, for the
    caller to keep once the step is taken.
    """
    (
        piece_body, piece_kind, piece_vstart, piece_vcount, piece_fstart, piece_fcount,
        piece_cstart, piece_ccount, piece_estart, piece_ecount,
    ) = model_ints  # fmt: skip
    kept_keys, kept_ints, kept_floats, n_kept = previous
    made_keys, made_ints, made_floats = made
    if ci.shape[0] < n_pairs or made_keys.shape[0] < n_pairs:
        return -n_pairs
    n_pieces = piece_body.shape[0]
    out = np.empty(OUT_SIZE)
    ids = np.empty(MAX_POINTS, np.int64)
    ra = np.empty(3)
    rb = np.empty(3)
    pose = np.empty(12)
    rot = np.empty((x.shape[0], 9))
    for i in range(x.shape[0]):
        matrix(q, i, rot[i])
    m = 0
    cursor = 0
    kept_cursor = 0
    for k in range(n_pairs):
        pair = shared.pair_of(pairs, k, piece_body)
        pa, pb, ba, bb = pair
        # how far the pair can close during the step: relative speed, spins, gravity
        closing = shared.relative_speed(v, ba, bb)
        if piece_kind[pa] != PIECE_PLANE:
            closing += math.sqrt(w[ba, 0] ** 2 + w[ba, 1] ** 2 + w[ba, 2] ** 2) * piece_reach[pa]
        if piece_kind[pb] != PIECE_PLANE:
            closing += math.sqrt(w[bb, 0] ** 2 + w[bb, 1] ** 2 + w[bb, 2] ** 2) * piece_reach[pb]
        if gravity_on[ba] != gravity_on[bb]:
            closing += g * dt
        closing += (pull[ba] + pull[bb]) * dt
        margin = speculative + closing * dt
        # the kept manifold, if the pair has not moved too far since it was made
        key = pa * n_pieces + pb
        if piece_reach[pa] >= piece_reach[pb]:
            frame, other, reach = ba, bb, piece_reach[pb]
        else:
            frame, other, reach = bb, ba, piece_reach[pa]
        _relative_pose(frame, other, x, rot, pose)
        row, kept_cursor = shared.find_cached(kept_keys, n_kept, key, kept_cursor)
        count = -1
        if row >= 0:
            moved = _moved(pose, kept_floats[row], reach)
            if kept_ints[row, M_COUNT] == 0:
                if kept_floats[row, M_GAP] - moved > margin:
                    count = 0
            elif moved < reuse and _rebuild(
                kept_floats[row], kept_ints[row], ba, bb, frame, x, rot, out, ids
            ):
                count = kept_ints[row, M_COUNT]
        made_keys[k] = key
        if count >= 0:
            made_floats[k] = kept_floats[row]
            made_ints[k] = kept_ints[row]
        else:
            out[6] = -np.inf  # no bound on the gap unless the kernel finds one
            count = collide_pieces(
                pa, pb, piece_kind, piece_radius, piece_vstart, piece_vcount, piece_fstart,
                piece_fcount, piece_cstart, piece_ccount, piece_estart, piece_ecount, vertices,
                normals, face_first, face_size, corners, edges, margin, slop, out, ids,
            )  # fmt: skip
            _keep(made_floats[k], made_ints[k], pose, count, out, ids, ba, bb, frame, x, rot)
        if count == 0:
            continue
        # the kernels' normal runs from A to B; a contact's from B to A
        nx = -out[0]
        ny = -out[1]
        nz = -out[2]
        kept = 0
        for j in range(count):
            px = out[3 + 4 * j]
            py = out[4 + 4 * j]
            pz = out[5 + 4 * j]
            sep = out[6 + 4 * j]
            ra[0] = px - x[ba, 0]
            ra[1] = py - x[ba, 1]
            ra[2] = pz - x[ba, 2]
            rb[0] = px - x[bb, 0]
            rb[1] = py - x[bb, 1]
            rb[2] = pz - x[bb, 2]
            ux, uy, uz = relative_velocity(ba, bb, ra, rb, v, w)
            un = ux * nx + uy * ny + uz * nz
            if not shared.keeps_point(
                un, sep, gravity_on[ba] != gravity_on[bb], g, dt, speculative,
                pull[ba] + pull[bb],
            ):  # fmt: skip
                continue
            o = point_offset(kept)
            cf[m, o + P_RAX] = ra[0]
            cf[m, o + P_RAY] = ra[1]
            cf[m, o + P_RAZ] = ra[2]
            cf[m, o + P_RBX] = rb[0]
            cf[m, o + P_RBY] = rb[1]
            cf[m, o + P_RBZ] = rb[2]
            # core anchors: behind the point along n by half the gap and the radius
            ka = 0.5 * sep + piece_radius[pa]
            kb = 0.5 * sep + piece_radius[pb]
            cf[m, o + P_KA] = ka
            cf[m, o + P_KB] = kb
            cf[m, o + P_BASE] = sep - (
                (ra[0] - rb[0]) * nx + (ra[1] - rb[1]) * ny + (ra[2] - rb[2]) * nz + ka + kb
            )
            cf[m, o + P_X] = px
            cf[m, o + P_Y] = py
            cf[m, o + P_Z] = pz
            for c in range(3):  # R_A^T r_A
                cf[m, o + P_LAX + c] = (
                    rot[ba, c] * ra[0] + rot[ba, 3 + c] * ra[1] + rot[ba, 6 + c] * ra[2]
                )
            shared.open_point(
                cf, ci, m, kept, o, un, sep, ids[j], (P_VREL, P_SEP),
                (P_NMASS, P_JN, P_JT1, P_JT2, P_TOTAL),
            )  # fmt: skip
            kept += 1
        if kept == 0:
            continue
        t1x, t1y, t1z, t2x, t2y, t2z = tangents(nx, ny, nz)
        cf[m, F_NX] = nx
        cf[m, F_NY] = ny
        cf[m, F_NZ] = nz
        cf[m, F_T1X] = t1x
        cf[m, F_T1Y] = t1y
        cf[m, F_T1Z] = t1z
        cf[m, F_T2X] = t2x
        cf[m, F_T2Y] = t2y
        cf[m, F_T2Z] = t2z
        ma, mb = shared.write_pair(
            cf, ci, m, pair, kept, I_FLAGS, material, (mu_table, e_table), (F_MU, F_E)
        )
        cf[m, F_ROLL] = rolling_table[ma, mb]
        cf[m, F_JR1] = 0.0
        cf[m, F_JR2] = 0.0
        row, cursor = shared.find_cached(cache_keys, n_cache, pa * n_pieces + pb, cursor)
        if row >= 0:
            _warm_start(cf, ci, m, kept, cache_ids[row], cache_impulses[row], 2.0 * slop)
        m += 1
    return m


@njit(cache=True, inline="always")
def _warm_start(
    cf: np.ndarray, ci: np.ndarray, m: int, count: int, ids: np.ndarray, cached: np.ndarray,
    near: float,
) -> None:  # fmt: skip
    """Contact m's ``count`` points warm-started from its cached points (``ids`` (4,),
    ``cached`` (4, 7), :data:`CACHE_IMPULSES`): each point takes the impulses of the cached
    point with its feature id; a point that finds none takes those of the nearest cached point
    left, in A's body frame, if within ``near`` [m]. Clipping two faces that line up (a box
    on a box) names the same corner by another pair of features from one step to the next;
    without this, a stack's warm start was lost at almost every step and it rocked."""
    taken = 0  # the cached points used, one bit each
    found = 0  # the points matched
    for j in range(count):
        for c in range(MAX_POINTS):
            if ids[c] >= 0 and ids[c] == ci[m, I_ID0 + j] and not (taken >> c) & 1:
                _take(cf, m, j, cached[c])
                taken |= 1 << c
                found |= 1 << j
                break
    for j in range(count):
        if (found >> j) & 1:
            continue
        o = point_offset(j)
        best = -1
        best_d2 = near * near
        for c in range(MAX_POINTS):
            if ids[c] < 0 or (taken >> c) & 1:
                continue
            d2 = 0.0
            for k in range(3):
                d2 += (cf[m, o + P_LAX + k] - cached[c, 4 + k]) ** 2
            if d2 <= best_d2:
                best_d2 = d2
                best = c
        if best >= 0:
            _take(cf, m, j, cached[best])
            taken |= 1 << best


@njit(cache=True, inline="always")
def _take(cf: np.ndarray, m: int, j: int, cached: np.ndarray) -> None:
    """Point j of contact m takes a cached point's normal impulse and its tangent one (a world
    vector) on the contact's tangents."""
    o = point_offset(j)
    cf[m, o + P_JN] = cached[0]
    for t, f in ((P_JT1, F_T1X), (P_JT2, F_T2X)):
        cf[m, o + t] = cached[1] * cf[m, f] + cached[2] * cf[m, f + 1] + cached[3] * cf[m, f + 2]


@leaf
def store_tangents(cf: np.ndarray, ci: np.ndarray, n_contacts: int, cache: np.ndarray) -> None:
    """Each point's tangent impulse as a world vector into the warm-start cache (K, 4, 7),
    beside the normal one (:func:`carom.engines.stepped.contacts.store_points`): a turning
    normal carries it over; and where the point is in A's body frame."""
    for m in range(n_contacts):
        for q in range(ci[m, I_COUNT]):
            o = point_offset(q)
            j1 = cf[m, o + P_JT1]
            j2 = cf[m, o + P_JT2]
            for k in range(3):
                cache[m, q, 1 + k] = j1 * cf[m, F_T1X + k] + j2 * cf[m, F_T2X + k]
                cache[m, q, 4 + k] = cf[m, o + P_LAX + k]
