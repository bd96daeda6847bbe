"""Broad phase, one source for 2D and 3D: the pairs of pieces whose boxes overlap, in O(P)
on average, and the pairs kept from step to step through fat boxes.

Each dimension makes its pieces' swept boxes (:func:`carom.engines.rigid.broadphase.piece_boxes`,
:func:`carom.engines.rigid3d.broadphase.piece_boxes`): lower corner then upper, (P, 2 d).
:func:`find_pairs` puts them in a uniform grid of square or cubic cells hashed into a table
(Teschner et al. 2003); two pieces are a candidate pair when they share a cell and their boxes
overlap. A pair sharing several cells is reported from one of them only: the cell holding the
lowest corner of the boxes' overlap. A box covering more than :func:`max_cells_of` cells (the
ground, a plane, a long static slab, a very fast body) is kept apart and tested against every
box (a handful of such pieces, each O(P)). Pairs come out sorted by ``(a, b)``, ``a < b``, so the
contact list has the same order every step and every run.

The grid is rebuilt only when a piece leaves its *fat box* (its swept box grown by :data:`FAT`
of its reach, as Box2D's enlarged boxes): the pairs of overlapping fat boxes are kept, and each
step takes from them the pairs whose swept boxes overlap (:func:`select_pairs`). Every swept box
lies in its fat box, so that is every pair :func:`find_pairs` would give, in the same order; a
resting stack never rebuilds.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numba import njit

from carom.geometry.bvh import overlap, query_bvh
from carom.laws.kinds import KIND_DYNAMIC

__all__ = [
    "FAT",
    "KeptPairs",
    "find_pairs",
    "grid_cell",
    "max_cells_of",
    "refit",
    "select_pairs",
    "wanted_pair",
]

#: a fat box is a piece's swept box grown by this fraction of the piece's reach on each side
FAT = 0.1


@njit(cache=True, inline="always")
def wanted_pair(
    piece_body: np.ndarray, active: np.ndarray, dynamic: np.ndarray, a: int, b: int
) -> bool:
    """A pair worth a manifold: two bodies, one of them active, one of them dynamic."""
    ba = piece_body[a]
    bb = piece_body[b]
    wanted: bool = ba != bb and (active[ba] or active[bb]) and (dynamic[ba] or dynamic[bb])
    return wanted


def grid_cell(kind: np.ndarray, piece_body: np.ndarray, piece_reach: np.ndarray) -> float:
    """The grid's cell side [m]: four times the median reach of the dynamic pieces (a typical
    piece then sits in one to four square cells or one to eight cubic ones).

    Parameters
    ----------
    kind : (N,) int8
        Each body's kind.
    piece_body : (P,) int64
        Each piece's body.
    piece_reach : (P,) float64
        Each piece's reach from its body's centre [m]; a plane's is infinite and not counted.
    """
    finite = np.isfinite(piece_reach)
    dynamic = (kind[piece_body] == KIND_DYNAMIC) & finite
    reach = piece_reach[dynamic] if dynamic.any() else piece_reach[finite]
    if reach.size == 0:
        return 1.0
    cell = 4.0 * float(np.median(reach))
    return cell if cell > 0.0 and math.isfinite(cell) else 1.0


@njit(cache=True, inline="always")
def max_cells_of(d: int) -> int:
    """How many cells a box may cover in ``d`` dimensions and still go in the grid: four per
    axis (16 squares, 64 cubes); a bigger box is tested against every box instead."""
    cells: int = 4**d
    return cells


@njit(cache=True, inline="always")
def _bucket(cx: int, cy: int, cz: int, mask: int) -> int:
    # Teschner's spatial hash: a large prime per axis, xored, masked to the table; a 2D cell
    # has cz = 0, which leaves the hash of (cx, cy) as it is
    return ((cx * 73856093) ^ (cy * 19349663) ^ (cz * 83492791)) & mask


@njit(cache=True, inline="always")
def _cells(boxes: np.ndarray, p: int, k: int, d: int, inv: float) -> tuple[float, float]:
    """Piece ``p``'s box along axis ``k`` in cells; (0, 0) for the third axis of a 2D box."""
    if k >= d:
        return 0.0, 0.0
    return boxes[p, k] * inv, boxes[p, d + k] * inv


