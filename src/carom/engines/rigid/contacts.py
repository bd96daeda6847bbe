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

import math

import numpy as np
from numba import njit

from carom.engines.rigid.motion import relative_velocity
from carom.engines.stepped.contacts import find_cached
from carom.engines.stepped.rows import (
    I_BODY_A,
    I_BODY_B,
    I_COUNT,
    I_ID0,
    I_PIECE_A,
    I_PIECE_B,
    flags_column,
)
from carom.geometry.manifold2d import collide

__all__ = [
    "CONTACT_FLOATS",
    "CONTACT_INTS",
    "extremes",
    "narrow_phase",
    "point_offset",
]

# float columns of a contact row
F_NX = 0
F_NY = 1
F_MU = 2  # friction coefficient [-]
F_E = 3  # restitution [-]
POINT0 = 4  # first point's columns; a point has POINT_FLOATS of them
POINT_FLOATS = 13
# a point's columns, from its offset
P_RAX = 0  # anchor on A [m]
P_RAY = 1
P_RBX = 2  # anchor on B [m]
P_RBY = 3
P_BASE = 4  # separation less (r_A - r_B) . n at the step's start [m]
P_NMASS = 5  # effective mass along n [kg] (the solver's, for the restitution pass)
P_JN = 6  # accumulated normal impulse [N s]
P_JT = 7  # accumulated tangent impulse [N s]
P_TOTAL = 8  # normal impulse applied over the step [N s]
P_VREL = 9  # normal relative speed at the step's start [m/s] (negative: approaching)
P_SEP = 10  # separation at the step's start [m]
P_X = 11  # the point [m]
P_Y = 12
CONTACT_FLOATS = POINT0 + 2 * POINT_FLOATS

# int columns of a contact row
# the declared integer columns (carom.engines.stepped.rows): bodies, pieces, points (1 or 2),
# their feature ids, then the flags
I_ID1 = I_ID0 + 1
I_FLAGS = flags_column(2)
CONTACT_INTS = I_FLAGS + 1


@njit(cache=True, inline="always")
def point_offset(j: int) -> int:
    """Column of point ``j``'s first float."""
    return POINT0 + POINT_FLOATS * j


@njit(cache=True)
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
    dt: float,
    speculative: float,
    slop: float,
    cache_keys: np.ndarray,
    cache_ids: np.ndarray,
    cache_impulses: np.ndarray,
    n_cache: int,
    cf: np.ndarray,
    ci: np.ndarray,
) -> int:
    """Manifolds of the candidate ``pairs`` into contact rows ``cf`` (floats), ``ci`` (ints).

    Returns the number of contacts, or minus the number of pairs when the rows may not
    suffice (the caller grows them to at least that and calls again). Impulses found in the
    cache (``cache_keys`` sorted, ``cache_ids`` (K, 2), ``cache_impulses`` (K, 4): normal and
    tangent of each point) warm-start the matching points.
    """
    if ci.shape[0] < n_pairs:
        return -n_pairs
    n_pieces = piece_start.shape[0]
    out = np.empty(8)
    ids = np.empty(2, np.int64)
    m = 0
    cursor = 0  # where the next warm-start cache search starts
    for k in range(n_pairs):
        pa = pairs[k, 0]
        pb = pairs[k, 1]
        ba = piece_body[pa]
        bb = piece_body[pb]
        # how far the pair can close during the step: relative speed, spins, gravity
        dvx = v[ba, 0] - v[bb, 0]
        dvy = v[ba, 1] - v[bb, 1]
        closing = math.sqrt(dvx * dvx + dvy * dvy)
        closing += abs(omega[ba]) * piece_reach[pa] + abs(omega[bb]) * piece_reach[pb]
        if gravity_on[ba] != gravity_on[bb]:
            closing += g * dt
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
            approach = max(0.0, -un)
            if gravity_on[ba] != gravity_on[bb]:
                approach += g * dt
            if sep > speculative + approach * dt:
                continue
            o = point_offset(kept)
            cf[m, o + P_RAX] = rax
            cf[m, o + P_RAY] = ray
            cf[m, o + P_RBX] = rbx
            cf[m, o + P_RBY] = rby
            cf[m, o + P_BASE] = sep - ((rax - rbx) * nx + (ray - rby) * ny)
            cf[m, o + P_JN] = 0.0
            cf[m, o + P_JT] = 0.0
            cf[m, o + P_TOTAL] = 0.0
            cf[m, o + P_VREL] = un
            cf[m, o + P_SEP] = sep
            cf[m, o + P_X] = px
            cf[m, o + P_Y] = py
            ci[m, I_ID0 + kept] = ids[j]
            kept += 1
        if kept == 0:
            continue
        cf[m, F_NX] = nx
        cf[m, F_NY] = ny
        ma = material[ba]
        mb = material[bb]
        cf[m, F_MU] = mu_table[ma, mb]
        cf[m, F_E] = e_table[ma, mb]
        ci[m, I_BODY_A] = ba
        ci[m, I_BODY_B] = bb
        ci[m, I_PIECE_A] = pa
        ci[m, I_PIECE_B] = pb
        ci[m, I_COUNT] = kept
        ci[m, I_FLAGS] = 0
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


@njit(cache=True)
def extremes(cf: np.ndarray, ci: np.ndarray, nc: int) -> tuple[np.ndarray, np.ndarray]:
    """Each contact's least separation [m] and least normal relative speed [m/s] over its
    points, (nc,) each (:func:`carom.engines.stepped.islands.plan`)."""
    closest = np.full(nc, np.inf)
    closing = np.full(nc, np.inf)
    for m in range(nc):
        for j in range(ci[m, I_COUNT]):
            closest[m] = min(closest[m], cf[m, point_offset(j) + P_SEP])
            closing[m] = min(closing[m], cf[m, point_offset(j) + P_VREL])
    return closest, closing


@njit(cache=True)
def store_impulses(
    cf: np.ndarray,
    ci: np.ndarray,
    n_contacts: int,
    n_pieces: int,
    cache_keys: np.ndarray,
    cache_ids: np.ndarray,
    cache_impulses: np.ndarray,
) -> int:
    """Keep each contact's impulses for the next step's warm start; return the count.

    Contacts come in key order (their pairs were sorted), so the cache stays sorted.
    """
    for m in range(n_contacts):
        cache_keys[m] = ci[m, I_PIECE_A] * n_pieces + ci[m, I_PIECE_B]
        for q in range(2):
            if q < ci[m, I_COUNT]:
                o = point_offset(q)
                cache_ids[m, q] = ci[m, I_ID0 + q]
                cache_impulses[m, 2 * q] = cf[m, o + P_JN]
                cache_impulses[m, 2 * q + 1] = cf[m, o + P_JT]
            else:
                cache_ids[m, q] = -1
                cache_impulses[m, 2 * q] = 0.0
                cache_impulses[m, 2 * q + 1] = 0.0
    return n_contacts
