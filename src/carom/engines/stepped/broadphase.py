"""What both dimensions' broad phase shares: which pairs of pieces are wanted, and the pairs
kept from step to step through fat boxes.

The grid of a dimension (:func:`carom.engines.rigid.broadphase.find_pairs`,
:func:`carom.engines.rigid3d.broadphase.find_pairs`) is rebuilt only when a piece leaves its
*fat box* (its swept box grown by :data:`FAT` of its reach, as Box2D's enlarged boxes): the
pairs of overlapping fat boxes are kept, and each step takes from them the pairs whose swept
boxes overlap (:func:`select_pairs`). Every swept box lies in its fat box, so that is every
pair ``find_pairs`` would give, in the same order; a resting stack never rebuilds.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numba import njit

__all__ = ["FAT", "KeptPairs", "refit", "select_pairs", "wanted_pair"]

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


@njit(cache=True)
def refit(boxes: np.ndarray, fat: np.ndarray, piece_reach: np.ndarray) -> int:
    """Give each piece whose swept box is not inside its fat box a new one; return how many.

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
    """
    d = boxes.shape[1] // 2
    moved = 0
    for p in range(boxes.shape[0]):
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


@njit(cache=True, inline="always")
def _overlap_any(boxes: np.ndarray, a: int, b: int) -> bool:
    """Whether boxes a and b (lower corner then upper, in any dimension) overlap."""
    d = boxes.shape[1] // 2
    overlap = True
    for k in range(d):
        overlap = overlap and boxes[a, k] <= boxes[b, d + k] and boxes[b, k] <= boxes[a, d + k]
    return overlap


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
        if wanted_pair(piece_body, active, dynamic, a, b) and _overlap_any(boxes, a, b):
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
        ``find(boxes, active, out)``: the dimension's ``find_pairs`` for these pieces, into
        ``out`` (K, 2) int64; the count, or minus the count needed when ``out`` is too small.
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
        #: the pairs of the last :meth:`update`, (K, 2) int64, in its first rows
        self.pairs = np.zeros((max(64, 4 * bodies), 2), np.int64)
        self._find = find
        self._fat_pairs = np.zeros((max(64, 4 * bodies), 2), np.int64)
        self._n_fat = -1  # how many fat pairs; -1: they are not those of the fat boxes now
        self._busy = True  # a piece left its fat box at the last step
        self._everyone = np.ones(bodies, np.bool_)

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
        moved = refit(boxes, self.fat, piece_reach)
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
