"""Narrow phase: the contact manifold of every candidate pair, kept as rows of two arrays.

A contact joins piece ``a`` of body A and piece ``b`` of body B (``a < b``); its normal points
from B to A (A is pushed along ``+n``). Each of its one or two points keeps its anchors
``r_A = p - x_A`` and ``r_B = p - x_B`` (fixed in the world frame over the step, as Box2D v3
does), its separation at the start of the step, and the solver's impulses, which warm-start
the same point (same pieces, same feature id) at the next step.

Which points are kept: those within the speculative distance, plus how far the pair can close
along the normal during the step (``dt`` times the approach speed at the point), so a fast
body meets what is in front of it and not what it merely passes by.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from carom.engines.rigid.motion import relative_velocity
from carom.engines.stepped.contacts import (
    find_cached,
    keeps_point,
    open_point,
    pair_of,
    relative_speed,
    write_pair,
)
from carom.engines.stepped.rows import I_COUNT, I_ID0, flags_column, point_layout
from carom.geometry.manifold2d import collide
from carom.jit import leaf

__all__ = [
    "CONTACT_FLOATS",
    "CONTACT_INTS",
    "MAX_POINTS",
    "narrow_phase",
    "point_offset",
    "store_tangents",
]

# float columns of a contact row
F_NX = 0
F_NY = 1
F_MU = 2  # friction coefficient [-]
F_E = 3  # restitution [-]
POINT0 = 4  # first point's columns; a point has POINT_FLOATS of them
# a point's columns, from its offset (carom.engines.stepped.rows.point_layout)
_POINT = point_layout(2)
P_RAX, P_RAY, P_RBX, P_RBY = _POINT.ra, _POINT.ra + 1, _POINT.rb, _POINT.rb + 1  # anchors [m]
P_BASE, P_NMASS, P_JN, P_JT = _POINT.base, _POINT.nmass, _POINT.jn, _POINT.jt
P_TOTAL, P_VREL, P_SEP, P_X, P_Y = _POINT.total, _POINT.vrel, _POINT.sep, _POINT.at, _POINT.at + 1
POINT_FLOATS = _POINT.size
#: points in a manifold, at the most
MAX_POINTS = 2
#: a cached contact's impulses: the normal and tangent one of each of its points
CACHE_IMPULSES = (2 * MAX_POINTS,)
CONTACT_FLOATS = POINT0 + MAX_POINTS * POINT_FLOATS

# int columns of a contact row
# the declared integer columns (carom.engines.stepped.rows): bodies, pieces, points (1 or 2),
# their feature ids, then the flags
I_ID1 = I_ID0 + 1
I_FLAGS = flags_column(MAX_POINTS)
CONTACT_INTS = I_FLAGS + 1


@njit(cache=True, inline="always")
def point_offset(j: int) -> int:
    """Column of point ``j``'s first float."""
    return POINT0 + POINT_FLOATS * j


