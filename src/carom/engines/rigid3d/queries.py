"""Rays cast into a 3D rigid world, many in one compiled call (:mod:`carom.geometry.rays`).

As in 2D (:mod:`carom.engines.rigid.queries`): the static pieces through the engine's tree
over them, the planes one by one, the moving bodies' pieces through a tree over their reach
(or one by one for a few rays); each piece met is placed at its body's pose now and tested
exactly: a sphere, a capsule, a convex polytope (boxes, hulls, a mesh's triangles) or a plane.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from carom.engines.rigid3d.contacts import collide_pieces
from carom.engines.rigid3d.model import PIECE_PLANE, PIECE_ROUND
from carom.engines.rigid3d.motion import place_piece
from carom.engines.stepped.sensors import sensor_pair
from carom.geometry.bvh import is_empty, ray_candidate, ray_candidates
from carom.geometry.manifold3d import MAX_POINTS, OUT_SIZE
from carom.geometry.overlaps import box_meets_piece_3d, point_in_piece_3d
from carom.geometry.rays import ray_capsule, ray_plane, ray_polytope, ray_sphere
from carom.geometry.rotation import matrix

__all__ = ["cast_rays", "overlap_pieces", "sensed"]


@njit(cache=True, inline="always")
def _place(
    p: int, b: int, x: np.ndarray, q: np.ndarray, vstart: np.ndarray, vcount: np.ndarray,
    fstart: np.ndarray, fcount: np.ndarray, local_vertices: np.ndarray,
    local_normals: np.ndarray, rot: np.ndarray, v: np.ndarray, n: np.ndarray,
) -> None:  # fmt: skip
    """Piece ``p`` of body ``b`` at the body's pose now: its corners into ``v`` (k, 3) and its
    face normals into ``n`` (f, 3) (``rot`` (9,): room for the body's rotation)."""
    matrix(q, b, rot)
    for i in range(vcount[p]):
        lv = local_vertices[vstart[p] + i]
        for a in range(3):
            v[i, a] = (
                x[b, a] + rot[3 * a] * lv[0] + rot[3 * a + 1] * lv[1] + (rot[3 * a + 2] * lv[2])
            )
    for f in range(fcount[p]):
        ln = local_normals[fstart[p] + f]
        for a in range(3):
            n[f, a] = rot[3 * a] * ln[0] + rot[3 * a + 1] * ln[1] + rot[3 * a + 2] * ln[2]


@njit(cache=True, error_model="numpy")
def cast_rays(
    origins: np.ndarray, directions: np.ndarray, lengths: np.ndarray, statics: tuple[Any, ...],
    open_statics: np.ndarray, movers: tuple[Any, ...], x: np.ndarray, q: np.ndarray,
    model_ints: tuple[Any, ...], piece_radius: np.ndarray, local_vertices: np.ndarray,
    local_normals: np.ndarray, face_first: np.ndarray, face_size: np.ndarray,
    corners: np.ndarray, categories: np.ndarray, mask: int, room: tuple[int, int],
    distance: np.ndarray, piece: np.ndarray, normal: np.ndarray,
) -> None:  # fmt: skip
    """Cast rays ``origins`` (R, 3) [m] along unit ``directions`` (R, 3) up to ``lengths``
    (R,) [m]: each one's ``distance`` [m] (inf: no hit), the ``piece`` hit (-1) and the outward
    ``normal`` (R, 3) there. ``model_ints``: the pieces' body, kind, vertex start and count,
    face start and count, corner start (:class:`.model.Model3D`); ``statics``, ``open_statics``
    and ``movers`` as in 2D (:func:`carom.engines.rigid.queries.cast_rays`); a piece whose
    ``categories`` (P,) bits hold none of ``mask`` is not seen; ``room``: the most corners
    and faces a piece has."""
    piece_body, piece_kind, vstart, vcount, fstart, fcount, cstart = model_ints
    m_boxes, m_pieces = movers[5], movers[6]
    alone = m_pieces.shape[0] if is_empty(movers[3], movers[1]) else 0  # tested one by one
    v = np.empty((room[0], 3))
    n = np.empty((room[1], 3))
    rot = np.empty(9)
    found = np.empty(64, np.int64)
    inv = np.empty(3)
    out = np.empty(3)
    for r in range(origins.shape[0]):
        o, d = origins[r], directions[r]
        for k in range(3):
            # (IEEE's 1 / +-0 = +-inf, the slab test's axis the ray runs along; written out,
            # as plain Python warns where the compiled kernel does not)
            inv[k] = 1.0 / d[k] if d[k] != 0.0 else math.copysign(math.inf, d[k])
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
            _place(
                p, b, x, q, vstart, vcount, fstart, fcount, local_vertices, local_normals, rot, v, n
            )
            kind = piece_kind[p]
            if kind == PIECE_PLANE:
                t = ray_plane(o, d, v[0], n[0])
                out[0], out[1], out[2] = n[0, 0], n[0, 1], n[0, 2]
            elif kind == PIECE_ROUND and vcount[p] == 1:
                t = ray_sphere(o, d, v[0], piece_radius[p])
                if t < math.inf:
                    for a in range(3):
                        out[a] = (o[a] + t * d[a] - v[0, a]) / piece_radius[p]
            elif kind == PIECE_ROUND:
                t = ray_capsule(o, d, v[0], v[1], piece_radius[p], out)
            else:
                fs, fc = fstart[p], fcount[p]
                t = ray_polytope(
                    o, d, v[: vcount[p]], n[:fc], face_first[fs : fs + fc],
                    face_size[fs : fs + fc], corners[cstart[p] :], out,
                )  # fmt: skip
            if t <= best and t < distance[r]:
                best = t
                distance[r] = t
                piece[r] = p
                normal[r, 0], normal[r, 1], normal[r, 2] = out[0], out[1], out[2]


@njit(cache=True)
def overlap_pieces(
    candidates: np.ndarray, low: np.ndarray, high: np.ndarray, point: bool, x: np.ndarray,
    q: np.ndarray, model_ints: tuple[Any, ...], piece_radius: np.ndarray,
    local_vertices: np.ndarray, local_normals: np.ndarray, face_first: np.ndarray,
    corners: np.ndarray, edges: np.ndarray, categories: np.ndarray, mask: int,
    room: tuple[int, int], hit: np.ndarray,
) -> None:  # fmt: skip
    """Which of the pieces ``candidates`` (K,) hold the point ``low`` (``point``) or meet the
    box ``[low, high]`` (3,) now, exactly (:mod:`carom.geometry.overlaps`), into ``hit``
    (K,) bool. ``model_ints``: the pieces' body, kind, vertex start and count, face start and
    count, corner start, edge start and count; a piece whose ``categories`` (P,) bits hold
    none of ``mask`` is not seen; ``room``: the most corners and faces a piece has."""
    piece_body, piece_kind, vstart, vcount, fstart, fcount, cstart, estart, ecount = model_ints
    v = np.empty((room[0], 3))
    n = np.empty((room[1], 3))
    rot = np.empty(9)
    for j in range(candidates.shape[0]):
        p = candidates[j]
        b = piece_body[p]
        hit[j] = False
        if categories[p] & mask == 0:
            continue
        _place(p, b, x, q, vstart, vcount, fstart, fcount, local_vertices, local_normals, rot, v, n)
        fs, fc = fstart[p], fcount[p]
        if point:
            hit[j] = point_in_piece_3d(
                low, piece_kind[p], v, vcount[p], n, fc, face_first[fs : fs + fc],
                corners[cstart[p] :], piece_radius[p],
            )  # fmt: skip
        else:
            hit[j] = box_meets_piece_3d(
                low, high, piece_kind[p], v, vcount[p], n, fc,
                edges[estart[p] : estart[p] + ecount[p]], piece_radius[p],
            )  # fmt: skip


@njit(cache=True)
def sensed(
    pairs: np.ndarray, n_pairs: int, sensor: np.ndarray, filters: np.ndarray,
    number: np.ndarray, x: np.ndarray, q: np.ndarray, model_ints: tuple[Any, ...],
    piece_radius: np.ndarray, local_vertices: np.ndarray, local_normals: np.ndarray,
    face_first: np.ndarray, face_size: np.ndarray, corners: np.ndarray, edges: np.ndarray,
    vertices: np.ndarray, normals: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """The sensor pairs among the broad phase's piece ``pairs[:n_pairs]`` that overlap or
    touch now, as keys in the caller's ``number``: the 2D engine's
    (:func:`carom.engines.rigid.queries.sensed`), the pieces placed into ``vertices``,
    ``normals`` and met by the narrow phase's kernels (:func:`.contacts.collide_pieces`).
    ``model_ints``: the pieces' body, kind, vertex start and count, face start and count,
    corner start and count, edge start and count."""
    (
        piece_body, piece_kind, vstart, vcount, fstart, fcount, cstart, ccount, estart, ecount,
    ) = model_ints  # fmt: skip
    keys = np.empty(n_pairs, np.int64)
    base = number.shape[0] + 1
    out = np.empty(OUT_SIZE)
    ids = np.empty(MAX_POINTS, np.int64)
    k = 0
    for j in range(n_pairs):
        s, o, ps, po = sensor_pair(pairs[j, 0], pairs[j, 1], piece_body, sensor, filters, number)
        if s < 0:
            continue
        for p, b in ((ps, s), (po, o)):
            place_piece(
                p, x, q, b, vstart, vcount, fstart, fcount, local_vertices, local_normals,
                vertices, normals,
            )  # fmt: skip
        if collide_pieces(
            ps, po, piece_kind, piece_radius, vstart, vcount, fstart, fcount, cstart, ccount,
            estart, ecount, vertices, normals, face_first, face_size, corners, edges, 0.0, 0.0,
            out, ids,
        ):  # fmt: skip
            keys[k] = (number[s] + 1) * base + number[o] + 1
            k += 1
    return keys[:k]
