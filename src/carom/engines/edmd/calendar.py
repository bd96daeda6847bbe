"""An event calendar: O(1) scheduling of one event per body (after Paul, JCP 221, 615, 2007).

Time is cut into ``B`` buckets of width ``w`` from ``base``; a body's event at time ``t`` goes
to bucket ``floor((t - base) / w)`` (an unsorted doubly linked list), or, if that is past the
last bucket, to an overflow list. Only the current bucket is kept ordered, in a small binary
heap on ``(time, body)``; when it empties, the next non-empty bucket is poured into it. When
the last bucket is passed, a new "year" starts at the earliest overflow event and the
overflow is shared out again, with the bucket width re-estimated from the year's event rate.

Bucket index is monotone in time and equal times share a bucket, so the top is always the
minimum of ``(time, body)`` over all events: the same order, bit for bit, as a single heap.
Events at infinite time (none to come) are kept nowhere.

Arrays (all in :class:`carom.engines.edmd.state.State`; the kernels take them as one tuple,
``Calendar``, in this order):

``cal_head`` (B + 1,) int32, first body of each bucket (index B: overflow), -1 if empty;
``cal_next``, ``cal_prev`` (N,) int32 the lists; ``cal_loc`` (N,) int32 where each body's
event is: a bucket, ``IN_HEAP``, or ``NOWHERE``; ``cur_heap`` (N,) int32, ``cur_key`` (N,)
float64 and ``cur_where`` (N,) int32 the current bucket's heap and each body's node in it;
``cal_f`` (2,) float64 ``[base, width]``; ``cal_i`` (4,) int64 ``[current bucket, heap size,
events in the calendar, events popped this year]``.

In the engine ``cal_next``, ``cal_prev``, ``cal_loc`` and ``cur_where`` are the columns
``CAL_NEXT`` .. ``CAL_WHERE`` of one (N, 4) int32 array (``State.cal_body``,
:func:`calendar_views`): a body's four are then one 16-byte record, one cache line where
four arrays took four. At large N each is a miss, and pouring a bucket, filing an event or
taking one out reads them body by body along a bucket's list.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.edmd.jitflags import njit_inlined

IN_HEAP = -1
NOWHERE = -2

# columns of ``State.cal_body``: a body's calendar record (module docstring)
CAL_NEXT = 0
CAL_PREV = 1
CAL_LOC = 2
CAL_WHERE = 3
CAL_WIDTH = 4
#: what a record holds with no event filed (no list neighbours, filed nowhere, heap node 0)
CAL_EMPTY = (-1, -1, NOWHERE, 0)

F_BASE = 0
F_WIDTH = 1
I_CUR = 0
I_SIZE = 1
I_COUNT = 2
I_POPPED = 3

# the width aims at about this many events per bucket: fewer pours of a bucket into the heap,
# against a deeper heap (interleaved A/B against 2: 8 was 1.03 to 1.05x faster at 1e3 and 1e4
# bodies, 1.01 to 1.02x at 1e5 and 1e6; 4 and 16 gained less)
EVENTS_PER_BUCKET = 8.0

# The calendar's arrays, in this order, as one tuple (module docstring); a tuple costs nothing
# in the inlined functions and keeps every call to one argument.
Calendar = tuple[
    np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    np.ndarray,
]  # fmt: skip


@njit(cache=True, error_model="numpy", inline="always")
def calendar_views(cal_body: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``cal_next``, ``cal_prev``, ``cal_loc`` and ``cur_where``, (N,) each: the columns of
    the records ``cal_body`` (N, 4) int32 (in Python or in compiled code: the same views)."""
    return (
        cal_body[:, CAL_NEXT],
        cal_body[:, CAL_PREV],
        cal_body[:, CAL_LOC],
        cal_body[:, CAL_WHERE],
    )


@njit_inlined
def _before(key_a: float, body_a: int, key_b: float, body_b: int) -> bool:
    return key_a < key_b or (key_a == key_b and body_a < body_b)


@njit_inlined
def _place(
    heap: np.ndarray, key: np.ndarray, where: np.ndarray, k: int, body: int, t: float
) -> None:
    heap[k] = body
    key[k] = t
    where[body] = k


