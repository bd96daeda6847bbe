"""What both dimensions' contact stages share: which manifold points are kept, the integer
half of a contact row, each contact's extremes for the islands, and the warm-start cache
(Box2D's and Rapier's warm start), read and written alike in 2D and 3D.

A dimension's float row layout is told to these kernels as a ``layout`` tuple of its columns:
the first point's first column, the columns per point and, from a point's offset, the columns
of the values a kernel reads.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.stepped.rows import (
    I_BODY_A,
    I_BODY_B,
    I_COUNT,
    I_ID0,
    I_PIECE_A,
    I_PIECE_B,
)
from carom.jit import leaf

__all__ = [
    "extremes",
    "find_cached",
    "keeps_point",
    "open_point",
    "pair_of",
    "relative_speed",
    "store_points",
    "write_pair",
]


@njit(cache=True, inline="always")
def find_cached(keys: np.ndarray, count: int, key: int, cursor: int) -> tuple[int, int]:
    """Row of ``key`` in the sorted ``keys[:count]`` (-1 if absent), searched from row
    ``cursor`` on, and where the next search may start.

    Keys asked for in increasing order (the pairs come sorted) walk the cache once in all:
    O(pairs + cache) per step, not a search per pair.
    """
    while cursor < count and keys[cursor] < key:
        cursor += 1
    row = cursor if cursor < count and keys[cursor] == key else -1
    return row, cursor


@njit(cache=True, inline="always")
def keeps_point(
    un: float, sep: float, falls_apart: bool, g: float, dt: float, speculative: float,
    pull: float,
) -> bool:  # fmt: skip
    """Whether a manifold point of separation ``sep`` [m] and normal relative speed ``un``
    [m/s] (negative: approaching) is kept: it lies within the speculative distance plus how
    far the pair can close along the normal during the step ``dt`` [s], the approach speed
    and, when gravity ``g`` [m/s^2] acts on one body only (``falls_apart``), what it adds,
    and what the forces and torques on the two bodies can add (``pull``, the most they
    accelerate a point of either, summed [m/s^2]; 0 without)."""
    approach = max(0.0, -un)
    if falls_apart:
        approach += g * dt
    approach += pull * dt
    kept: bool = sep <= speculative + approach * dt
    return kept


@njit(cache=True, inline="always")
def pair_of(pairs: np.ndarray, k: int, piece_body: np.ndarray) -> tuple[int, int, int, int]:
    """Candidate pair ``k``'s pieces and bodies ``(pa, pb, ba, bb)``."""
    pa = pairs[k, 0]
    pb = pairs[k, 1]
    return pa, pb, piece_body[pa], piece_body[pb]


@njit(cache=True, inline="always")
def relative_speed(v: np.ndarray, a: int, b: int) -> float:
    """``|v_a - v_b|`` [m/s] of two bodies' velocities ``v`` (N, d), d = 2 or 3."""
    dx = v[a, 0] - v[b, 0]
    dy = v[a, 1] - v[b, 1]
    if v.shape[1] == 2:
        return math.sqrt(dx * dx + dy * dy)
    dz = v[a, 2] - v[b, 2]
    speed: float = math.sqrt(dx * dx + dy * dy + dz * dz)
    return speed


@njit(cache=True, inline="always")
def open_point(
    cf: np.ndarray, ci: np.ndarray, m: int, j: int, o: int, un: float, sep: float, feature: int,
    columns: tuple[int, int], zeroed: tuple[int, ...],
) -> None:  # fmt: skip
    """Point ``j`` of contact row ``m`` (its columns from ``o``): its normal relative speed
    ``un`` [m/s] and separation ``sep`` [m] into the ``columns`` (vrel, sep) from ``o``, its
    feature id, and its impulses and totals (``zeroed``, from ``o``) at zero."""
    for c in zeroed:
        cf[m, o + c] = 0.0
    cf[m, o + columns[0]] = un
    cf[m, o + columns[1]] = sep
    ci[m, I_ID0 + j] = feature


@njit(cache=True, inline="always")
def write_pair(
    cf: np.ndarray, ci: np.ndarray, m: int, pair: tuple[int, int, int, int], points: int,
    flags: int, material: np.ndarray, tables: tuple[np.ndarray, np.ndarray],
    columns: tuple[int, int],
) -> tuple[int, int]:  # fmt: skip
    """What contact row ``m`` says of its pair ``(pa, pb, ba, bb)``: bodies, pieces, how many
    points, flags cleared (column ``flags``), and the friction and restitution of the
    bodies' materials from ``tables`` (mu, e) into the float ``columns`` (mu, e); the points'
    feature ids are written with the points. Return the two materials."""
    pa, pb, ba, bb = pair
    ma = material[ba]
    mb = material[bb]
    cf[m, columns[0]] = tables[0][ma, mb]
    cf[m, columns[1]] = tables[1][ma, mb]
    ci[m, I_BODY_A] = ba
    ci[m, I_BODY_B] = bb
    ci[m, I_PIECE_A] = pa
    ci[m, I_PIECE_B] = pb
    ci[m, I_COUNT] = points
    ci[m, flags] = 0
    return ma, mb


@njit(cache=True)
def extremes(
    cf: np.ndarray, ci: np.ndarray, nc: int, layout: tuple[int, int, int, int]
) -> tuple[np.ndarray, np.ndarray]:
    """Each contact's least separation [m] and least normal relative speed [m/s] over its
    points, (nc,) each (:func:`carom.engines.stepped.islands.plan`). ``layout``: a row's first
    point column, the columns per point, and the separation's and speed's columns from a
    point's offset."""
    point0, point_floats, sep, vrel = layout
    closest = np.full(nc, np.inf)
    closing = np.full(nc, np.inf)
    for m in range(nc):
        for j in range(ci[m, I_COUNT]):
            o = point0 + point_floats * j
            closest[m] = min(closest[m], cf[m, o + sep])
            closing[m] = min(closing[m], cf[m, o + vrel])
    return closest, closing


@leaf
def store_points(
    cf: np.ndarray, ci: np.ndarray, n_contacts: int, n_pieces: int,
    layout: tuple[int, int, int], cache_keys: np.ndarray, cache_ids: np.ndarray,
    cache_impulses: np.ndarray,
) -> int:  # fmt: skip
    """Keep each contact's key, its points' feature ids and normal impulses for the next
    step's warm start; return the count. ``layout``: a row's first point column, the columns
    per point, and the normal impulse's column from a point's offset.

    ``cache_impulses`` (K, points, C): per point the normal impulse, then C - 1 tangent
    components, zeroed here; the dimension writes the tangents of the points a contact has.
    A point the contact lacks gets id -1. Contacts come in key order (their pairs were
    sorted), so the cache stays sorted.
    """
    point0, point_floats, jn = layout
    for m in range(n_contacts):
        cache_keys[m] = ci[m, I_PIECE_A] * n_pieces + ci[m, I_PIECE_B]
        for q in range(cache_ids.shape[1]):
            for c in range(cache_impulses.shape[2]):
                cache_impulses[m, q, c] = 0.0
            if q < ci[m, I_COUNT]:
                cache_ids[m, q] = ci[m, I_ID0 + q]
                cache_impulses[m, q, 0] = cf[m, point0 + point_floats * q + jn]
            else:
                cache_ids[m, q] = -1
    return n_contacts