@njit(cache=True, inline="always")
def _buckets(
    boxes: np.ndarray, p: int, inv: float, mask: int, max_cells: int, mine: np.ndarray
) -> int:
    """The distinct buckets of the cells piece ``p``'s box covers, into ``mine``; return how
    many, or -1 when the box covers more than ``max_cells`` cells (a big piece)."""
    d = boxes.shape[1] // 2
    x0, x1 = _cells(boxes, p, 0, d, inv)
    y0, y1 = _cells(boxes, p, 1, d, inv)
    z0, z1 = _cells(boxes, p, 2, d, inv)
    for a, b in ((x0, x1), (y0, y1), (z0, z1)):
        # an unbounded box (a plane's) or a very long one covers too many cells
        if not (math.isfinite(a) and math.isfinite(b)) or b - a > max_cells:
            return -1
    lx, hx = math.floor(x0), math.floor(x1)
    ly, hy = math.floor(y0), math.floor(y1)
    lz, hz = math.floor(z0), math.floor(z1)
    if (hx - lx + 1) * (hy - ly + 1) * (hz - lz + 1) > max_cells:
        return -1
    used = 0
    for cx in range(lx, hx + 1):
        for cy in range(ly, hy + 1):
            for cz in range(lz, hz + 1):
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
    loose: np.ndarray,
    tree_box: np.ndarray,
    tree_left: np.ndarray,
    tree_first: np.ndarray,
    tree_count: np.ndarray,
    tree_order: np.ndarray,
    pairs: np.ndarray,
) -> int:
    """Candidate pairs of pieces, sorted, into ``pairs`` (capacity, 2); return their number.

    The pieces of static bodies with finite boxes are in a tree built once
    (:mod:`carom.geometry.bvh`); every other piece (``loose``: dynamic, kinematic, a static
    plane) goes in the grid. Pairs come from the grid's cells, from the loose pieces too big
    for it against every loose piece, and from each loose piece of a dynamic body walking
    the tree; two static pieces are never paired, nor even looked at. The cost grows
    with the loose pieces and the static pieces they meet, not with the static ones.

    Parameters
    ----------
    boxes : (P, 2 d) float64
        Swept boxes [m], lower corner then upper, d = 2 or 3; a plane's may be unbounded.
    piece_body : (P,) int64
        Each piece's body.
    active : (N,) bool
        Bodies that move this step (awake dynamic or kinematic); a pair needs one.
    dynamic : (N,) bool
        Dynamic bodies (awake or asleep); a pair needs one (two static or kinematic bodies
        never collide).
    cell : float
        Grid cell side [m].
    loose : (L,) int64
        The pieces not in the tree, ascending.
    tree_box, tree_left, tree_first, tree_count, tree_order
        The tree over the other pieces (:class:`carom.geometry.bvh.Bvh`); its node boxes hold
        those pieces' ``boxes``.
    pairs : (capacity, 2) int64
        Written. When more pairs are found than fit, the return value is minus the number
        needed and the caller grows ``pairs`` and calls again.
    """
    n = loose.shape[0]
    d = boxes.shape[1] // 2
    max_cells = max_cells_of(d)
    size = 64
    while size < 2 * n:
        size *= 2
    mask = size - 1
    inv = 1.0 / cell
    big = np.zeros(n, np.bool_)
    start = np.zeros(size + 1, np.int64)
    mine = np.empty(max_cells, np.int64)
    # every loose piece goes in the grid, even one of a body that does not move (asleep,
    # kinematic at rest): an active body may run into it
    for i in range(n):
        used = _buckets(boxes, loose[i], inv, mask, max_cells, mine)
        if used < 0:
            big[i] = True
        for k in range(used):
            start[mine[k] + 1] += 1
    for h in range(size):
        start[h + 1] += start[h]
    fill = start[:-1].copy()
    entries = np.empty(start[size], np.int64)
    for i in range(n):
        for k in range(_buckets(boxes, loose[i], inv, mask, max_cells, mine)):
            h = mine[k]
            entries[fill[h]] = loose[i]
            fill[h] += 1
    count = 0
    capacity = pairs.shape[0]
    for h in range(size):
        for i in range(start[h], start[h + 1]):
            a = entries[i]
            for j in range(i + 1, start[h + 1]):
                b = entries[j]
                if not wanted_pair(piece_body, active, dynamic, a, b):
                    continue
                if not overlap(boxes, a, boxes[b]):
                    continue
                # report from the bucket of the overlap's lowest cell only
                cx = math.floor(max(boxes[a, 0], boxes[b, 0]) * inv)
                cy = math.floor(max(boxes[a, 1], boxes[b, 1]) * inv)
                cz = math.floor(max(boxes[a, 2], boxes[b, 2]) * inv) if d == 3 else 0
                if _bucket(cx, cy, cz, mask) != h:
                    continue
                count = _put(pairs, count, capacity, a, b)
    for i in range(n):
        if not big[i]:
            continue
        a = loose[i]
        for j in range(n):
            if j == i or (big[j] and j < i):
                continue  # two big pieces: once
            b = loose[j]
            if wanted_pair(piece_body, active, dynamic, a, b) and overlap(boxes, a, boxes[b]):
                count = _put(pairs, count, capacity, a, b)
    # the pieces in the tree (none dynamic), met by the loose pieces of dynamic bodies
    hits = np.empty(64, np.int64)
    for i in range(n):
        a = loose[i]
        if not dynamic[piece_body[a]]:
            continue
        found = query_bvh(
            tree_box, tree_left, tree_first, tree_count, tree_order, boxes, boxes[a], hits
        )
        if found > hits.shape[0]:  # more than fit: walk again into room enough
            hits = np.empty(2 * found, np.int64)
            found = query_bvh(
                tree_box, tree_left, tree_first, tree_count, tree_order, boxes, boxes[a], hits
            )
        for k in range(found):
            if wanted_pair(piece_body, active, dynamic, a, hits[k]):
                count = _put(pairs, count, capacity, a, hits[k])
    if count > capacity:
        return -count
    _sort_pairs(pairs, count, boxes.shape[0])
    return count