@njit_inlined
def _sift_up(
    heap: np.ndarray, key: np.ndarray, where: np.ndarray, k: int, body: int, t: float
) -> None:
    while k > 0:
        parent = (k - 1) >> 1
        if not _before(t, body, key[parent], heap[parent]):
            break
        _place(heap, key, where, k, heap[parent], key[parent])
        k = parent
    _place(heap, key, where, k, body, t)


@njit_inlined
def _sift_down(
    heap: np.ndarray, key: np.ndarray, where: np.ndarray, n: int, k: int, body: int, t: float
) -> None:
    while True:
        child = 2 * k + 1
        if child >= n:
            break
        right = child + 1
        if right < n and _before(key[right], heap[right], key[child], heap[child]):
            child = right
        if not _before(key[child], heap[child], t, body):
            break
        _place(heap, key, where, k, heap[child], key[child])
        k = child
    _place(heap, key, where, k, body, t)


@njit_inlined
def _bucket(t: float, cal_f: np.ndarray, cur: int, n_buckets: int) -> int:
    """Where an event at ``t`` goes: ``IN_HEAP`` (current bucket or earlier), a bucket, the
    overflow (``n_buckets``), or ``NOWHERE`` (t infinite)."""
    if math.isinf(t):
        return NOWHERE
    x = (t - cal_f[F_BASE]) / cal_f[F_WIDTH]
    if x >= n_buckets:
        return n_buckets
    k = math.floor(x)
    return IN_HEAP if k <= cur else k


@njit_inlined
def _insert(body: int, t: float, cal: Calendar) -> None:
    cal_head, cal_next, cal_prev, cal_loc, cur_heap, cur_key, cur_where, cal_f, cal_i = cal
    n_buckets = cal_head.shape[0] - 1
    loc = _bucket(t, cal_f, cal_i[I_CUR], n_buckets)
    cal_loc[body] = loc
    if loc == NOWHERE:
        return
    cal_i[I_COUNT] += 1
    if loc == IN_HEAP:
        n = cal_i[I_SIZE]
        cal_i[I_SIZE] = n + 1
        _sift_up(cur_heap, cur_key, cur_where, n, body, t)
        return
    first = cal_head[loc]
    cal_next[body] = first
    cal_prev[body] = -1
    if first >= 0:
        cal_prev[first] = body
    cal_head[loc] = body


@njit_inlined
def _remove(body: int, cal: Calendar) -> None:
    cal_head, cal_next, cal_prev, cal_loc, cur_heap, cur_key, cur_where, _cal_f, cal_i = cal
    loc = cal_loc[body]
    if loc == NOWHERE:
        return
    cal_loc[body] = NOWHERE
    cal_i[I_COUNT] -= 1
    if loc == IN_HEAP:
        k = cur_where[body]
        n = cal_i[I_SIZE] - 1
        cal_i[I_SIZE] = n
        if k == n:
            return
        last = cur_heap[n]
        t_last = cur_key[n]
        if k > 0 and _before(t_last, last, cur_key[(k - 1) >> 1], cur_heap[(k - 1) >> 1]):
            _sift_up(cur_heap, cur_key, cur_where, k, last, t_last)
        else:
            _sift_down(cur_heap, cur_key, cur_where, n, k, last, t_last)
        return
    nxt = cal_next[body]
    prv = cal_prev[body]
    if prv >= 0:
        cal_next[prv] = nxt
    else:
        cal_head[loc] = nxt
    if nxt >= 0:
        cal_prev[nxt] = prv


@njit_inlined
def calendar_update(keys: np.ndarray, body: int, cal: Calendar) -> None:
    """Re-file ``body`` after its event time ``keys[body]`` changed."""
    _remove(body, cal)
    _insert(body, keys[body], cal)


