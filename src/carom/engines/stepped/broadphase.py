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

The pairs are kept from step to step through *fat boxes* (each piece's swept box grown by
:data:`FAT` of its reach, as Box2D's enlarged boxes): the pairs of overlapping fat boxes are
kept, and each step takes from them the pairs whose swept boxes overlap (:func:`select_pairs`).
Every swept box lies in its fat box, so that is every pair :func:`find_pairs` would give, in the
same order; a resting stack never pairs again. When a piece leaves its fat box, it gets a new
one; a few such pieces are paired again one by one and the kept pairs mended
(:func:`repair_pairs`, as Box2D's move buffer), more and the grid is made again.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numba import njit

from carom.geometry.bvh import STACK, overlap, query_bvh
from carom.jit import leaf
from carom.laws.kinds import KIND_DYNAMIC

__all__ = [
    "FAT",
    "FEW",
    "KeptPairs",
    "find_pairs",
    "grid_cell",
    "max_cells_of",
    "refit",
    "repair_pairs",
    "select_pairs",
    "wanted_pair",
]

#: a fat box is a piece's swept box grown by this fraction of the piece's reach on each side
FAT = 0.1
#: at most this many pieces leaving their fat boxes in a step have their pairs mended one by
#: one (:func:`repair_pairs`, O(FEW L) against the L loose pieces, a few ns a test); more, and
#: the grid is made again (O(L): 0.5 us a piece on the game loop's pit of boxes)
FEW = 64


@njit(cache=True, inline="always")
def wanted_pair(
    piece_body: np.ndarray, active: np.ndarray, dynamic: np.ndarray, a: int, b: int
) -> bool:
    """A pair worth a manifold: two bodies, one of them active, one of them dynamic.

    Without branches: a helper taking arrays that branches keeps Numba's reference counts of
    them at every call (atomic, ~30 ns; measured: the grid's pair loop at 80 ns a pair), which
    one that does not lets LLVM drop (~2 ns)."""
    ba = piece_body[a]
    bb = piece_body[b]
    wanted: bool = (ba != bb) & (active[ba] | active[bb]) & (dynamic[ba] | dynamic[bb])
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
    if capacity == 0:
        return -1  # (_put needs a row: the caller grows pairs and asks again)
    for h in range(size):
        for i in range(start[h], start[h + 1]):
            a = entries[i]
            for j in range(i + 1, start[h + 1]):
                b = entries[j]
                if not overlap(boxes, a, boxes[b]):
                    continue
                if not wanted_pair(piece_body, active, dynamic, a, b):
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
            if overlap(boxes, a, boxes[b]) and wanted_pair(piece_body, active, dynamic, a, b):
                count = _put(pairs, count, capacity, a, b)
    # the pieces in the tree (none dynamic), met by the loose pieces of dynamic bodies
    hits = np.empty(64, np.int64)
    stack = np.empty(STACK, np.int64)
    for i in range(n):
        a = loose[i]
        if not dynamic[piece_body[a]]:
            continue
        found = query_bvh(
            tree_box, tree_left, tree_first, tree_count, tree_order, boxes, boxes[a], hits,
            stack,
        )  # fmt: skip
        if found > hits.shape[0]:  # more than fit: walk again into room enough
            hits = np.empty(2 * found, np.int64)
            found = query_bvh(
                tree_box, tree_left, tree_first, tree_count, tree_order, boxes, boxes[a],
                hits, stack,
            )  # fmt: skip
        for k in range(found):
            if wanted_pair(piece_body, active, dynamic, a, hits[k]):
                count = _put(pairs, count, capacity, a, hits[k])
    if count > capacity:
        return -count
    _sort_pairs(pairs, count, boxes.shape[0])
    return count


@njit(cache=True, inline="always")
def _put(pairs: np.ndarray, count: int, capacity: int, a: int, b: int) -> int:
    """Write the pair (a, b), lower piece first, into row ``count`` (into the last row when
    it does not fit: the caller, told the count, grows ``pairs`` and asks again); return the
    new count. Without a branch, so that Numba keeps no reference counts per pair
    (:func:`wanted_pair`)."""
    row = min(count, capacity - 1)
    pairs[row, 0] = min(a, b)
    pairs[row, 1] = max(a, b)
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


@leaf
def refit(
    boxes: np.ndarray, fat: np.ndarray, piece_reach: np.ndarray, which: np.ndarray,
    moved: np.ndarray,
) -> int:  # fmt: skip
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
    moved : (M,) int64
        Written: the pieces refitted, in the order of ``which``, in the first rows.
    """
    d = boxes.shape[1] // 2
    count = 0
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
        moved[count] = p
        count += 1
    return count


@leaf
def _moved_pairs(
    fat: np.ndarray,
    moved: np.ndarray,
    n_moved: int,
    again: np.ndarray,
    piece_body: np.ndarray,
    active: np.ndarray,
    dynamic: np.ndarray,
    loose: np.ndarray,
    tree: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    keys: np.ndarray,
    hits: np.ndarray,
    stack: np.ndarray,
) -> tuple[int, int]:
    """:func:`repair_pairs`'s new pairs, each moved piece's with the loose pieces and the
    tree's, as keys ``a P + b`` into ``keys`` (unsorted) while they fit, the tree's hits of a
    piece into ``hits`` (``stack``: the tree walk's scratch); returns how many pairs and the
    most hits of one piece (more than fit: the caller gives room and calls again). A leaf
    (:func:`carom.jit.leaf`): nothing is allocated or grown in the loop (measured: growing
    an array in it 3.5x slower). Its cost is its pair tests: ~12 ns a test (the game loop's
    pit of 100 boxes: 25 pieces leave their fat boxes a frame, 32 us a mend)."""
    pieces = fat.shape[0]
    node_box, left, first, count, order = tree
    found = 0
    most = 0
    for k in range(n_moved):
        a = moved[k]
        for b in loose:
            if (b == a) | (again[b] & (b < a)):
                continue  # (two moved pieces: paired once, from the lower)
            if overlap(fat, a, fat[b]) and wanted_pair(piece_body, active, dynamic, a, b):
                if found < keys.shape[0]:
                    keys[found] = min(a, b) * pieces + max(a, b)
                found += 1
        if not dynamic[piece_body[a]]:
            continue  # (a static tree piece pairs with dynamic pieces only)
        near = query_bvh(node_box, left, first, count, order, fat, fat[a], hits, stack)
        most = max(most, near)
        for j in range(min(near, hits.shape[0])):
            b = hits[j]
            if wanted_pair(piece_body, active, dynamic, a, b):
                if found < keys.shape[0]:
                    keys[found] = min(a, b) * pieces + max(a, b)
                found += 1
    return found, most


@njit(cache=True)
def repair_pairs(
    fat: np.ndarray,
    moved: np.ndarray,
    n_moved: int,
    piece_body: np.ndarray,
    active: np.ndarray,
    dynamic: np.ndarray,
    loose: np.ndarray,
    tree: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    old: np.ndarray,
    n_old: int,
    out: np.ndarray,
) -> int:
    """The pairs of overlapping ``fat`` boxes after the pieces ``moved[:n_moved]`` were given
    new ones, made from the pairs before (``old[:n_old]``, sorted): those of two pieces that
    kept their boxes stay, and each moved piece is paired again with every ``loose`` piece and
    the static ``tree``'s (node boxes, left, first, count, order; its items' boxes in
    ``fat``). The result, sorted by ``(a, b)``, is the set :func:`find_pairs` gives for
    ``fat`` with ``active`` bodies, so the same list; written into ``out`` (K, 2). Returns
    how many, or minus the rows needed when they do not fit. O(n_moved L + K): a game's few
    pushed bodies cost far less than pairing every box again.
    """
    pieces = fat.shape[0]
    again = np.zeros(pieces, np.bool_)
    for k in range(n_moved):
        again[moved[k]] = True
    keys = np.empty(max(16, 8 * n_moved), np.int64)
    hits = np.empty(64, np.int64)
    stack = np.empty(STACK, np.int64)
    found, most = _moved_pairs(
        fat, moved, n_moved, again, piece_body, active, dynamic, loose, tree, keys, hits, stack
    )
    if found > keys.shape[0] or most > hits.shape[0]:  # room enough, and again
        keys = np.empty(found, np.int64)
        hits = np.empty(most, np.int64)
        _moved_pairs(
            fat, moved, n_moved, again, piece_body, active, dynamic, loose, tree, keys, hits,
            stack,
        )  # fmt: skip
    new = np.sort(keys[:found])
    # merge the pairs kept (in order) with the new ones (in order)
    total = 0
    capacity = out.shape[0]
    if capacity == 0:
        return -1  # (as find_pairs)
    j = 0
    for k in range(n_old):
        a, b = old[k, 0], old[k, 1]
        if again[a] | again[b]:
            continue
        key = a * pieces + b
        while j < found and new[j] < key:
            total = _put(out, total, capacity, new[j] // pieces, new[j] % pieces)
            j += 1
        total = _put(out, total, capacity, a, b)
    for rest in range(j, found):  # (the new pairs after every kept one)
        total = _put(out, total, capacity, new[rest] // pieces, new[rest] % pieces)
    return total if total <= capacity else -total


@leaf
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
        if overlap(boxes, a, boxes[b]) and wanted_pair(piece_body, active, dynamic, a, b):
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
    repair : callable
        ``repair(fat, active, moved, n_moved, old, n_old, out)``: :func:`repair_pairs` for
        these pieces, likewise.
    """

    def __init__(
        self,
        pieces: int,
        dims: int,
        bodies: int,
        find: Callable[[np.ndarray, np.ndarray, np.ndarray], int],
        repair: Callable[
            [np.ndarray, np.ndarray, np.ndarray, int, np.ndarray, int, np.ndarray], int
        ],
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
        self._repair = repair
        self._fat_pairs = np.zeros((max(64, 4 * bodies), 2), np.int64)
        self._spare = np.zeros_like(self._fat_pairs)  # (the pairs repaired go here, then swap)
        self._n_fat = -1  # how many fat pairs; -1: they are not those of the fat boxes now
        self._busy = True  # more than FEW pieces left their fat boxes at the last step
        self._everyone = np.ones(bodies, np.bool_)
        self._moved = np.zeros(pieces, np.int64)

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

        When a few pieces (up to :data:`FEW`) left their fat boxes, the pairs of overlapping
        fat boxes are mended: those of the pieces that stayed are kept, the others paired
        again one by one (:func:`repair_pairs`; a game's pushed bodies). When more left, the
        fat pairs are made again from the grid; while more than that leave theirs step
        after step (a tumbler), the swept boxes are paired directly, which costs less than pairing
        the fat boxes and choosing among them. Every way gives the pairs ``find`` gives for
        ``boxes`` (two bodies, one ``moving``, one ``dynamic``), in the same order.
        """
        moved = int(refit(boxes, self.fat, piece_reach, self.loose, self._moved))
        if 0 < moved <= FEW and self._n_fat >= 0:
            self._mend(moved)
        elif moved:
            self._n_fat = -1
        busy, self._busy = self._busy, moved > FEW
        if busy and self._busy:
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

    def _mend(self, moved: int) -> None:
        """The fat pairs after the ``moved`` pieces in :attr:`_moved` got new fat boxes
        (:func:`repair_pairs`), into the spare array, which becomes the fat pairs."""
        old, n_old = self._fat_pairs, self._n_fat
        self._n_fat, self._fat_pairs = _filled(
            lambda out: self._repair(self.fat, self._everyone, self._moved, moved, old, n_old, out),
            self._spare,
        )
        self._spare = old

    def _grown(
        self, boxes: np.ndarray, active: np.ndarray, out: np.ndarray
    ) -> tuple[int, np.ndarray]:
        """``find`` into ``out``, grown until they fit: the count and the array."""
        return _filled(lambda rows: self._find(boxes, active, rows), out)


def _filled(fill: Callable[[np.ndarray], int], out: np.ndarray) -> tuple[int, np.ndarray]:
    """``fill(out)`` (the count of pairs written into ``out`` (K, 2), or minus the rows
    needed), ``out`` grown until they fit: the count and the array."""
    while True:
        count = int(fill(out))
        if count >= 0:
            return count, out
        out = np.zeros((2 * -count, 2), np.int64)
