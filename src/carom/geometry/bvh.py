"""A bounding volume tree over boxes that do not move (a static mesh's triangles, the static
pieces of a rigid world): which of them a box may touch.

Built once, in O(T log T): the boxes' centres are put in Morton order (their cells' bits
interleaved, one sort), and the tree halves that order, range by range, down to leaves of at
most :data:`LEAF` boxes; each node's box is then the union of its children's (a linear bounding
volume hierarchy, as Karras 2012 and parry's static trees; binary, axis-aligned). Queried every
step (Numba): a stack walk that descends only into nodes whose box overlaps the query box, so a
body on a large terrain meets O(log T) nodes, not T triangles.

Boxes come in the broad phase's layout: lower corner then upper, ``(T, 2 d)`` with d = 2 or 3.
Node k has a box ``box[k]`` (2 d,); an inner node's children are ``left[k]`` and
``left[k] + 1`` (``count[k] == 0``); a leaf holds ``order[first[k] : first[k] + count[k]]``
(the boxes' indices). Node 0 is the root. Every box must be finite (a plane's is not: keep
it out).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray

from carom.geometry.rays import ray_box
from carom.jit import leaf

__all__ = [
    "LEAF",
    "STACK",
    "Bvh",
    "build_bvh",
    "empty_bvh",
    "is_empty",
    "query_bvh",
    "ray_candidates",
    "ray_query_bvh",
]

#: boxes in a leaf at most
LEAF = 4
#: nodes a walk keeps waiting at most: a tree's depth is about log2(T / LEAF), under 64 for any
#: number of boxes a machine holds
STACK = 128

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class Bvh:
    """A tree over boxes (module docstring for the layout).

    Attributes
    ----------
    box : (K, 2 d) float64
        Each node's box [m], lower corner then upper.
    left, first, count : (K,) int64
        An inner node's first child; a leaf's first entry in ``order`` and its size.
    order : (T,) int64
        The boxes' indices, leaf by leaf.
    """

    box: FloatArray
    left: IntArray
    first: IntArray
    count: IntArray
    order: IntArray


def empty_bvh(dims: int) -> Bvh:
    """A tree over no box, in ``dims`` dimensions."""
    return Bvh(
        np.zeros((1, 2 * dims)),
        np.zeros(1, np.int64),
        np.zeros(1, np.int64),
        np.zeros(1, np.int64),
        np.zeros(0, np.int64),
    )


def build_bvh(boxes: FloatArray, which: IntArray | None = None) -> Bvh:
    """The tree over ``boxes[which]`` (all of them by default); its ``order`` holds indices
    into ``boxes``. Deterministic: boxes whose centres share a Morton cell keep the order of
    ``which``.

    Parameters
    ----------
    boxes : (T, 2 d) float64
        Lower corner then upper [m], d = 2 or 3; the chosen ones finite.
    which : (M,) int64, optional
        The boxes to put in the tree.
    """
    b = np.ascontiguousarray(boxes, dtype=np.float64)
    d = b.shape[1] // 2
    items = np.arange(b.shape[0], dtype=np.int64) if which is None else np.asarray(which, np.int64)
    if items.size == 0:
        return empty_bvh(d)
    if not np.all(np.isfinite(b[items])):
        raise ValueError("a tree's boxes must be finite (an unbounded plane is kept out)")
    centre = 0.5 * (b[items, :d] + b[items, d:])
    low, high = centre.min(axis=0), centre.max(axis=0)
    span = np.where(high > low, high - low, 1.0)
    bits = 21 if d == 3 else 31
    cell = np.minimum(((centre - low) / span * (2**bits - 1)).astype(np.int64), 2**bits - 1)
    code = _morton(cell, bits)
    order = items[np.argsort(code, kind="stable")]
    capacity = max(1, 2 * items.size)
    node_box = np.zeros((capacity, 2 * d))
    left = np.zeros(capacity, np.int64)
    first = np.zeros(capacity, np.int64)
    count = np.zeros(capacity, np.int64)
    used = _build(b, order, node_box, left, first, count)
    return Bvh(node_box[:used], left[:used], first[:used], count[:used], order)


def _morton(cell: IntArray, bits: int) -> IntArray:
    """Each row's cell (M, d) coordinates of ``bits`` bits, interleaved into one code."""
    d = cell.shape[1]
    code = np.zeros(cell.shape[0], np.int64)
    for bit in range(bits):
        for axis in range(d):
            code |= ((cell[:, axis] >> bit) & 1) << (bit * d + axis)
    return code


