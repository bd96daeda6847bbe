"""Renumbering a running engine's bodies along the Morton curve, in place.

The engine numbers bodies along a Morton curve through its cell grid when it is built
(:func:`carom.engines.edmd.ordering.spatial_order`), so that bodies near in space are near in
memory. As a gas runs, bodies diffuse away from the neighbours they started with, and a
body's neighbours, records and events spread over more and more cache lines: on a gas of 10^5
spheres the cost per collision rose by 8% over the first 250 collisions a body, towards that
of a random numbering (15-20% above a sorted one; docs/engine.md). :func:`renumber` sorts the
bodies again by the cells their shells are filed in, in the same order as the build.

It is a permutation and nothing else: every row of every per-body array moves to the body's
new number, and every array that holds body numbers (neighbour lists, cell rows, the event
calendar's links and heap, the partners of pair events) is mapped to the new numbers. No
time, position or prediction is computed again, so a run renumbered as it goes gives the
events a run without renumbering gives, at the same times (tested bit for bit; only events at
equal times may come in another order, since ties are taken by body number). The rows move
in place, cycle by cycle: besides the new numbers (4 bytes a body), nothing of the size of
the bodies is allocated, so a renumbering raises the peak memory of a large run by a few MB.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numba import njit
from numpy.typing import NDArray

from carom.engines.edmd.calendar import CAL_NEXT, CAL_PREV, CAL_WHERE, I_SIZE
from carom.engines.edmd.codes import EV_PAIR
from carom.engines.edmd.model import Model
from carom.engines.edmd.ordering import KEY_ROWS, morton_keys
from carom.engines.edmd.state import SCHED_KIND, SCHED_OTHER, State

__all__ = ["cell_ranks", "renumber"]

#: Arrays of rows of 4-byte words that one renumbering moves at most (all of a state's)
MOVED_ARRAYS = 25
#: Rows of the schedule whose partners are mapped to new numbers at a time
MAP_ROWS = 1 << 16


@njit(cache=True)
def _new_numbers(cell: np.ndarray, cell_rank: np.ndarray, number: np.ndarray) -> bool:
    """Each body's new number, into ``number`` (N,): bodies sorted by the Morton rank
    ``cell_rank`` (C,) of their cell ``cell`` (N,), ties kept in the present order (a stable
    counting sort). Returns whether any number changed."""
    n_cells = cell_rank.shape[0]
    start = np.zeros(n_cells + 1, np.int32)  # (int32: at most 10^8 bodies, carom.limits)
    for i in range(cell.shape[0]):
        start[cell_rank[cell[i]] + 1] += 1
    for r in range(n_cells):
        start[r + 1] += start[r]
    changed = False
    for i in range(cell.shape[0]):
        r = cell_rank[cell[i]]
        number[i] = start[r]
        changed |= start[r] != i
        start[r] += 1
    return changed


@njit(cache=True, inline="always")
def _carry(arrays, carried: np.ndarray, j: int, put: bool) -> None:  # type: ignore[no-untyped-def]
    """``carried`` (one row an array) takes row ``j`` of each array; with ``put``, row ``j``
    takes what ``carried`` held (the two are swapped)."""
    for k in range(len(arrays)):
        a = arrays[k]
        for b in range(a.shape[1]):
            held = a[j, b]
            if put:
                a[j, b] = carried[k, b]
            carried[k, b] = held


@njit(cache=True)
def _move_rows(arrays, number: np.ndarray, seen: np.ndarray) -> None:  # type: ignore[no-untyped-def]
    """Move row ``i`` of each of ``arrays`` (a tuple of (N, W) views in 4-byte words) to
    row ``number[i]``, in place: each cycle of the permutation is followed once, the rows on
    their way carried in a spare. ``seen`` (N,) is False on entry."""
    carried = np.empty((len(arrays), max([a.shape[1] for a in arrays])), np.uint32)
    for first in range(number.shape[0]):
        if seen[first]:
            continue
        seen[first] = True
        j = number[first]
        if j == first:
            continue
        _carry(arrays, carried, first, False)
        while True:  # the rows carried go to j; j's rows are carried on
            _carry(arrays, carried, j, True)
            seen[j] = True
            if j == first:
                break
            j = number[j]


@njit(cache=True)
def _map_numbers(numbers: np.ndarray, number: np.ndarray) -> None:
    """Each body number ``b >= 0`` in ``numbers`` (flat) replaced by ``number[b]``, in place
    (negative entries mark an empty place and stay)."""
    for k in range(numbers.shape[0]):
        b = numbers[k]
        if b >= 0:
            numbers[k] = number[b]


def _move(arrays: tuple[NDArray[Any] | None, ...], number: NDArray[np.int32]) -> None:
    """Move row ``i`` of each of ``arrays`` (N, ...) to row ``number[i]``, in place (None
    stands for no array). Rows of whole 4-byte words move in one compiled pass, as views of
    such words, padded with empty views to :data:`MOVED_ARRAYS` (one type for every kind of
    state: one compile); others (the flags of which bodies move) through a copy."""
    n = number.shape[0]
    views: list[NDArray[np.uint32]] = []
    for array in arrays:
        if array is None:
            continue
        assert array.flags.c_contiguous
        row = array.reshape(n, -1)
        if row.shape[1] * row.itemsize % 4 == 0:
            views.append(row.view(np.uint32))
        else:
            moved = np.empty_like(array)
            moved[number] = array
            array[...] = moved
    assert len(views) <= MOVED_ARRAYS
    views += [np.empty((n, 0), np.uint32)] * (MOVED_ARRAYS - len(views))
    _move_rows(tuple(views), number, np.zeros(n, np.bool_))


def cell_ranks(ncell: NDArray[np.int64]) -> NDArray[np.int32]:
    """The place of each cell of a grid of ``ncell`` (d,) cells (row-major index, as
    ``State.cell``) along the Morton curve that
    :func:`carom.engines.edmd.ordering.spatial_order` follows: (C,) int32, made once for an
    engine's grid (:func:`renumber` takes it)."""
    n_cells = int(np.prod(ncell))
    key = np.empty(n_cells, np.uint64)
    for a in range(0, n_cells, KEY_ROWS):
        index = np.arange(a, min(a + KEY_ROWS, n_cells))
        key[a : a + KEY_ROWS] = morton_keys(np.stack(np.unravel_index(index, ncell), axis=1))
    along = np.argsort(key, kind="stable")
    del key
    rank = np.empty(n_cells, np.int32)
    rank[along] = np.arange(n_cells, dtype=np.int32)
    return rank


