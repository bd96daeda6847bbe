"""An indexed binary min-heap of event times: one entry per body (Marin, Risso & Cordero 1993).

``heap[k]`` is the body at node ``k``; ``where[i]`` is the node of body ``i``. Keys are the
bodies' event times; ties break on the body index, so the order of events never depends on
the history of the heap (same input, same output, bit for bit). Changing a body's key and
calling :func:`heap_update` restores the heap in O(log N).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", inline="always")
def _less(keys: np.ndarray, i: int, j: int) -> bool:
    ki = keys[i]
    kj = keys[j]
    return ki < kj or (ki == kj and i < j)


@njit(cache=True, error_model="numpy", inline="always")
def _sift_up(keys: np.ndarray, heap: np.ndarray, where: np.ndarray, k: int) -> None:
    body = heap[k]
    while k > 0:
        parent = (k - 1) >> 1
        other = heap[parent]
        if not _less(keys, body, other):
            break
        heap[k] = other
        where[other] = k
        k = parent
    heap[k] = body
    where[body] = k


@njit(cache=True, error_model="numpy", inline="always")
def _sift_down(keys: np.ndarray, heap: np.ndarray, where: np.ndarray, k: int) -> None:
    n = heap.shape[0]
    body = heap[k]
    while True:
        child = 2 * k + 1
        if child >= n:
            break
        right = child + 1
        if right < n and _less(keys, heap[right], heap[child]):
            child = right
        other = heap[child]
        if not _less(keys, other, body):
            break
        heap[k] = other
        where[other] = k
        k = child
    heap[k] = body
    where[body] = k


@njit(cache=True, error_model="numpy")
def heap_build(keys: np.ndarray, heap: np.ndarray, where: np.ndarray) -> None:
    """Fill ``heap`` and ``where`` with every body, ordered by ``keys`` (O(N))."""
    n = keys.shape[0]
    for i in range(n):
        heap[i] = i
        where[i] = i
    for k in range(n // 2 - 1, -1, -1):
        _sift_down(keys, heap, where, k)


@njit(cache=True, error_model="numpy", inline="always")
def heap_update(keys: np.ndarray, heap: np.ndarray, where: np.ndarray, body: int) -> None:
    """Restore the heap after ``keys[body]`` changed."""
    k = where[body]
    if k > 0 and _less(keys, body, heap[(k - 1) >> 1]):
        _sift_up(keys, heap, where, k)
    else:
        _sift_down(keys, heap, where, k)