@njit(cache=True, inline="always")
def _put(pairs: np.ndarray, count: int, capacity: int, a: int, b: int) -> int:
    """Write the pair (a, b), lower piece first, if it fits; return the new count."""
    if count < capacity:
        pairs[count, 0] = min(a, b)
        pairs[count, 1] = max(a, b)
    return count + 1


@njit(cache=True)
def _sort_pairs(pairs: np.ndarray, count: int, n: int) -> None:
    """Sort ``pairs[:count]`` (each ``a < b``, distinct, pieces below ``n``) by ``(a, b)``,
    in O(count log count) whatever ``n``."""
    keys = np.empty(count, np.int64)
    for k in range(count):
        keys[k] = pairs[k, 0] * n + pairs[k, 1]
    keys.sort()
    for k in range(count):
        pairs[k, 0] = keys[k] // n
        pairs[k, 1] = keys[k] % n


@njit(cache=True)
def refit(boxes: np.ndarray, fat: np.ndarray, piece_reach: np.ndarray, which: np.ndarray) -> int:
    """Give each piece of ``which`` whose swept box is not inside its fat box a new one;
    return how many.

    Parameters
    ----------
    boxes : (P, 2 d) float64
        Swept boxes [m], lower corner then upper, in d = 2 or 3 dimensions
        (:func:`carom.engines.rigid.broadphase.piece_boxes`, its 3D twin).
    fat : (P, 2 d) float64
        Fat boxes [m], updated; an empty box (lower corner above the upper) is refitted.
    piece_reach : (P,) float64
        Each piece's reach from its body's centre [m]; the new fat box is the swept box
        grown by ``FAT`` times it on every side.
    which : (M,) int64
        The pieces to look at (those that may move).
    """
    d = boxes.shape[1] // 2
    moved = 0
    for p in which:
        inside = True
        for k in range(d):
            if boxes[p, k] < fat[p, k] or boxes[p, d + k] > fat[p, d + k]:
                inside = False
        if inside:
            continue
        grow = FAT * piece_reach[p]
        for k in range(d):
            fat[p, k] = boxes[p, k] - grow
            fat[p, d + k] = boxes[p, d + k] + grow
        moved += 1
    return moved


