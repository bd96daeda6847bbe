"""Broad phase in 3D: each piece's swept box for this step; the grid that pairs the boxes is
shared with 2D (:func:`carom.engines.stepped.broadphase.find_pairs`).

Each piece gets an axis-aligned box around everything it can reach during the step: its placed
corners grown by its radius, swept by its body's motion (``v dt``, and ``g dt^2/2`` under
gravity), by the farthest any point can turn (``|w| dt`` times the piece's reach, at most twice
the reach) and by a margin. A plane's box is unbounded, except along the axis its normal lies
on, if it lies on one (a floor's box ends at the floor); the grid tests it against every box.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.rigid3d.model import PIECE_PLANE

__all__ = ["piece_boxes", "sweep_box"]


@njit(cache=True)
def piece_boxes(
    vertices: np.ndarray, normals: np.ndarray, piece_kind: np.ndarray, piece_vstart: np.ndarray,
    piece_vcount: np.ndarray, piece_fstart: np.ndarray, piece_radius: np.ndarray,
    piece_reach: np.ndarray, piece_body: np.ndarray, v: np.ndarray, w: np.ndarray,
    which: np.ndarray, gravity_on: np.ndarray, g: np.ndarray, pull: np.ndarray, dt: float,
    margin: float, body_pieces: np.ndarray, boxes: np.ndarray,
) -> None:  # fmt: skip
    """Swept boxes ``(lo x, lo y, lo z, hi x, hi y, hi z)`` [m] of the pieces of the bodies with
    ``which[b]`` true, into ``boxes`` (P, 6); ``gravity_on[b]``: gravity ``g`` (3,) acts;
    ``pull[b]``: the most the forces and torques given to body b for this step accelerate
    any of its points [m/s^2] (0 without).
    Body b's pieces are ``body_pieces[b]`` to ``body_pieces[b + 1]``: the other bodies'
    pieces (a static terrain's millions of triangles) are not looked at."""
    for b in range(body_pieces.shape[0] - 1):
        if which[b]:
            for p in range(body_pieces[b], body_pieces[b + 1]):
                sweep_box(
                    p, b, vertices, normals, piece_kind, piece_vstart, piece_vcount,
                    piece_fstart, piece_radius, piece_reach, v, w, gravity_on, g, pull[b], dt,
                    margin, boxes[p],
                )  # fmt: skip


@njit(cache=True, inline="always")
def sweep_box(
    p: int, b: int, vertices: np.ndarray, normals: np.ndarray, piece_kind: np.ndarray,
    piece_vstart: np.ndarray, piece_vcount: np.ndarray, piece_fstart: np.ndarray,
    piece_radius: np.ndarray, piece_reach: np.ndarray, v: np.ndarray, w: np.ndarray,
    gravity_on: np.ndarray, g: np.ndarray, pull: float, dt: float, margin: float,
    box: np.ndarray,
) -> None:  # fmt: skip
    """Piece ``p``'s (of body ``b``) swept box over ``dt`` [s] into ``box`` (6,); ``pull``
    [m/s^2] bounds what accelerates its points besides gravity."""
    if piece_kind[p] == PIECE_PLANE:
        n = normals[piece_fstart[p]]
        at = vertices[piece_vstart[p]]
        for k in range(3):
            box[k] = -np.inf
            box[3 + k] = np.inf
        for k in range(3):
            if abs(n[k]) == 1.0 and n[(k + 1) % 3] == 0.0 and n[(k + 2) % 3] == 0.0:
                if n[k] > 0.0:
                    box[3 + k] = at[k]  # the solid lies below
                else:
                    box[k] = at[k]
        return
    s = piece_vstart[p]
    r = piece_radius[p] + margin
    turn = min(math.sqrt(w[b, 0] ** 2 + w[b, 1] ** 2 + w[b, 2] ** 2) * dt, 2.0)
    turn *= piece_reach[p]
    turn += 0.5 * pull * dt * dt
    for k in range(3):
        lo = vertices[s, k]
        hi = lo
        for j in range(1, piece_vcount[p]):
            c = vertices[s + j, k]
            lo = min(lo, c)
            hi = max(hi, c)
        d = v[b, k] * dt
        if gravity_on[b]:
            d += 0.5 * g[k] * dt * dt
        box[k] = min(lo, lo + d) - turn - r
        box[3 + k] = max(hi, hi + d) + turn + r
