"""An indexed binary min-heap of event times: one entry per body (Marin, Risso & Cordero 1993).

``heap[k]`` is the body at node ``k`` and ``heap_key[k]`` its key (kept beside it, so that
sifting compares contiguous memory instead of looking each key up by body); ``where[i]`` is
the node of body ``i``. Keys are the bodies' event times; ties break on the body index, so
the order of events never depends on the history of the heap (same input, same output, bit
for bit). Changing a body's key and calling :func:`heap_update` restores the heap in O(log N).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", inline="always")
def _before(key_a: float, body_a: int, key_b: float, body_b: int) -> bool:
    return key_a < key_b or (key_a == key_b and body_a < body_b)


@njit(cache=True, error_model="numpy", inline="always")
def _sift_up(
    heap: np.ndarray, heap_key: np.ndarray, where: np.ndarray, k: int, body: int, key: float
) -> None:
    while k > 0:
        parent = (k - 1) >> 1
        other = heap[parent]
        other_key = heap_key[parent]
        if not _before(key, body, other_key, other):
            break
        heap[k] = other
        heap_key[k] = other_key
        where[other] = k
        k = parent
    heap[k] = body
    heap_key[k] = key
    where[body] = k


@njit(cache=True, error_model="numpy", inline="always")
def _sift_down(
    heap: np.ndarray, heap_key: np.ndarray, where: np.ndarray, k: int, body: int, key: float
) -> None:
    n = heap.shape[0]
    while True:
        child = 2 * k + 1
        if child >= n:
            break
        right = child + 1
        if right < n and _before(heap_key[right], heap[right], heap_key[child], heap[child]):
            child = right
        other = heap[child]
        other_key = heap_key[child]
        if not _before(other_key, other, key, body):
            break
        heap[k] = other
        heap_key[k] = other_key
        where[other] = k
        k = child
    heap[k] = body
    heap_key[k] = key
    where[body] = k


@njit(cache=True, error_model="numpy")
def heap_build(keys: np.ndarray, heap: np.ndarray, heap_key: np.ndarray, where: np.ndarray) -> None:
    """Fill the heap with every body, ordered by ``keys`` (O(N))."""
    n = keys.shape[0]
    for i in range(n):
        heap[i] = i
        heap_key[i] = keys[i]
        where[i] = i
    for k in range(n // 2 - 1, -1, -1):
        _sift_down(heap, heap_key, where, k, heap[k], heap_key[k])


@njit(cache=True, error_model="numpy", inline="always")
def heap_update(
    keys: np.ndarray, heap: np.ndarray, heap_key: np.ndarray, where: np.ndarray, body: int
) -> None:
    """Restore the heap after ``keys[body]`` changed."""
    k = where[body]
    key = keys[body]
    if k > 0:
        parent = (k - 1) >> 1
        if _before(key, body, heap_key[parent], heap[parent]):
            _sift_up(heap, heap_key, where, k, body, key)
            return
    _sift_down(heap, heap_key, where, k, body, key)