@njit(cache=True)
def _build(
    boxes: np.ndarray,
    order: np.ndarray,
    node_box: np.ndarray,
    left: np.ndarray,
    first: np.ndarray,
    count: np.ndarray,
) -> int:
    """Halve ``order``'s range node by node down to leaves of at most LEAF, then give each
    node the union of its boxes (children come after their parent: a backward sweep);
    return how many nodes."""
    d = boxes.shape[1] // 2
    stack = np.empty((STACK, 3), np.int64)  # node, first, count; depth log2(T / LEAF) + 1
    stack[0, 0], stack[0, 1], stack[0, 2] = 0, 0, order.shape[0]
    top = 1
    used = 1
    while top > 0:
        top -= 1
        node, start, size = stack[top, 0], stack[top, 1], stack[top, 2]
        if size <= LEAF:
            first[node] = start
            count[node] = size
            continue
        half = size // 2
        left[node] = used
        used += 2
        stack[top, 0], stack[top, 1], stack[top, 2] = left[node] + 1, start + half, size - half
        stack[top + 1, 0], stack[top + 1, 1], stack[top + 1, 2] = left[node], start, half
        top += 2
    for node in range(used - 1, -1, -1):
        for k in range(d):
            node_box[node, k] = np.inf
            node_box[node, d + k] = -np.inf
        if count[node] > 0:
            for i in range(first[node], first[node] + count[node]):
                item = order[i]
                for k in range(d):
                    node_box[node, k] = min(node_box[node, k], boxes[item, k])
                    node_box[node, d + k] = max(node_box[node, d + k], boxes[item, d + k])
        else:
            for child in (left[node], left[node] + 1):
                for k in range(d):
                    node_box[node, k] = min(node_box[node, k], node_box[child, k])
                    node_box[node, d + k] = max(node_box[node, d + k], node_box[child, d + k])
    return used


@leaf
def query_bvh(
    node_box: np.ndarray, left: np.ndarray, first: np.ndarray, count: np.ndarray,
    order: np.ndarray, boxes: np.ndarray, query: np.ndarray, out: np.ndarray,
    stack: np.ndarray,
) -> int:  # fmt: skip
    """The boxes of ``boxes`` (T, 2 d) in the tree that overlap the box ``query`` (2 d,)
    [m] (touching counts), into ``out``, in the tree's order; ``stack`` (:data:`STACK`,)
    int64 is the walk's scratch (the caller's: this allocates nothing, so a loop of queries
    keeps no reference counts).

    Returns
    -------
    int
        How many there are; when more than ``out`` holds, only the first ones are written
        (the caller grows ``out`` and asks again).
    """
    stack[0] = 0
    top = 1
    found = 0
    while top > 0:
        top -= 1
        node = stack[top]
        if count[node] == 0 and left[node] == 0:
            continue  # an empty tree's root
        if not overlap(node_box, node, query):
            continue
        if count[node] > 0:
            for k in range(first[node], first[node] + count[node]):
                item = order[k]
                if not overlap(boxes, item, query):
                    continue
                if found < out.shape[0]:
                    out[found] = item
                found += 1
            continue
        stack[top] = left[node] + 1
        stack[top + 1] = left[node]
        top += 2
    return found


