"""Broad phase in 3D: the pairs of pieces whose swept boxes overlap this step, in O(N) on
average, as the 2D engine's (:mod:`carom.engines.rigid.broadphase`) with one more axis.

Each piece gets an axis-aligned box around everything it can reach during the step: its placed
corners grown by its radius, swept by its body's motion (``v dt``, and ``g dt^2/2`` under
gravity), by the farthest any point can turn (``|w| dt`` times the piece's reach, at most twice
the reach) and by a margin. Boxes go into a uniform grid of cubic cells hashed into a table
(Teschner et al. 2003); two pieces are a candidate pair when they share a cell and their boxes
overlap, reported from the bucket of the cell holding the overlap's lowest corner only. A box
covering more than ``MAX_CELLS`` cells (a plane, a long static slab, a very fast body) is kept
apart and tested against every box.

A plane's box is unbounded, except along the axis its normal lies on, if it lies on one (a
floor's box ends at the floor). Pairs are sorted by key ``a * P + b`` (``a < b``).

The driver keeps the pairs from step to step through fat boxes, as the 2D engine does
(:class:`carom.engines.stepped.broadphase.KeptPairs`): a resting stack is paired once.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.rigid3d.model import PIECE_PLANE
from carom.engines.stepped.broadphase import wanted_pair

__all__ = ["MAX_CELLS", "find_pairs", "piece_boxes"]

#: a box covering more cells than this is tested against every box instead of gridded
MAX_CELLS = 64


@njit(cache=True)
def piece_boxes(
    vertices: np.ndarray,
    normals: np.ndarray,
    piece_kind: np.ndarray,
    piece_vstart: np.ndarray,
    piece_vcount: np.ndarray,
    piece_fstart: np.ndarray,
    piece_radius: np.ndarray,
    piece_reach: np.ndarray,
    piece_body: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    which: np.ndarray,
    gravity_on: np.ndarray,
    g: np.ndarray,
    dt: float,
    margin: float,
    boxes: np.ndarray,
) -> None:
    """Swept boxes ``(lo x, lo y, lo z, hi x, hi y, hi z)`` [m] of the pieces of the bodies with
    ``which[b]`` true, into ``boxes`` (P, 6); ``gravity_on[b]``: gravity ``g`` (3,) acts."""
    for p in range(piece_vstart.shape[0]):
        b = piece_body[p]
        if not which[b]:
            continue
        if piece_kind[p] == PIECE_PLANE:
            n = normals[piece_fstart[p]]
            at = vertices[piece_vstart[p]]
            for k in range(3):
                boxes[p, k] = -np.inf
                boxes[p, 3 + k] = np.inf
            for k in range(3):
                if abs(n[k]) == 1.0 and n[(k + 1) % 3] == 0.0 and n[(k + 2) % 3] == 0.0:
                    if n[k] > 0.0:
                        boxes[p, 3 + k] = at[k]  # the solid lies below
                    else:
                        boxes[p, k] = at[k]
            continue
        s = piece_vstart[p]
        r = piece_radius[p] + margin
        turn = min(math.sqrt(w[b, 0] ** 2 + w[b, 1] ** 2 + w[b, 2] ** 2) * dt, 2.0)
        turn *= piece_reach[p]
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
            boxes[p, k] = min(lo, lo + d) - turn - r
            boxes[p, 3 + k] = max(hi, hi + d) + turn + r


@njit(cache=True, inline="always")
def _bucket(cx: int, cy: int, cz: int, mask: int) -> int:
    # Teschner's spatial hash: three large primes, xor, masked to the table
    return ((cx * 73856093) ^ (cy * 19349663) ^ (cz * 83492791)) & mask


@njit(cache=True, inline="always")
def _overlap(boxes: np.ndarray, a: int, b: int) -> bool:
    overlap: bool = (
        boxes[a, 0] <= boxes[b, 3]
        and boxes[b, 0] <= boxes[a, 3]
        and boxes[a, 1] <= boxes[b, 4]
        and boxes[b, 1] <= boxes[a, 4]
        and boxes[a, 2] <= boxes[b, 5]
        and boxes[b, 2] <= boxes[a, 5]
    )
    return overlap


@njit(cache=True, inline="always")
def _cells(boxes: np.ndarray, p: int, inv: float) -> tuple[int, int, int, int, int, int]:
    """The range of cells piece ``p``'s box covers; an unbounded box covers too many."""
    lo = boxes[p, :3] * inv
    hi = boxes[p, 3:] * inv
    for k in range(3):
        if not (math.isfinite(lo[k]) and math.isfinite(hi[k])) or hi[k] - lo[k] > MAX_CELLS:
            return 0, 0, 0, -1, 0, 0
    return (
        math.floor(lo[0]), math.floor(lo[1]), math.floor(lo[2]),
        math.floor(hi[0]), math.floor(hi[1]), math.floor(hi[2]),
    )  # fmt: skip


@njit(cache=True)
def _buckets(boxes: np.ndarray, p: int, inv: float, mask: int, mine: np.ndarray) -> int:
    """The distinct buckets of the cells piece ``p``'s box covers, into ``mine``; return how
    many, or -1 when the box covers more than MAX_CELLS cells (a big piece)."""
    x0, y0, z0, x1, y1, z1 = _cells(boxes, p, inv)
    if x1 < x0 or (x1 - x0 + 1) * (y1 - y0 + 1) * (z1 - z0 + 1) > MAX_CELLS:
        return -1
    used = 0
    for cx in range(x0, x1 + 1):
        for cy in range(y0, y1 + 1):
            for cz in range(z0, z1 + 1):
                h = _bucket(cx, cy, cz, mask)
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
    boxes : (P, 6) float64
        Swept boxes [m] (:func:`piece_boxes`).
    piece_body : (P,) int64
        Each piece's body.
    active : (N,) bool
        Bodies that move this step (awake dynamic or kinematic); a pair needs one.
    dynamic : (N,) bool
        Dynamic bodies (awake or asleep); a pair needs one.
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
                # report from the bucket of the overlap's lowest cell only
                cx = math.floor(max(boxes[a, 0], boxes[b, 0]) * inv)
                cy = math.floor(max(boxes[a, 1], boxes[b, 1]) * inv)
                cz = math.floor(max(boxes[a, 2], boxes[b, 2]) * inv)
                if _bucket(cx, cy, cz, mask) != h:
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
    order = np.argsort(pairs[:count, 0] * n + pairs[:count, 1])
    sorted_pairs = pairs[:count][order].copy()
    pairs[:count] = sorted_pairs
    return count