@njit(cache=True, error_model="numpy")
def _new_year(keys: np.ndarray, cal: Calendar) -> None:
    """Every bucket is spent: start a year at the earliest overflow event, with a width from
    the last year's event rate, and share the overflow out."""
    cal_head, cal_next, _cal_prev, cal_loc, _cur_heap, _cur_key, _cur_where, cal_f, cal_i = cal
    n_buckets = cal_head.shape[0] - 1
    t_min = math.inf
    body = cal_head[n_buckets]
    while body >= 0:
        t_min = min(t_min, keys[body])
        body = cal_next[body]
    span = n_buckets * cal_f[F_WIDTH]
    popped = cal_i[I_POPPED]
    if popped > 0:
        cal_f[F_WIDTH] = EVENTS_PER_BUCKET * span / popped
    cal_f[F_BASE] = t_min
    cal_i[I_CUR] = 0
    cal_i[I_POPPED] = 0
    body = cal_head[n_buckets]
    cal_head[n_buckets] = -1
    while body >= 0:
        following = cal_next[body]
        cal_loc[body] = NOWHERE
        cal_i[I_COUNT] -= 1
        _insert(body, keys[body], cal)
        body = following


@njit_inlined
def calendar_top(keys: np.ndarray, cal: Calendar) -> int:
    """The body with the earliest event (ties: lowest index), or -1 if no event is left."""
    cal_head, cal_next, _cal_prev, cal_loc, cur_heap, cur_key, cur_where, _cal_f, cal_i = cal
    n_buckets = cal_head.shape[0] - 1
    while cal_i[I_SIZE] == 0:
        if cal_i[I_COUNT] == 0:
            return -1
        cur = cal_i[I_CUR] + 1
        if cur >= n_buckets:
            _new_year(keys, cal)
            continue
        cal_i[I_CUR] = cur
        body = cal_head[cur]
        cal_head[cur] = -1
        while body >= 0:  # pour the bucket into the heap
            following = cal_next[body]
            cal_loc[body] = IN_HEAP
            n = cal_i[I_SIZE]
            cal_i[I_SIZE] = n + 1
            _sift_up(cur_heap, cur_key, cur_where, n, body, keys[body])
            body = following
    cal_i[I_POPPED] += 1
    return int(cur_heap[0])


@njit_inlined
def calendar_next(cal: Calendar, k: int) -> int:
    """A body whose event is likely among the next few after the top's, or -1: the heap's
    node ``k`` (1 or 2, the top's children) if the heap has one, else the first body filed in
    the ``k``-th bucket after the current one. Only a hint, for prefetching: nothing is
    changed."""
    cal_head, _cal_next, _cal_prev, _cal_loc, cur_heap, _cur_key, _cur_where, _cal_f, cal_i = cal
    if k < cal_i[I_SIZE]:
        return int(cur_heap[k])
    following = cal_i[I_CUR] + k
    if following < cal_head.shape[0] - 1:
        return int(cal_head[following])
    return -1


def calendar_build(keys: np.ndarray, cal: Calendar) -> None:
    """File every body's event (``keys`` (N,) [s], infinite for none); the first year starts
    at the earliest event, with buckets as wide as ``EVENTS_PER_BUCKET`` times the mean spacing
    of the earliest half of the events.

    Plain NumPy picks the width (``np.partition`` finds the two order statistics in linear
    time, where compiling Numba's sort cost a cold start more than a second) and a kernel
    files the events. The width only sets how the events share the buckets: the order they
    come out in is that of a sort on (time, body) whatever it is.
    """
    cal_f = cal[7]
    finite = keys[np.isfinite(keys)]
    if finite.shape[0] == 0:
        cal_f[F_BASE] = 0.0
        cal_f[F_WIDTH] = 1.0
    else:
        half = max(1, finite.shape[0] // 2)
        ordered = np.partition(finite, (0, half - 1))  # the earliest and the half-th earliest
        spread = ordered[half - 1] - ordered[0]
        cal_f[F_BASE] = ordered[0]
        cal_f[F_WIDTH] = EVENTS_PER_BUCKET * spread / half if spread > 0.0 else 1.0
    _file_all(keys, cal)


@njit(cache=True, error_model="numpy")
def _file_all(keys: np.ndarray, cal: Calendar) -> None:
    """Empty the calendar, then file every body's event in a year starting at ``cal_f``'s
    base and width (an infinite time is filed nowhere)."""
    cal_head, _cal_next, _cal_prev, cal_loc, _cur_heap, _cur_key, _cur_where, _cal_f, cal_i = cal
    cal_head[:] = -1
    cal_i[:] = 0
    cal_loc[:] = NOWHERE
    for body in range(keys.shape[0]):
        _insert(body, keys[body], cal)
