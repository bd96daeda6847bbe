"""Broad phase in 2D: each piece's swept box for this step; the grid that pairs the boxes is
shared with 3D (:func:`carom.engines.stepped.broadphase.find_pairs`).

Each piece gets an axis-aligned box around everything it can reach during the step: its
placed corners grown by its rounding radius, swept by its body's motion (``v dt`` and, under
gravity, ``g dt^2/2``), by the farthest any point can turn (``|omega| dt`` times the piece's
reach from the body's centre) and by a margin.
"""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["piece_boxes", "sweep_box"]


@njit(cache=True)
def piece_boxes(
    vertices: np.ndarray,
    piece_start: np.ndarray,
    piece_count: np.ndarray,
    piece_radius: np.ndarray,
    piece_reach: np.ndarray,
    piece_body: np.ndarray,
    velocity: np.ndarray,
    omega: np.ndarray,
    moving: np.ndarray,
    gravity_on: np.ndarray,
    gx: float,
    gy: float,
    pull: np.ndarray,
    dt: float,
    margin: float,
    boxes: np.ndarray,
) -> None:
    """Swept boxes ``(min x, min y, max x, max y)`` [m] of every piece, into ``boxes`` (P, 4).

    ``moving[i]``: body i moves this step (awake dynamic or kinematic); ``gravity_on[i]``:
    gravity acts on it; ``pull[i]``: the most the forces and torques given to it for this
    step accelerate any of its points [m/s^2] (0 without).
    """
    for p in range(piece_start.shape[0]):
        b = piece_body[p]
        sweep_box(
            p, vertices, piece_start, piece_count, piece_radius, piece_reach, velocity[b, 0],
            velocity[b, 1], omega[b] if moving[b] else 0.0, gx, gy,
            dt if moving[b] else 0.0, gravity_on[b], pull[b], margin, boxes[p],
        )  # fmt: skip


@njit(cache=True, inline="always")
def sweep_box(
    p: int, vertices: np.ndarray, piece_start: np.ndarray, piece_count: np.ndarray,
    piece_radius: np.ndarray, piece_reach: np.ndarray, vx: float, vy: float, omega: float,
    gx: float, gy: float, dt: float, gravity_on: bool, pull: float, margin: float,
    box: np.ndarray,
) -> None:  # fmt: skip
    """Placed piece ``p``'s box swept by where its points can go in ``dt`` [s] (its body's
    velocity ``(vx, vy)`` [m/s] and spin ``omega`` [rad/s], gravity ``(gx, gy)`` if
    ``gravity_on``, and any acceleration up to ``pull`` [m/s^2] besides), grown by its
    radius and ``margin`` [m], into ``box`` (4,)."""
    s = piece_start[p]
    lo_x = vertices[s, 0]
    hi_x = lo_x
    lo_y = vertices[s, 1]
    hi_y = lo_y
    for k in range(1, piece_count[p]):
        x = vertices[s + k, 0]
        y = vertices[s + k, 1]
        lo_x = min(lo_x, x)
        hi_x = max(hi_x, x)
        lo_y = min(lo_y, y)
        hi_y = max(hi_y, y)
    r = piece_radius[p] + margin
    if dt > 0.0:
        dx = vx * dt
        dy = vy * dt
        if gravity_on:
            dx += 0.5 * gx * dt * dt
            dy += 0.5 * gy * dt * dt
        turn = abs(omega) * dt * piece_reach[p]
        # an arc of angle |omega| dt is no longer than its chord bound, 2 reach
        turn = min(turn, 2.0 * piece_reach[p])
        turn += 0.5 * pull * dt * dt
        lo_x = min(lo_x, lo_x + dx) - turn
        hi_x = max(hi_x, hi_x + dx) + turn
        lo_y = min(lo_y, lo_y + dy) - turn
        hi_y = max(hi_y, hi_y + dy) + turn
    box[0] = lo_x - r
    box[1] = lo_y - r
    box[2] = hi_x + r
    box[3] = hi_y + r
