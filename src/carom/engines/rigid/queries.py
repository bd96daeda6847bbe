"""Rays cast into a 2D rigid world, many in one compiled call (:mod:`carom.geometry.rays`),
the pieces a point or a box overlaps (:mod:`carom.geometry.overlaps`), and the bodies
overlapping sensors (:mod:`carom.engines.stepped.sensors`).

A ray meets the pieces whose boxes it crosses: the static pieces through the engine's tree
over them (built once), the pieces of the bodies that move through a tree over their reach
built for the call (or one by one for a few rays), and each piece met is placed at its body's
pose now and tested exactly. The nearest hit within the ray's length wins.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from carom.engines.rigid.motion import place_piece
from carom.engines.stepped.sensors import sensor_pair
from carom.geometry.bvh import is_empty, ray_candidate, ray_candidates
from carom.geometry.manifold2d import collide
from carom.geometry.overlaps import box_meets_polygon, point_in_polygon
from carom.geometry.rays import ray_rounded_polygon

__all__ = ["cast_rays", "overlap_pieces", "sensed"]


@njit(cache=True, inline="always")
def _place(
    p: int, b: int, x: np.ndarray, angle: np.ndarray, piece_start: np.ndarray,
    piece_count: np.ndarray, local_vertices: np.ndarray, local_normals: np.ndarray,
    v: np.ndarray, n: np.ndarray,
) -> int:  # fmt: skip
    """Piece ``p`` of body ``b`` at the body's pose now: its corners into ``v`` and its edge
    normals into ``n`` (k, 2); returns its corner count."""
    c, s = math.cos(angle[b]), math.sin(angle[b])
    first, count = piece_start[p], piece_count[p]
    for i in range(count):
        lx, ly = local_vertices[first + i, 0], local_vertices[first + i, 1]
        v[i, 0] = x[b, 0] + (c * lx - s * ly)
        v[i, 1] = x[b, 1] + (s * lx + c * ly)
        nx, ny = local_normals[first + i, 0], local_normals[first + i, 1]
        n[i, 0] = c * nx - s * ny
        n[i, 1] = s * nx + c * ny
    return int(count)


@njit(cache=True, error_model="numpy")
def cast_rays(
    origins: np.ndarray, directions: np.ndarray, lengths: np.ndarray, statics: tuple[Any, ...],
    open_statics: np.ndarray, movers: tuple[Any, ...], x: np.ndarray, angle: np.ndarray,
    piece_body: np.ndarray, piece_start: np.ndarray, piece_count: np.ndarray,
    piece_radius: np.ndarray, local_vertices: np.ndarray, local_normals: np.ndarray,
    categories: np.ndarray, mask: int, room: tuple[int, int], distance: np.ndarray,
    piece: np.ndarray, normal: np.ndarray,
) -> None:  # fmt: skip
    """Cast rays ``origins`` (R, 2) [m] along unit ``directions`` (R, 2) up to ``lengths``
    (R,) [m]: each one's ``distance`` [m] (inf: no hit), the ``piece`` hit (-1) and the outward
    ``normal`` (R, 2) there.

    ``statics``: the static pieces' tree (node boxes, left, first, count, order) and their
    boxes; ``open_statics`` the static pieces with no finite box; ``movers``: the other pieces'
    tree over boxes of its own, then each box's piece (an empty tree: every box tested one
    by one). A body whose ``categories`` (N,) bits hold none of ``mask`` is not seen.
    ``room``: the most corners a piece has (and 0).
    """
    m_boxes, m_pieces = movers[5], movers[6]
    alone = m_pieces.shape[0] if is_empty(movers[3], movers[1]) else 0  # tested one by one
    v = np.empty((room[0], 2))
    n = np.empty((room[0], 2))
    found = np.empty(64, np.int64)
    inv = np.empty(2)
    out = np.empty(2)
    for r in range(origins.shape[0]):
        o, d = origins[r], directions[r]
        inv[0], inv[1] = 1.0 / d[0], 1.0 / d[1]
        best = lengths[r]
        distance[r] = math.inf
        piece[r] = -1
        found, k = ray_candidates(statics, movers, o, inv, best, found)
        for j in range(k + open_statics.shape[0] + alone):
            p = ray_candidate(j, found, k, open_statics, m_boxes, m_pieces, o, inv, best)
            if p < 0:
                continue
            b = piece_body[p]
            if categories[b] & mask == 0:
                continue
            count = _place(
                p, b, x, angle, piece_start, piece_count, local_vertices, local_normals, v, n
            )
            t = ray_rounded_polygon(o, d, v, n, count, piece_radius[p], out)
            if t <= best and t < distance[r]:
                best = t
                distance[r] = t
                piece[r] = p
                normal[r, 0], normal[r, 1] = out[0], out[1]


@njit(cache=True)
def overlap_pieces(
    candidates: np.ndarray, low: np.ndarray, high: np.ndarray, point: bool, x: np.ndarray,
    angle: np.ndarray, piece_body: np.ndarray, piece_start: np.ndarray,
    piece_count: np.ndarray, piece_radius: np.ndarray, local_vertices: np.ndarray,
    local_normals: np.ndarray, categories: np.ndarray, mask: int, room: int, hit: np.ndarray,
) -> None:  # fmt: skip
    """Which of the pieces ``candidates`` (K,) hold the point ``low`` (``point``) or meet the
    box ``[low, high]`` (2,) now, exactly (:mod:`carom.geometry.overlaps`), into ``hit``
    (K,) bool; a body whose ``categories`` bits hold none of ``mask`` is not seen."""
    v = np.empty((room, 2))
    n = np.empty((room, 2))
    for j in range(candidates.shape[0]):
        p = candidates[j]
        b = piece_body[p]
        hit[j] = False
        if categories[b] & mask == 0:
            continue
        count = _place(
            p, b, x, angle, piece_start, piece_count, local_vertices, local_normals, v, n
        )
        if point:
            hit[j] = point_in_polygon(low, v, n, count, piece_radius[p])
        else:
            hit[j] = box_meets_polygon(low, high, v, n, count, piece_radius[p])


@njit(cache=True)
def sensed(
    pairs: np.ndarray, n_pairs: int, sensor: np.ndarray, filters: np.ndarray,
    number: np.ndarray, x: np.ndarray, angle: np.ndarray, piece_body: np.ndarray,
    piece_start: np.ndarray, piece_count: np.ndarray, piece_radius: np.ndarray,
    local_vertices: np.ndarray, local_normals: np.ndarray, vertices: np.ndarray,
    normals: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """The sensor pairs among the broad phase's piece ``pairs[:n_pairs]`` that overlap or
    touch now (the pieces placed at their bodies' poses into ``vertices``, ``normals``; a
    separation <= 0 [m]), as keys ``(sensor + 1) * (M + 1) + (visitor + 1)`` in the caller's
    ``number`` (M,) (:mod:`carom.engines.stepped.sensors`), a pair once per pair of pieces.
    ``sensor`` (N,) marks the sensors, ``filters`` (N, 3) whom they see."""
    keys = np.empty(n_pairs, np.int64)
    base = number.shape[0] + 1
    out = np.empty(8)
    ids = np.empty(2, np.int64)
    k = 0
    for j in range(n_pairs):
        s, o, ps, po = sensor_pair(pairs[j, 0], pairs[j, 1], piece_body, sensor, filters, number)
        if s < 0:
            continue
        for p, b in ((ps, s), (po, o)):
            place_piece(
                p, x[b, 0], x[b, 1], angle[b], piece_start, piece_count, local_vertices,
                local_normals, vertices, normals,
            )  # fmt: skip
        if collide(
            vertices, normals, piece_start[ps], piece_count[ps], piece_radius[ps],
            piece_start[po], piece_count[po], piece_radius[po], 0.0, 0.0, out, ids,
        ):  # fmt: skip
            keys[k] = (number[s] + 1) * base + number[o] + 1
            k += 1
    return keys[:k]
