"""Contact events of the last step: pairs that began and ended touching, and hits.

After each step a rigid engine knows which pairs of bodies touch: the contacts of the step's
narrow phase with a point within the linear slop, and the pairs that met in an impact solved
exactly during the step (an impact between two steps touches for an instant; it counts as
touching in the step it happened). Against the last step's pairs this gives

- **begin**: pairs touching now that did not at the last step (the point and normal of the
  contact's deepest point; for a pair that met in an exact impact, the impact's);
- **end**: pairs that touched at the last step and do not now;
- **hit**: every exact impact and every solver contact that pushed, approaching at least the
  threshold [m/s]; its time, point, normal and approach speed.

Events name two bodies ``a < b`` (the caller's numbers; a wall of the world's box or a plane,
not one of the caller's bodies, is -1 and comes first) and the normal points from ``a`` to
``b``.
The arrays are NumPy structured arrays (:func:`event_dtypes`); the kernel reads the contact
rows once, so events cost a few microseconds a step.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from carom.engines.stepped.rows import FLAG_EXACT, I_BODY_A, I_BODY_B, I_COUNT, PointLayout

__all__ = [
    "ContactEvents",
    "EventArrays",
    "compare",
    "event_dtypes",
    "split_off",
    "step_events",
    "touches",
]


def event_dtypes(d: int) -> tuple[np.dtype[np.void], np.dtype[np.void], np.dtype[np.void]]:
    """The structured dtypes of ``begin``, ``end`` and ``hit`` events in ``d`` dimensions."""
    begin = np.dtype([("a", np.int64), ("b", np.int64), ("point", np.float64, (d,)),
                      ("normal", np.float64, (d,))])  # fmt: skip
    end = np.dtype([("a", np.int64), ("b", np.int64)])
    hit = np.dtype([("a", np.int64), ("b", np.int64), ("time", np.float64),
                    ("point", np.float64, (d,)), ("normal", np.float64, (d,)),
                    ("speed", np.float64)])  # fmt: skip
    return begin, end, hit


class EventArrays(NamedTuple):
    """One step's contact events: structured arrays (:func:`event_dtypes`)."""

    #: pairs that began touching: ``a``, ``b``, ``point`` (d,) [m], ``normal`` (d,) from a to b
    begin: NDArray[np.void]
    #: pairs that stopped touching: ``a``, ``b``
    end: NDArray[np.void]
    #: impacts at least the threshold: ``a``, ``b``, ``time`` [s], ``point``, ``normal``,
    #: ``speed`` [m/s] (the approach speed along the normal, positive)
    hit: NDArray[np.void]