@leaf
def narrow_phase(
    pairs: np.ndarray,
    n_pairs: int,
    vertices: np.ndarray,
    normals: np.ndarray,
    piece_start: np.ndarray,
    piece_count: np.ndarray,
    piece_radius: np.ndarray,
    piece_reach: np.ndarray,
    piece_body: np.ndarray,
    material: np.ndarray,
    e_table: np.ndarray,
    mu_table: np.ndarray,
    x: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    gravity_on: np.ndarray,
    g: float,
    pull: np.ndarray,
    dt: float,
    speculative: float,
    slop: float,
    cache_keys: np.ndarray,
    cache_ids: np.ndarray,
    cache_impulses: np.ndarray,
    n_cache: int,
    cf: np.ndarray,
    ci: np.ndarray,
    scratch: tuple[np.ndarray, np.ndarray],
) -> int:
    """Manifolds of the candidate ``pairs`` into contact rows ``cf`` (floats), ``ci`` (ints).

    Returns the number of contacts, or minus the number of pairs when the rows may not
    suffice (the caller grows them to at least that and calls again). Impulses found in the
    cache (``cache_keys`` sorted, ``cache_ids`` (K, 2), ``cache_impulses`` (K, 4): normal and
    tangent of each point, or (K, 2, 2)) warm-start the matching points. ``scratch``: room
    for one manifold, (8,) float64 and (2,) int64 (a leaf kernel: it allocates nothing).
    """
    if ci.shape[0] < n_pairs:
        return -n_pairs
    n_pieces = piece_start.shape[0]
    out, ids = scratch
    m = 0
    cursor = 0  # where the next warm-start cache search starts
    for k in range(n_pairs):
        pair = pair_of(pairs, k, piece_body)
        pa, pb, ba, bb = pair
        # how far the pair can close during the step: relative speed, spins, gravity
        closing = relative_speed(v, ba, bb)
        closing += abs(omega[ba]) * piece_reach[pa] + abs(omega[bb]) * piece_reach[pb]
        if gravity_on[ba] != gravity_on[bb]:
            closing += g * dt
        closing += (pull[ba] + pull[bb]) * dt
        reach = speculative + closing * dt
        count = collide(
            vertices,
            normals,
            piece_start[pa],
            piece_count[pa],
            piece_radius[pa],
            piece_start[pb],
            piece_count[pb],
            piece_radius[pb],
            reach,
            slop,
            out,
            ids,
        )
        if count == 0:
            continue
        nx = out[0]
        ny = out[1]
        kept = 0
        for j in range(count):
            px = out[2 + 3 * j]
            py = out[3 + 3 * j]
            sep = out[4 + 3 * j]
            rax = px - x[ba, 0]
            ray = py - x[ba, 1]
            rbx = px - x[bb, 0]
            rby = py - x[bb, 1]
            # relative velocity of the contact points, A's less B's
            ux, uy = relative_velocity(ba, bb, rax, ray, rbx, rby, v, omega)
            un = ux * nx + uy * ny
            falls = gravity_on[ba] != gravity_on[bb]
            if not keeps_point(un, sep, falls, g, dt, speculative, pull[ba] + pull[bb]):
                continue
            o = point_offset(kept)
            cf[m, o + P_RAX] = rax
            cf[m, o + P_RAY] = ray
            cf[m, o + P_RBX] = rbx
            cf[m, o + P_RBY] = rby
            cf[m, o + P_BASE] = sep - ((rax - rbx) * nx + (ray - rby) * ny)
            cf[m, o + P_X] = px
            cf[m, o + P_Y] = py
            open_point(cf, ci, m, kept, o, un, sep, ids[j], (P_VREL, P_SEP), (P_JN, P_JT, P_TOTAL))
            kept += 1
        if kept == 0:
            continue
        cf[m, F_NX] = nx
        cf[m, F_NY] = ny
        write_pair(cf, ci, m, pair, kept, I_FLAGS, material, (mu_table, e_table), (F_MU, F_E))
        row, cursor = find_cached(cache_keys, n_cache, pa * n_pieces + pb, cursor)
        if row >= 0:
            for j in range(kept):
                for q in range(2):
                    if cache_ids[row, q] == ci[m, I_ID0 + j]:
                        o = point_offset(j)
                        cf[m, o + P_JN] = cache_impulses[row, 2 * q]
                        cf[m, o + P_JT] = cache_impulses[row, 2 * q + 1]
        m += 1
    return m


@leaf
def store_tangents(cf: np.ndarray, ci: np.ndarray, n_contacts: int, cache: np.ndarray) -> None:
    """Each point's tangent impulse into the warm-start cache (K, 2, 2) beside the normal one
    (:func:`carom.engines.stepped.contacts.store_points`)."""
    for m in range(n_contacts):
        for q in range(ci[m, I_COUNT]):
            cache[m, q, 1] = cf[m, point_offset(q) + P_JT]