def renumber(
    model: Model,
    state: State,
    order: NDArray[np.int64],
    cell_rank: NDArray[np.int32] | None = None,
) -> bool:
    """Renumber the bodies of an engine along the Morton curve through its cell grid, by
    the cells their shells are filed in, changing every array in place (module docstring).

    Parameters
    ----------
    model : Model
        Its per-body arrays (radius, mass, ...) are reordered.
    state : State
        Every per-body array is reordered and every body number in it mapped; the event log
        must be empty (drained).
    order : (N,) int64
        The caller's number of each engine row: reordered with the rows.
    cell_rank : (C,) int32, optional
        :func:`cell_ranks` of the model's grid, if the caller keeps it (made here if not).

    Returns
    -------
    bool
        Whether any body changed number (False if they were still in order: a second
        renumbering changes nothing).
    """
    assert state.log_n[0] == 0, "drain the event log before renumbering"
    n = order.shape[0]
    if cell_rank is None:
        cell_rank = cell_ranks(model.ncell)
    number = np.empty(n, np.int32)
    if not _new_numbers(state.cell, cell_rank, number):
        return False
    wraps = state.wraps if len(state.wraps) else None  # (no rows until a force acts)
    per_body = (
        model.mobile, model.radius, model.mass, model.inv_mass, model.q, model.material,
        state.kin, state.acc, state.pull, wraps, state.support, state.w, state.orient,
        state.orient_t, state.last_coll, state.shell, state.nbr, state.nbr_count,
        state.nbr_mark, state.cell, state.slot, state.ev_time, state.sched, state.counter,
        state.cal_body, order,
    )  # fmt: skip
    _move(per_body, number)
    # the arrays that hold body numbers; places past a list's or a row's count are spare,
    # and hold numbers of bodies too (or zeros): they are mapped like the rest
    for numbers in (state.nbr, state.cell_body, state.cal_head):
        assert numbers.flags.c_contiguous  # (so that the flat view below is no copy)
        _map_numbers(numbers.reshape(-1), number)
    for column in (CAL_NEXT, CAL_PREV):  # (the calendar's lists; the records' other two
        _map_numbers(state.cal_body[:, column], number)  # columns are places, not bodies)
    sched = state.sched
    for a in range(0, n, MAP_ROWS):
        rows = sched[a : a + MAP_ROWS]
        pair = rows[:, SCHED_KIND] == EV_PAIR
        rows[pair, SCHED_OTHER] = number[rows[pair, SCHED_OTHER]]
    # the current bucket's heap is ordered on (time, body number): mapped, then sorted again
    # (a sorted array is a heap), since equal times are taken in order of body number
    size = int(state.cal_i[I_SIZE])
    heap, key = state.cur_heap, state.cur_key
    bodies = number[heap[:size]]
    by = np.lexsort((bodies, key[:size]))
    heap[:size] = bodies[by]
    key[:size] = key[:size][by]
    state.cal_body[heap[:size], CAL_WHERE] = np.arange(size, dtype=np.int32)
    return True