@njit(cache=True)
def touches(
    cf: np.ndarray, ci: np.ndarray, nc: int, point0: int, point_floats: int, d: int,
    layout: tuple[int, int, int, int], flags: int, slop: float, threshold: float,
    log: np.ndarray, logged: int, number: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:  # fmt: skip
    """The pairs touching this step and its hits.

    ``cf``, ``ci``: the step's ``nc`` contact rows (their points from column ``point0``,
    ``point_floats`` each; ``layout``: a point's separation, normal relative speed, total
    normal impulse and position columns; the flags' column ``flags``); ``log``: the step's
    ``logged`` exact impacts (time into the step, A, B, ..., the normal in the last ``d``
    columns, the point after the impulse and speeds, as the dimension logs them); ``number``
    (N,): each engine row's caller number (-1: a wall or plane).

    Returns ``keys`` (k,) int64 (``a`` and ``b``, in ``number``'s terms plus one, as
    ``a * (N + 1) + b``), ``where`` (k, 2 d) their point and normal, and the hits as ``pairs``
    (h, 2), ``times`` (h,) (into the step), ``values`` (h, 2 d + 1) point, normal, speed.
    """
    sep_col, vrel_col, total_col, at_col = layout
    n = number.shape[0] + 1
    keys = np.empty(nc + logged, np.int64)
    where = np.empty((nc + logged, 2 * d))
    pairs = np.empty((nc + logged, 2), np.int64)
    times = np.empty(nc + logged)
    values = np.empty((nc + logged, 2 * d + 1))
    k = 0
    h = 0
    for m in range(nc):
        a = number[ci[m, I_BODY_A]]
        b = number[ci[m, I_BODY_B]]
        sign = 1.0 if a < b else -1.0  # the normal from a to b: the rows' is from B to A
        lo, hi = min(a, b), max(a, b)
        deepest = np.inf
        best = 0
        fastest = 0.0
        quick = -1
        for j in range(ci[m, I_COUNT]):
            o = point0 + j * point_floats
            if cf[m, o + sep_col] < deepest:
                deepest = cf[m, o + sep_col]
                best = o
            approach = -cf[m, o + vrel_col]
            exact = ci[m, flags] & FLAG_EXACT
            if not exact and cf[m, o + total_col] > 0.0 and approach > fastest:
                fastest = approach
                quick = o
        if deepest <= slop:
            keys[k] = (lo + 1) * n + (hi + 1)
            for c in range(d):
                where[k, c] = cf[m, best + at_col + c]
                where[k, d + c] = -sign * cf[m, c]
            k += 1
        if quick >= 0 and fastest >= threshold:
            pairs[h, 0], pairs[h, 1] = lo, hi
            times[h] = 0.0
            for c in range(d):
                values[h, c] = cf[m, quick + at_col + c]
                values[h, d + c] = -sign * cf[m, c]
            values[h, 2 * d] = fastest
            h += 1
    width = log.shape[1]
    for r in range(logged):
        a = number[int(log[r, 1])]
        b = number[int(log[r, 2])]
        sign = 1.0 if a < b else -1.0
        lo, hi = min(a, b), max(a, b)
        keys[k] = (lo + 1) * n + (hi + 1)
        for c in range(d):
            where[k, c] = log[r, 5 + d + c]
            where[k, d + c] = -sign * log[r, width - d + c]
        k += 1
        approach = -log[r, 3 + d]
        if approach >= threshold:
            pairs[h, 0], pairs[h, 1] = lo, hi
            times[h] = log[r, 0]
            for c in range(2 * d):
                values[h, c] = where[k - 1, c]
            values[h, 2 * d] = approach
            h += 1
    return keys[:k], where[:k], pairs[:h], times[:h], values[:h]


@njit(cache=True)
def _stable_order(keys: np.ndarray) -> np.ndarray:
    """The stable sorting order of ``keys`` (k,): one pass when they are sorted already, as
    a step's contacts come when each body is one piece (their pairs are sorted)."""
    for i in range(1, keys.shape[0]):
        if keys[i] < keys[i - 1]:
            return np.argsort(keys, kind="mergesort")
    return np.arange(keys.shape[0])


@njit(cache=True)
def compare(
    keys: np.ndarray, last: np.ndarray, moving: np.ndarray, n: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """This step's touching pairs against the last step's.

    ``keys`` (k,): this step's pairs as :func:`touches` gives them (repeats allowed);
    ``last`` (m,): the last step's, sorted, unique; ``moving`` (N,) the awake dynamic bodies
    (a last pair of which neither moves still touches: it sleeps); ``n`` the keys' base.
    Returns this step's pairs sorted and unique, those that began with the row of ``keys``
    each came from, and those that ended."""
    order = _stable_order(keys)  # (the first row of a pair kept)
    unique = np.empty(keys.shape[0] + last.shape[0], np.int64)
    began = np.empty(keys.shape[0], np.int64)
    row = np.empty(keys.shape[0], np.int64)
    ended = np.empty(last.shape[0], np.int64)
    u = b = e = 0
    i = j = 0
    while i < order.shape[0] or j < last.shape[0]:
        new = keys[order[i]] if i < order.shape[0] else -1
        old = last[j] if j < last.shape[0] else -1
        if j >= last.shape[0] or (i < order.shape[0] and new < old):
            if u == 0 or unique[u - 1] != new:
                unique[u] = new
                u += 1
                began[b] = new
                row[b] = order[i]
                b += 1
            i += 1
        elif i >= order.shape[0] or old < new:
            lo, hi = old // n - 1, old % n - 1  # (a wall, -1, never moves)
            if (lo < 0 or not moving[lo]) and not moving[hi]:
                unique[u] = old  # asleep: still touching
                u += 1
            else:
                ended[e] = old
                e += 1
            j += 1
        else:  # touching then and now
            if u == 0 or unique[u - 1] != new:
                unique[u] = new
                u += 1
            i += 1
            if i >= order.shape[0] or keys[order[i]] != new:
                j += 1
    return unique[:u], began[:b], row[:b], ended[:e]


@njit(cache=True)
def step_events(
    rows: tuple[np.ndarray, np.ndarray, int],
    columns: tuple[int, int, int, int],
    layout: tuple[int, int, int, int],
    limits: tuple[float, float, float],
    log: np.ndarray,
    number: np.ndarray,
    last: np.ndarray,
    moving: np.ndarray,
    ending: np.ndarray,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """One step's events in one call: :func:`touches`, :func:`compare`, and the three event
    arrays' records written as rows of int64 (the integer fields) and float64 (the others,
    through a view): every field is 8 bytes, so a (k, fields) buffer viewed as
    :func:`event_dtypes`'s dtype is the structured array, made without a NumPy call per field.

    ``rows``: the contact rows (floats, ints, count); ``columns``: the first point's column, a
    point's width, the flags' column, d; ``layout`` as :func:`touches`; ``limits``: the
    slop [m], the hit threshold [m/s] and the step's start [s]; ``log`` the step's exact
    impacts (all of its rows); ``number``, ``last``, ``moving`` as :func:`touches` and
    :func:`compare`; ``ending``: keys of pairs that end whatever this step says (bodies
    taken out), ended first. Returns the pairs touching now (sorted keys) and the begin
    (b, 2 + 2 d), end (e, 2) and hit (h, 4 + 2 d) records.
    """
    cf, ci, nc = rows
    point0, point_floats, flags, d = columns
    slop, threshold, start = limits
    keys, where, pairs, times, values = touches(
        cf, ci, nc, point0, point_floats, d, layout, flags, slop, threshold, log,
        log.shape[0], number,
    )  # fmt: skip
    n = number.shape[0] + 1
    now, began, row, ended = compare(keys, last, moving, n)
    begin = np.empty((began.shape[0], 2 + 2 * d), np.int64)
    begin_f = begin.view(np.float64)
    for k in range(began.shape[0]):
        begin[k, 0] = began[k] // n - 1
        begin[k, 1] = began[k] % n - 1
        for c in range(2 * d):
            begin_f[k, 2 + c] = where[row[k], c]
    end = np.empty((ending.shape[0] + ended.shape[0], 2), np.int64)
    for k in range(end.shape[0]):
        key = ending[k] if k < ending.shape[0] else ended[k - ending.shape[0]]
        end[k, 0] = key // n - 1
        end[k, 1] = key % n - 1
    hit = np.empty((pairs.shape[0], 4 + 2 * d), np.int64)
    hit_f = hit.view(np.float64)
    for k in range(pairs.shape[0]):
        hit[k, 0] = pairs[k, 0]
        hit[k, 1] = pairs[k, 1]
        hit_f[k, 2] = start + times[k]
        for c in range(2 * d + 1):
            hit_f[k, 3 + c] = values[k, c]
    return now, begin, end, hit


def split_off(
    keys: NDArray[np.int64], gone: NDArray[np.int64], n: int
) -> tuple[NDArray[np.int64], NDArray[np.int64]]:
    """Pairs ``keys`` (keys of base ``n``, as :func:`compare` takes them) split into those of
    no body in ``gone`` (the caller's numbers) and those of one: ``(kept, dropped)``."""
    out = np.isin(keys // n - 1, gone) | np.isin(keys % n - 1, gone)
    return keys[~out], keys[out]


class ContactEvents:
    """The pairs touching at the last step, and the events of the last step, for an engine of
    ``d`` dimensions whose rows are numbered ``number`` (N,) for the caller (-1: walls).

    :meth:`update` after each step while :attr:`on`; :attr:`last` the step's events.
    """

    def __init__(self, d: int, number: NDArray[np.int64], layout: PointLayout) -> None:
        self.d = d
        self.number = number
        self.layout = (layout.sep, layout.vrel, layout.total, layout.at)
        self.dtypes = event_dtypes(d)
        #: the last step's touching pairs (sorted keys) and the threshold for hits [m/s]
        self.keys = np.zeros(0, np.int64)
        self.threshold = 1.0
        #: whether steps gather events (a game loop's steps do; a run's need not pay for them)
        self.on = False
        self.last = self._none = EventArrays(*(np.zeros(0, t) for t in self.dtypes))
        #: pairs of bodies taken out of the world since the last step: they end in the next
        self.ending = np.zeros(0, np.int64)

    def forget(self, gone: NDArray[np.int64]) -> None:
        """Bodies ``gone`` (the caller's numbers) left the world: their pairs end at the next
        step (a removed body does not move, and would otherwise touch for ever)."""
        self.keys, dropped = split_off(self.keys, gone, self.number.shape[0] + 1)
        self.ending = np.concatenate((self.ending, dropped))

    def update(
        self,
        rows: tuple[NDArray[np.float64], NDArray[np.int64], int],
        columns: tuple[int, int, int],
        slop: float,
        log: NDArray[np.float64],
        start: float,
        moving: NDArray[np.bool_],
    ) -> None:
        """The events of the step that began at ``start`` [s], from its contact ``rows``
        (floats, ints, count; ``columns``: the first point's column, a point's width, the
        flags' column) and its exact impacts' ``log``. ``moving`` (N,) marks the awake
        dynamic bodies: a pair of which neither moves (asleep, static) has no contact row
        while it sleeps, and still touches (as in Box2D, sleep ends nothing)."""
        now, begin, end, hit = step_events(
            rows, (*columns, self.d), self.layout,
            (slop, self.threshold, start), log, self.number, self.keys, moving, self.ending,
        )  # fmt: skip
        self.keys = now
        if self.ending.size:
            self.ending = np.zeros(0, np.int64)
        if begin.shape[0] == 0 and end.shape[0] == 0 and hit.shape[0] == 0:
            self.last = self._none  # (a step of no event: the same empty arrays)
            return
        begin_t, end_t, hit_t = self.dtypes
        self.last = EventArrays(
            begin.view(begin_t)[:, 0], end.view(end_t)[:, 0], hit.view(hit_t)[:, 0]
        )
