"""A bounding volume tree over a static mesh's triangles: which triangles a box may touch.

Built once (NumPy) by splitting the triangles at the median of their boxes' centres along the
longest axis of the node's box, down to leaves of at most :data:`LEAF` triangles (a binary
tree of axis-aligned boxes, as parry's and Bullet's static trees). Queried every step (Numba):
a stack walk that descends only into nodes whose box overlaps the query box, so a body on a
large terrain meets O(log T) nodes, not T triangles.

Layout: node k has a box ``lo[k], hi[k]`` (3,); an inner node's children are ``left[k]`` and
``left[k] + 1`` (``count[k] == 0``); a leaf holds ``order[first[k] : first[k] + count[k]]``
(triangle indices). Node 0 is the root.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit
from numpy.typing import NDArray

__all__ = ["LEAF", "Bvh", "build_bvh", "query_bvh"]

#: triangles in a leaf at most
LEAF = 4

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


@dataclass(frozen=True)
class Bvh:
    """A tree over boxes (module docstring for the layout)."""

    lo: FloatArray
    hi: FloatArray
    left: IntArray
    first: IntArray
    count: IntArray
    order: IntArray


def build_bvh(lo: FloatArray, hi: FloatArray) -> Bvh:
    """The tree over the boxes ``lo``, ``hi`` (T, 3) [m] (e.g. each triangle's corners' min and
    max). Deterministic: ties in the median split keep the input order."""
    boxes_lo = np.asarray(lo, float)
    boxes_hi = np.asarray(hi, float)
    n = boxes_lo.shape[0]
    centres = 0.5 * (boxes_lo + boxes_hi)
    order = np.arange(n, dtype=np.int64)
    capacity = max(1, 2 * n)
    node_lo = np.zeros((capacity, 3))
    node_hi = np.zeros((capacity, 3))
    left = np.zeros(capacity, np.int64)
    first = np.zeros(capacity, np.int64)
    count = np.zeros(capacity, np.int64)
    used = 1
    stack = [(0, 0, n)]  # node, first, count
    while stack:
        node, start, size = stack.pop()
        members = order[start : start + size]
        node_lo[node] = boxes_lo[members].min(axis=0) if size else 0.0
        node_hi[node] = boxes_hi[members].max(axis=0) if size else 0.0
        if size <= LEAF:
            first[node] = start
            count[node] = size
            continue
        axis = int(np.argmax(node_hi[node] - node_lo[node]))
        ranked = members[np.argsort(centres[members, axis], kind="stable")]
        order[start : start + size] = ranked
        half = size // 2
        left[node] = used
        used += 2
        stack.append((left[node] + 1, start + half, size - half))
        stack.append((left[node], start, half))
    return Bvh(node_lo[:used], node_hi[:used], left[:used], first[:used], count[:used], order)


@njit(cache=True)
def query_bvh(
    lo: np.ndarray, hi: np.ndarray, left: np.ndarray, first: np.ndarray, count: np.ndarray,
    order: np.ndarray, item_lo: np.ndarray, item_hi: np.ndarray, box_lo: np.ndarray,
    box_hi: np.ndarray, out: np.ndarray,
) -> int:  # fmt: skip
    """The items (triangles) whose own boxes ``item_lo``, ``item_hi`` (T, 3) overlap the box
    ``box_lo``, ``box_hi`` (3,) [m], into ``out``, in the tree's order.

    Returns
    -------
    int
        How many there are; when more than ``out`` holds, only the first ones are written
        (the caller grows ``out`` and asks again).
    """
    stack = np.empty(64, np.int64)  # a median split's depth: log2(T/LEAF) + 1 < 64
    stack[0] = 0
    top = 1
    found = 0
    while top > 0:
        top -= 1
        node = stack[top]
        if _apart(lo[node], hi[node], box_lo, box_hi):
            continue
        if count[node] > 0 or left[node] == 0:
            for k in range(first[node], first[node] + count[node]):
                item = order[k]
                if _apart(item_lo[item], item_hi[item], box_lo, box_hi):
                    continue
                if found < out.shape[0]:
                    out[found] = item
                found += 1
            continue
        stack[top] = left[node] + 1
        stack[top + 1] = left[node]
        top += 2
    return found


@njit(cache=True, inline="always")
def _apart(a_lo: np.ndarray, a_hi: np.ndarray, b_lo: np.ndarray, b_hi: np.ndarray) -> bool:
    """Whether two boxes are apart along some axis (touching counts as overlapping)."""
    return bool(
        a_lo[0] > b_hi[0] or a_hi[0] < b_lo[0]
        or a_lo[1] > b_hi[1] or a_hi[1] < b_lo[1]
        or a_lo[2] > b_hi[2] or a_hi[2] < b_lo[2]
    )  # fmt: skip
