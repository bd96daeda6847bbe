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
from carom.geometry.manifold2d import collide, core_witness
from carom.geometry.overlaps import box_meets_polygon, point_in_polygon
from carom.geometry.rays import ray_rounded_polygon

__all__ = ["CAST_ITERATIONS", "cast_rays", "cast_shape", "overlap_pieces", "sensed"]

#: conservative-advancement steps of a shape cast against one piece, at the most (each step
#: closes the gap by at least its share of the translation: a grazing pass takes the most)
CAST_ITERATIONS = 500


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
    by one). A piece whose ``categories`` (P,) bits (its body's; none for a sensor's piece)
    hold none of ``mask`` is not seen.
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
        # (IEEE's 1 / +-0 = +-inf, written out: plain Python warns where the kernel does not)
        inv[0] = 1.0 / d[0] if d[0] != 0.0 else math.copysign(math.inf, d[0])
        inv[1] = 1.0 / d[1] if d[1] != 0.0 else math.copysign(math.inf, d[1])
        best = lengths[r]
        distance[r] = math.inf
        piece[r] = -1
        found, k = ray_candidates(statics, movers, o, inv, best, found)
        for j in range(k + open_statics.shape[0] + alone):
            p = ray_candidate(j, found, k, open_statics, m_boxes, m_pieces, o, inv, best)
            if p < 0:
                continue
            b = piece_body[p]
            if categories[p] & mask == 0:
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
    (K,) bool; a piece whose ``categories`` (P,) bits hold none of ``mask`` is not seen."""
    v = np.empty((room, 2))
    n = np.empty((room, 2))
    for j in range(candidates.shape[0]):
        p = candidates[j]
        b = piece_body[p]
        hit[j] = False
        if categories[p] & mask == 0:
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


@njit(cache=True)
def cast_shape(
    cast: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    pose: np.ndarray, move: np.ndarray, candidates: np.ndarray, x: np.ndarray,
    angle: np.ndarray, piece_body: np.ndarray, piece_start: np.ndarray,
    piece_count: np.ndarray, piece_radius: np.ndarray, piece_reach: np.ndarray,
    local_vertices: np.ndarray, local_normals: np.ndarray, categories: np.ndarray, mask: int,
    room: int, hit: np.ndarray,
) -> int:  # fmt: skip
    """The first piece of ``candidates`` (K,) that a shape moved from ``pose`` (x, y, angle)
    along ``move`` (2,) [m] (turning not) would touch, and when: returns the piece (-1: none)
    and writes ``hit``: the fraction of ``move`` travelled, the point (2) and the piece's
    outward normal there (2).

    ``cast``: the shape's pieces in its own frame (corners, edge normals, each piece's first
    corner, corner count, rounding radius and reach). Per candidate piece and cast piece,
    conservative advancement along the translation: from a gap ``d`` (the exact distance of
    the cores less the radii, :func:`carom.geometry.manifold2d.core_witness`) the shape
    cannot touch before travelling ``d``, so the fraction moves on by ``d / |move|`` until
    the gap is within a billionth of the pieces' reach; a shape that starts touching or
    overlapping hits at 0. A piece whose ``categories`` (P,) bits hold none of ``mask`` is not
    seen.
    """
    c_vertices, c_normals, c_start, c_count, c_radius, c_reach = cast
    length = math.hypot(move[0], move[1])
    most = int(c_count.max()) if c_count.shape[0] else 1
    v = np.empty((room + most, 2))
    n = np.empty((room + most, 2))
    out = np.empty(8)
    ids = np.empty(2, np.int64)
    best = 1.0
    found = -1
    cs, sn = math.cos(pose[2]), math.sin(pose[2])
    for j in range(candidates.shape[0]):
        p = candidates[j]
        b = piece_body[p]
        if categories[p] & mask == 0:
            continue
        kb = _place(p, b, x, angle, piece_start, piece_count, local_vertices, local_normals, v, n)
        for q in range(c_start.shape[0]):
            ka = c_count[q]
            tol = 1e-9 * (c_reach[q] + piece_reach[p])
            t = 0.0
            for _ in range(CAST_ITERATIONS):
                ox, oy = pose[0] + t * move[0], pose[1] + t * move[1]
                for i in range(ka):
                    lx, ly = c_vertices[c_start[q] + i, 0], c_vertices[c_start[q] + i, 1]
                    v[room + i, 0] = ox + cs * lx - sn * ly
                    v[room + i, 1] = oy + sn * lx + cs * ly
                    nx, ny = c_normals[c_start[q] + i, 0], c_normals[c_start[q] + i, 1]
                    n[room + i, 0] = cs * nx - sn * ny
                    n[room + i, 1] = sn * nx + cs * ny
                d, _, _ = core_witness(v, n, room, ka, 0, kb)
                gap = d - c_radius[q] - piece_radius[p] if d > 0.0 else -1.0
                if gap <= tol:
                    if t < best or found < 0:
                        count = collide(
                            v, n, room, ka, c_radius[q], 0, kb, piece_radius[p], np.inf, 0.0,
                            out, ids,
                        )  # fmt: skip
                        best = t
                        found = p
                        hit[0] = t
                        deepest = 0
                        for k in range(1, count):
                            if out[4 + 3 * k] < out[4 + 3 * deepest]:
                                deepest = k
                        hit[1] = out[2 + 3 * deepest]
                        hit[2] = out[3 + 3 * deepest]
                        hit[3] = out[0]
                        hit[4] = out[1]
                    break
                t += gap / length
                if t > best:
                    break
    return found
