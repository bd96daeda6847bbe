"""What both dimensions' contact stages share: finding last step's contact of a pair of
pieces, to warm start from it (Box2D's and Rapier's warm start)."""

from __future__ import annotations

import numpy as np
from numba import njit

__all__ = ["find_cached"]


@njit(cache=True, inline="always")
def find_cached(keys: np.ndarray, count: int, key: int, cursor: int) -> tuple[int, int]:
    """Row of ``key`` in the sorted ``keys[:count]`` (-1 if absent), searched from row
    ``cursor`` on, and where the next search may start.

    Keys asked for in increasing order (the pairs come sorted) walk the cache once in all:
    O(pairs + cache) per step, not a search per pair.
    """
    while cursor < count and keys[cursor] < key:
        cursor += 1
    row = cursor if cursor < count and keys[cursor] == key else -1
    return row, cursor
