"""The event calendar hands out events in exactly the order of a sort on (time, body)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit

from carom.engines.edmd import calendar as calendar_kernels
from carom.engines.edmd.calendar import I_SIZE, Calendar, calendar_build


# the calendar's kernels run only inside compiled code (no entry point from Python:
# carom.engines.edmd.jitflags), as in the loop; these call them from there
@njit
def calendar_top(keys, cal):  # type: ignore[no-untyped-def]
    return calendar_kernels.calendar_top(keys, cal)


@njit
def calendar_update(keys, body, cal):  # type: ignore[no-untyped-def]
    calendar_kernels.calendar_update(keys, body, cal)


@njit
def calendar_next(cal, k):  # type: ignore[no-untyped-def]
    return calendar_kernels.calendar_next(cal, k)


def empty_calendar(n: int) -> Calendar:
    """A calendar for ``n`` bodies as the engine allocates it, before any event is filed
    (each body's links, place and heap node one record: ``State.cal_body``)."""
    records = np.empty((n, calendar_kernels.CAL_WIDTH), np.int32)
    records[:] = np.array(calendar_kernels.CAL_EMPTY, np.int32)
    cal_next, cal_prev, cal_loc, cur_where = calendar_kernels.calendar_views(records)
    return (
        np.full(n + 1, -1, np.int32),  # cal_head
        cal_next,
        cal_prev,
        cal_loc,
        np.zeros(n, np.int32),  # cur_heap
        np.full(n, np.inf),  # cur_key
        cur_where,
        np.array([0.0, 1.0]),  # cal_f
        np.zeros(4, np.int64),  # cal_i
    )


def _expected(keys: np.ndarray) -> int:
    """The reference: the body of least (time, body), or -1 when every time is infinite."""
    finite = np.flatnonzero(np.isfinite(keys))
    if finite.size == 0:
        return -1
    return int(finite[np.lexsort((finite, keys[finite]))[0]])


@pytest.mark.parametrize("seed", range(6))
def test_calendar_pops_in_time_then_body_order(seed: int) -> None:
    # Random schedules as the engine makes them: the earliest body gets a new time no earlier
    # than now, and a random other body too; times are drawn on scales that change by six
    # orders of magnitude (the bucket width must follow), with ties (equal times, settled
    # by body index), bodies with no event (inf), far-future events (the overflow and new
    # years) and stretches with every event gone.
    rng = np.random.default_rng(seed)
    n = int(rng.integers(1, 60))
    keys = rng.exponential(1.0, n)
    keys[rng.random(n) < 0.1] = np.inf
    keys[rng.random(n) < 0.2] = 0.5  # ties
    cal = empty_calendar(n)
    calendar_build(keys, cal)
    now = 0.0
    for step in range(3000):
        scale = 10.0 ** (6 * math.sin(step / 300.0) - 3)
        top = calendar_top(keys, cal)
        assert top == _expected(keys)
        if top < 0:  # nothing scheduled: schedule a few bodies again
            for body in rng.integers(0, n, 3):
                keys[body] = now + rng.exponential(scale)
                calendar_update(keys, int(body), cal)
            continue
        now = keys[top]
        draw = rng.random()
        if draw < 0.05:
            keys[top] = np.inf
        elif draw < 0.1:
            keys[top] = now  # an event at once (touching pairs)
        elif draw < 0.15:
            keys[top] = now + 1e4 * scale * n  # far beyond this year
        else:
            keys[top] = now + rng.exponential(scale)
        calendar_update(keys, top, cal)
        other = int(rng.integers(0, n))
        if math.isfinite(keys[other]) and rng.random() < 0.5:
            keys[other] = now + rng.exponential(scale)
            calendar_update(keys, other, cal)


def test_the_next_event_is_hinted_whenever_the_heap_holds_it() -> None:
    # calendar_next only guides prefetching (the loop reads the data of the bodies it names
    # early), so it must name real bodies or -1, and, when the current bucket's heap holds two
    # events or more, the event after the top is one of the top's two children.
    rng = np.random.default_rng(5)
    n = 200
    keys = rng.exponential(1.0, n)
    cal = empty_calendar(n)
    calendar_build(keys, cal)
    hinted = 0
    for _ in range(4000):
        top = calendar_top(keys, cal)
        hints = [calendar_next(cal, 1), calendar_next(cal, 2)]
        for b in hints:
            assert b == -1 or (0 <= b < n and b != top and np.isfinite(keys[b]))
        if cal[8][I_SIZE] >= 2:
            order = np.lexsort((np.arange(n), keys))
            assert int(order[1]) in hints
            hinted += 1
        keys[top] += rng.exponential(1.0)
        calendar_update(keys, top, cal)
    assert hinted > 1000  # the heap often holds two or more (8 events a bucket)
