"""Kernels run over ranges of bodies on several threads at once, with the same bits as one.

A build's passes over every body (the neighbour scans, the first predictions, the overlap
check) write only the rows of the bodies they are given and read what no other range
writes, so a kernel compiled without the GIL (``nogil=True``) can take a range of bodies on
each of several Python threads: the result is the same whatever the number of ranges.
:func:`in_ranges` splits the bodies into contiguous ranges (bodies near in number are near in
space, so each thread reads its own part of memory), one for each of Numba's threads
(``numba.set_num_threads`` limits them), and one only below :data:`THREAD_BODIES` bodies or
without the JIT.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from typing import Any

import numba
from numba import config

#: bodies below which a pass runs on the calling thread alone (a thread's start costs about
#: what a pass over a few thousand bodies does)
THREAD_BODIES = 1 << 15


def range_count(n: int) -> int:
    """How many ranges :func:`in_ranges` splits ``n`` bodies into."""
    if config.DISABLE_JIT or n < THREAD_BODIES:  # type: ignore[attr-defined]
        return 1
    return min(numba.get_num_threads(), n // (THREAD_BODIES // 2))


def in_ranges(kernel: Callable[..., Any], n: int, *args: Any) -> list[Any]:
    """``kernel(lo, hi, *args)`` over contiguous ranges covering bodies ``0 .. n - 1``, at
    once on :func:`range_count` threads (this one takes the first range): its results in
    the order of the ranges. The first error raised by a range is raised here, after every
    range has ended."""
    parts = range_count(n)
    if parts == 1:
        return [kernel(0, n, *args)]
    bounds = [n * k // parts for k in range(parts + 1)]
    ranges = list(itertools.pairwise(bounds))
    with ThreadPoolExecutor(parts - 1) as pool:
        rest = [pool.submit(kernel, lo, hi, *args) for lo, hi in ranges[1:]]
        first = kernel(*ranges[0], *args)
        return [first, *(future.result() for future in rest)]