@njit(cache=True)
def ray_query_bvh(
    node_box: np.ndarray, left: np.ndarray, first: np.ndarray, count: np.ndarray,
    order: np.ndarray, boxes: np.ndarray, o: np.ndarray, inv: np.ndarray, t_max: float,
    out: np.ndarray, start: int,
) -> int:  # fmt: skip
    """The boxes of ``boxes`` (T, 2 d) in the tree that the ray from ``o`` (d,) with inverse
    direction ``inv`` (d,) meets within ``[0, t_max]`` [m] (:func:`carom.geometry.rays.ray_box`),
    into ``out`` from ``start``; returns where they end (past ``out``'s size: grow it and ask
    again)."""
    stack = np.empty(STACK, np.int64)
    stack[0] = 0
    top = 1
    found = start
    while top > 0:
        top -= 1
        node = stack[top]
        if node == 0 and is_empty(count, left):
            continue
        if not ray_box(o, inv, node_box[node], t_max):
            continue
        if count[node] > 0:
            for k in range(first[node], first[node] + count[node]):
                item = order[k]
                if not ray_box(o, inv, boxes[item], t_max):
                    continue
                if found < out.shape[0]:
                    out[found] = item
                found += 1
            continue
        stack[top] = left[node] + 1
        stack[top + 1] = left[node]
        top += 2
    return found


@njit(cache=True)
def ray_candidates(
    statics: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
    movers: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
                  np.ndarray],
    o: np.ndarray, inv: np.ndarray, t_max: float, found: np.ndarray,
) -> tuple[np.ndarray, int]:  # fmt: skip
    """The pieces whose boxes a ray (``o``, inverse direction ``inv``, up to ``t_max``) meets
    in two trees: ``statics`` (node boxes, left, first, count, order, the items' boxes, the
    items being pieces) and ``movers`` (the same over boxes of its own, then the piece of each
    of those boxes; an empty tree is skipped). Returns ``found`` (grown if need be) and how
    many pieces it holds."""
    s_box, s_left, s_first, s_count, s_order, s_boxes = statics
    m_box, m_left, m_first, m_count, m_order, m_boxes, m_pieces = movers
    while True:
        k = ray_query_bvh(s_box, s_left, s_first, s_count, s_order, s_boxes, o, inv, t_max,
                          found, 0)  # fmt: skip
        total = k
        if not is_empty(m_count, m_left):
            total = ray_query_bvh(m_box, m_left, m_first, m_count, m_order, m_boxes, o, inv,
                                  t_max, found, k)  # fmt: skip
        if total <= found.shape[0]:
            for j in range(k, total):
                found[j] = m_pieces[found[j]]
            return found, total
        found = np.empty(2 * total, np.int64)


@njit(cache=True, inline="always")
def ray_candidate(
    j: int, found: np.ndarray, k: int, open_pieces: np.ndarray, boxes: np.ndarray,
    pieces: np.ndarray, o: np.ndarray, inv: np.ndarray, t_max: float,
) -> int:  # fmt: skip
    """Candidate ``j`` of a ray: the ``k`` pieces :func:`ray_candidates` ``found``, then the
    ``open_pieces`` (no finite box), then ``pieces`` one by one whose ``boxes`` the ray meets
    within ``t_max`` (-1 for one it misses)."""
    if j < k:
        piece: int = found[j]
        return piece
    j -= k
    if j < open_pieces.shape[0]:
        piece = open_pieces[j]
        return piece
    j -= open_pieces.shape[0]
    if not ray_box(o, inv, boxes[j], t_max):
        return -1
    piece = pieces[j]
    return piece


@njit(cache=True, inline="always")
def is_empty(count: np.ndarray, left: np.ndarray) -> bool:
    """Whether a tree (its nodes' ``count`` and ``left``) holds no box."""
    empty: bool = count[0] == 0 and left[0] == 0
    return empty


@njit(cache=True, inline="always")
def overlap(boxes: np.ndarray, i: int, query: np.ndarray) -> bool:
    """Whether box ``i`` of ``boxes`` (·, 2 d) and ``query`` (2 d,) overlap (touching
    counts)."""
    d = boxes.shape[1] // 2
    meet = True
    for k in range(d):
        meet = meet and boxes[i, k] <= query[d + k] and query[k] <= boxes[i, d + k]
    return meet
