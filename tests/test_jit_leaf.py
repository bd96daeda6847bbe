"""Leaf kernels (:func:`carom.jit.leaf`): compiled without Numba's reference counting, they
compute what the same function compiled with it computes, hold no reference to the arrays
they are given, and a function that would allocate an array is refused, not miscompiled."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from numba import njit
from numba.core.errors import NumbaError

from carom.jit import leaf
from tests.conftest import JIT_DISABLED


def _pair_test(boxes: np.ndarray, body: np.ndarray, i: int, j: int) -> bool:
    """The broad phase's kind of helper: arrays in, a branch, a bool out."""
    if body[i] == body[j]:
        return False
    return bool(boxes[i, 0] <= boxes[j, 2] and boxes[j, 0] <= boxes[i, 2])


def _count(test, boxes: np.ndarray, body: np.ndarray) -> int:  # type: ignore[no-untyped-def]
    return int(sum(test(boxes, body, i, j) for i in range(len(body)) for j in range(len(body))))


def test_a_leaf_computes_what_the_counted_function_computes_and_keeps_no_reference() -> None:
    rng = np.random.default_rng(3)
    lo = rng.uniform(0.0, 5.0, (40, 2))
    boxes = np.hstack([lo, lo + 0.7])
    body = rng.integers(0, 30, 40)
    counted, bare = njit(_pair_test), leaf(_pair_test)
    before = sys.getrefcount(boxes), sys.getrefcount(body)
    assert _count(bare, boxes, body) == _count(counted, boxes, body) > 0
    assert (sys.getrefcount(boxes), sys.getrefcount(body)) == before


@pytest.mark.skipif(JIT_DISABLED, reason="without the JIT a leaf is plain Python")
def test_a_leaf_that_would_allocate_is_refused_when_compiled() -> None:
    def doubled(a: np.ndarray) -> float:
        b = np.empty_like(a)  # an allocation: needs Numba's runtime
        b[:] = 2.0 * a
        return float(b.sum())

    # (Numba refuses it while typing the allocation, or lowering it: either names why)
    with pytest.raises(NumbaError, match=r"NRT required|Only accept returning of array passed"):
        leaf(doubled)(np.ones(3))
