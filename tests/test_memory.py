"""Giving freed memory back to the system (carom/_memory.py)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from carom._memory import release_free_memory


def _resident_mb() -> float:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS"):
            return int(line.split()[1]) / 1024
    raise AssertionError("no VmRSS")


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="needs Linux's /proc")
def test_freed_arrays_in_the_heap_are_given_back() -> None:
    # after a 24 MB block is freed, glibc serves blocks of up to that size from its heap, and
    # keeps their pages when they are freed in the middle of it (measured: freeing the 160 MB
    # below gives back nothing by itself); the call gives them back
    big = np.ones(3_000_000)
    del big
    blocks = [np.ones(500_000) for _ in range(40)]  # 40 x 4 MB, from the heap
    keep = np.ones(1000)  # (above them: the heap cannot shrink from its top)
    held = _resident_mb()
    del blocks
    if not release_free_memory():
        pytest.skip("not glibc: nothing to give back")
    # at least half of the 160 MB freed is given back (the rest: what else shares the heap)
    assert held - _resident_mb() > 80.0
    assert keep.sum() == 1000.0
