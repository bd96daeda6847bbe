"""Broad phase: the pairs of pieces whose swept boxes overlap this step, in O(N) on average.

Each piece gets an axis-aligned box around everything it can reach during the step: its
placed corners grown by its rounding radius, swept by its body's motion (``v dt`` and, under
gravity, ``g dt^2/2``), by the farthest any point can turn (``|omega| dt`` times the piece's
reach from the body's centre) and by a margin. Boxes go into a uniform grid of square cells,
hashed into a table (Teschner et al. 2003); two pieces are a candidate pair when they share a
cell and their boxes overlap. A pair sharing several cells is reported from one of them only:
the cell holding the lower-left corner of the boxes' overlap. A box spanning more than
``MAX_CELLS`` cells (a long static segment, the ground, a very fast body) is kept apart and
tested against every box (a handful of such pieces, each O(N)).

Pairs are sorted by key ``a * P + b`` (``a < b``, P pieces), so the contact list comes out in
the same order every step and every run.

The grid is rebuilt only when a piece leaves its fat box
(:class:`carom.engines.stepped.broadphase.KeptPairs`); a resting stack never rebuilds.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.stepped.broadphase import wanted_pair

__all__ = ["MAX_CELLS", "find_pairs", "piece_boxes"]

#: a box covering more cells than this is tested against every box instead of gridded
MAX_CELLS = 16


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
    dt: float,
    margin: float,
    boxes: np.ndarray,
) -> None:
    """Swept boxes ``(min x, min y, max x, max y)`` [m] of every piece, into ``boxes`` (P, 4).

    ``moving[i]``: body i moves this step (awake dynamic or kinematic); ``gravity_on[i]``:
    gravity acts on it.
    """
    for p in range(piece_start.shape[0]):
        s = piece_start[p]
        r = piece_radius[p] + margin
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
        b = piece_body[p]
        if moving[b]:
            dx = velocity[b, 0] * dt
            dy = velocity[b, 1] * dt
            if gravity_on[b]:
                dx += 0.5 * gx * dt * dt
                dy += 0.5 * gy * dt * dt
            turn = abs(omega[b]) * dt * piece_reach[p]
            # an arc of angle |omega| dt is no longer than its chord bound, 2 reach
            turn = min(turn, 2.0 * piece_reach[p])
            lo_x = min(lo_x, lo_x + dx) - turn
            hi_x = max(hi_x, hi_x + dx) + turn
            lo_y = min(lo_y, lo_y + dy) - turn
            hi_y = max(hi_y, hi_y + dy) + turn
        boxes[p, 0] = lo_x - r
        boxes[p, 1] = lo_y - r
        boxes[p, 2] = hi_x + r
        boxes[p, 3] = hi_y + r


@njit(cache=True, inline="always")
def _bucket(cx: int, cy: int, mask: int) -> int:
    # Teschner's spatial hash: two large primes, xor, masked to the table
    return ((cx * 73856093) ^ (cy * 19349663)) & mask


@njit(cache=True, inline="always")
def _overlap(boxes: np.ndarray, a: int, b: int) -> bool:
    overlap: bool = (
        boxes[a, 0] <= boxes[b, 2]
        and boxes[b, 0] <= boxes[a, 2]
        and boxes[a, 1] <= boxes[b, 3]
        and boxes[b, 1] <= boxes[a, 3]
    )
    return overlap


@njit(cache=True, inline="always")
def _buckets(boxes: np.ndarray, p: int, inv: float, mask: int, mine: np.ndarray) -> int:
    """The distinct buckets of the cells piece ``p``'s box covers, into ``mine``; return how
    many, or -1 when the box covers more than MAX_CELLS cells (a big piece)."""
    x0 = math.floor(boxes[p, 0] * inv)
    y0 = math.floor(boxes[p, 1] * inv)
    x1 = math.floor(boxes[p, 2] * inv)
    y1 = math.floor(boxes[p, 3] * inv)
    if (x1 - x0 + 1) * (y1 - y0 + 1) > MAX_CELLS:
        return -1
    used = 0
    for cx in range(x0, x1 + 1):
        for cy in range(y0, y1 + 1):
            h = _bucket(cx, cy, mask)
            seen = False
            for k in range(used):
                if mine[k] == h:
                    seen = True
            if not seen:
                mine[used] = h
                used += 1
    return used


@njit(cache=True)
def find_pairs(
    boxes: np.ndarray,
    piece_body: np.ndarray,
    active: np.ndarray,
    dynamic: np.ndarray,
    cell: float,
    pairs: np.ndarray,
) -> int:
    """Candidate pairs of pieces, sorted, into ``pairs`` (capacity, 2); return their number.

    Parameters
    ----------
    boxes : (P, 4) float64
        Swept boxes [m] (:func:`piece_boxes`).
    piece_body : (P,) int64
        Each piece's body.
    active : (N,) bool
        Bodies that move this step (awake dynamic or kinematic); a pair needs one.
    dynamic : (N,) bool
        Dynamic bodies (awake or asleep); a pair needs one (two static or kinematic bodies
        never collide).
    cell : float
        Grid cell side [m].
    pairs : (capacity, 2) int64
        Written. When more pairs are found than fit, the return value is minus the number
        needed and the caller grows ``pairs`` and calls again.
    """
    n = boxes.shape[0]
    size = 64
    while size < 2 * n:
        size *= 2
    mask = size - 1
    inv = 1.0 / cell
    big = np.zeros(n, np.bool_)
    start = np.zeros(size + 1, np.int64)
    mine = np.empty(MAX_CELLS, np.int64)
    # every piece goes in the grid, even one of a body that does not move (static, asleep,
    # kinematic at rest): an active body may run into it
    for p in range(n):
        used = _buckets(boxes, p, inv, mask, mine)
        if used < 0:
            big[p] = True
        for k in range(used):
            start[mine[k] + 1] += 1
    for h in range(size):
        start[h + 1] += start[h]
    fill = start[:-1].copy()
    entries = np.empty(start[size], np.int64)
    for p in range(n):
        for k in range(_buckets(boxes, p, inv, mask, mine)):
            h = mine[k]
            entries[fill[h]] = p
            fill[h] += 1
    count = 0
    capacity = pairs.shape[0]
    for h in range(size):
        for i in range(start[h], start[h + 1]):
            a = entries[i]
            for j in range(i + 1, start[h + 1]):
                b = entries[j]
                if not wanted_pair(piece_body, active, dynamic, a, b) or not _overlap(boxes, a, b):
                    continue
                # report from the bucket of the overlap's lower-left cell only
                cx = math.floor(max(boxes[a, 0], boxes[b, 0]) * inv)
                cy = math.floor(max(boxes[a, 1], boxes[b, 1]) * inv)
                if _bucket(cx, cy, mask) != h:
                    continue
                if count < capacity:
                    pairs[count, 0] = min(a, b)
                    pairs[count, 1] = max(a, b)
                count += 1
    for a in range(n):
        if not big[a]:
            continue
        for b in range(n):
            if b == a or (big[b] and b < a):
                continue  # two big pieces: once
            if not wanted_pair(piece_body, active, dynamic, a, b) or not _overlap(boxes, a, b):
                continue
            if count < capacity:
                pairs[count, 0] = min(a, b)
                pairs[count, 1] = max(a, b)
            count += 1
    if count > capacity:
        return -count
    _sort_pairs(pairs, count, n)
    return count


@njit(cache=True)
def _sort_pairs(pairs: np.ndarray, count: int, n: int) -> None:
    """Sort ``pairs[:count]`` (each ``a < b``, distinct) by ``(a, b)`` in O(count + n): a
    counting sort on ``a``, then each piece's few partners by insertion."""
    start = np.zeros(n + 1, np.int64)
    for k in range(count):
        start[pairs[k, 0] + 1] += 1
    for a in range(n):
        start[a + 1] += start[a]
    fill = start[:-1].copy()
    partner = np.empty(count, np.int64)
    for k in range(count):
        a = pairs[k, 0]
        partner[fill[a]] = pairs[k, 1]
        fill[a] += 1
    for a in range(n):
        for i in range(start[a] + 1, start[a + 1]):
            b = partner[i]
            j = i - 1
            while j >= start[a] and partner[j] > b:
                partner[j + 1] = partner[j]
                j -= 1
            partner[j + 1] = b
        for i in range(start[a], start[a + 1]):
            pairs[i, 0] = a
            pairs[i, 1] = partner[i]