@njit(cache=True)
def select_pairs(
    candidates: np.ndarray,
    n_candidates: int,
    boxes: np.ndarray,
    piece_body: np.ndarray,
    active: np.ndarray,
    dynamic: np.ndarray,
    pairs: np.ndarray,
) -> int:
    """The ``candidates`` (sorted pairs of overlapping fat boxes) whose swept ``boxes``
    (P, 2 d) overlap and that :func:`find_pairs` would want (two bodies, one ``active``, one
    ``dynamic``), in order, into ``pairs`` (at least ``n_candidates`` rows); return how many.
    """
    count = 0
    for k in range(n_candidates):
        a = candidates[k, 0]
        b = candidates[k, 1]
        if wanted_pair(piece_body, active, dynamic, a, b) and overlap(boxes, a, boxes[b]):
            pairs[count, 0] = a
            pairs[count, 1] = b
            count += 1
    return count


class KeptPairs:
    """The candidate pairs of a rigid engine (2D or 3D), kept from step to step through fat
    boxes (module docstring): both engines' stage 2.

    Parameters
    ----------
    pieces, dims, bodies : int
        How many pieces, in how many dimensions (2 or 3), of how many bodies.
    find : callable
        ``find(boxes, active, out)``: :func:`find_pairs` for these pieces, into ``out``
        (K, 2) int64; the count, or minus the count needed when ``out`` is too small.
    """

    def __init__(
        self,
        pieces: int,
        dims: int,
        bodies: int,
        find: Callable[[np.ndarray, np.ndarray, np.ndarray], int],
    ) -> None:
        # fat boxes (empty: refitted at the first step) and the pairs of those that overlap
        self.fat = np.zeros((pieces, 2 * dims))
        self.fat[:, :dims] = np.inf
        self.fat[:, dims:] = -np.inf
        #: the pieces that may move (all of them unless :meth:`settle` says otherwise)
        self.loose = np.arange(pieces, dtype=np.int64)
        #: the pairs of the last :meth:`update`, (K, 2) int64, in its first rows
        self.pairs = np.zeros((max(64, 4 * bodies), 2), np.int64)
        self._find = find
        self._fat_pairs = np.zeros((max(64, 4 * bodies), 2), np.int64)
        self._n_fat = -1  # how many fat pairs; -1: they are not those of the fat boxes now
        self._busy = True  # a piece left its fat box at the last step
        self._everyone = np.ones(bodies, np.bool_)

    def settle(self, boxes: np.ndarray, still: np.ndarray) -> None:
        """The pieces ``still`` (indices) never move: their fat boxes are their ``boxes``
        (P, 2 d) themselves, never refitted (grown by a reach measured from their body's
        centre, a terrain's far triangles would get boxes tens of metres wide); the other
        pieces stay :attr:`loose`."""
        self.fat[still] = boxes[still]
        keep = np.ones(self.fat.shape[0], np.bool_)
        keep[still] = False
        self.loose = np.flatnonzero(keep).astype(np.int64)

    def update(
        self,
        boxes: np.ndarray,
        piece_reach: np.ndarray,
        piece_body: np.ndarray,
        moving: np.ndarray,
        dynamic: np.ndarray,
    ) -> int:
        """The pairs of swept ``boxes`` that overlap, into :attr:`pairs`; return how many.

        The pairs of overlapping fat boxes are made again only when a piece left its fat box;
        while pieces leave theirs step after step (a tumbler), the swept boxes are paired
        directly, which costs less than pairing the fat boxes and choosing among them. Both
        give the pairs ``find`` gives for ``boxes`` (two bodies, one ``moving``, one
        ``dynamic``), in the same order.
        """
        moved = refit(boxes, self.fat, piece_reach, self.loose)
        busy, self._busy = self._busy, moved > 0
        if moved:
            self._n_fat = -1
            if busy:
                count, self.pairs = self._grown(boxes, moving, self.pairs)
                return count
        if self._n_fat < 0:
            self._n_fat, self._fat_pairs = self._grown(self.fat, self._everyone, self._fat_pairs)
        if self.pairs.shape[0] < self._n_fat:
            self.pairs = np.zeros_like(self._fat_pairs)
        return int(
            select_pairs(
                self._fat_pairs, self._n_fat, boxes, piece_body, moving, dynamic, self.pairs
            )
        )

    def _grown(
        self, boxes: np.ndarray, active: np.ndarray, out: np.ndarray
    ) -> tuple[int, np.ndarray]:
        """``find`` into ``out``, grown until they fit: the count and the array."""
        while True:
            count = int(self._find(boxes, active, out))
            if count >= 0:
                return count, out
            out = np.zeros((2 * -count, 2), np.int64)
