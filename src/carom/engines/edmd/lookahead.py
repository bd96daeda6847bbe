"""What the event loop asks for before it reads it: prefetches of the next events' data.

Past the caches (about 10^5 bodies) an event's cost is mostly waiting on memory, and its
misses hang on each other: the calendar gives the body, its row gives its list and partner,
the list gives the neighbours, whose records the prediction reads; a shell exit reads the
cells around the body, which give the candidates. A miss costs about 200 ns on the machines
measured, while twenty independent ones overlap in about that time. So each level is asked
for a step before it is read (:func:`carom.engines.edmd.prefetch.prefetch_row`):

* during a bucket, the list of the next one, a body an event (:func:`ask_for_pour`): pouring
  it into the calendar's heap is one dependent read a body;
* when a bucket is poured, the rows of its bodies (:func:`ask_for_body`), about eight events
  before they are processed, and for a shell exit the rows of the cells around where the body
  will be (:func:`ask_for_cells`);
* at each event, for the two bodies whose events are likely next (the heap's two top
  children), their rows being in cache by then: the records of their neighbours
  (:func:`ask_for_neighbours`), their partner's rows, and for a shell exit the shell records
  of the bodies in those cells (:func:`ask_for_next`).

A prefetch reads nothing into the computation: the results are the same bits with or without
them (tests/engines/edmd/test_loop.py). All are no-ops without the JIT.
"""

from __future__ import annotations

import numpy as np

from carom.engines.edmd.calendar import I_CUR
from carom.engines.edmd.codes import EV_PAIR, EV_SHELL
from carom.engines.edmd.jitflags import njit_inlined
from carom.engines.edmd.neighbours import axis_cells
from carom.engines.edmd.prefetch import prefetch_item, prefetch_row
from carom.engines.edmd.state import KIN_T, KIN_V, SCHED_KIND, SCHED_OTHER


@njit_inlined
def ask_for_body(  # type: ignore[no-untyped-def]
    b, kin, nbr, list_line, nbr_count, sched, ev_time, cal_body, shell, last_coll, counter,
    material, inv_mass, radius,
) -> None:  # fmt: skip
    """Prefetch body ``b``'s rows that an event of it reads or writes (both lines of its
    list: ``list_line`` is an entry on the second)."""
    prefetch_row(sched, b)
    prefetch_row(kin, b)
    prefetch_row(nbr, b)
    prefetch_item(nbr, b, list_line)
    prefetch_row(nbr_count, b)
    prefetch_row(cal_body, b)
    prefetch_row(shell, b)
    prefetch_row(ev_time, b)
    prefetch_row(last_coll, b)
    prefetch_row(counter, b)
    prefetch_row(material, b)
    prefetch_row(inv_mass, b)
    prefetch_row(radius, b)


@njit_inlined
def ask_for_neighbours(b, kin, nbr, nbr_count, counter) -> None:  # type: ignore[no-untyped-def]
    """Prefetch the records of body ``b``'s neighbours, which its prediction reads, and their
    collision counters (the stamp of the one it will meet)."""
    for slot in range(nbr_count[b]):
        j = nbr[b, slot]
        prefetch_row(kin, j)
        prefetch_row(counter, j)


@njit_inlined
def _cell_coordinate(kin, b, k, dt, box, periodic, cell_size, ncell) -> int:  # type: ignore[no-untyped-def]
    """The cell coordinate on axis ``k`` of body ``b`` ``dt`` [s] after its clock, in a
    straight line: a hint, always on the grid (clamped; 0 for a NaN), since the cells it names
    are read."""
    p = kin[b, k] + kin[b, KIN_V + k] * dt
    if periodic:
        p -= box[k] * np.floor(p / box[k])
    q = p / cell_size[k]
    if not q >= 1.0:  # (NaN included)
        return 0
    if q >= ncell[k] - 1.0:
        return int(ncell[k] - 1)
    return int(q)


@njit_inlined
def ask_for_cells(  # type: ignore[no-untyped-def]
    b, kin, ev_time, cell_count, cell_body, shell, box, periodic, cell_size, ncell, candidates
) -> None:
    """Prefetch the rows of the 3^dim cells around where body ``b`` will be at its event, the
    cells a shell exit scans (:func:`carom.engines.edmd.neighbours.rebuild_shell`); with
    ``candidates``, the shell records of the bodies filed in them instead (the rows being in
    cache)."""
    dt = ev_time[b] - kin[b, KIN_T]
    three = ncell.shape[0] == 3
    c0 = _cell_coordinate(kin, b, 0, dt, box, periodic, cell_size, ncell)
    c1 = _cell_coordinate(kin, b, 1, dt, box, periodic, cell_size, ncell)
    c2 = _cell_coordinate(kin, b, 2, dt, box, periodic, cell_size, ncell) if three else 0
    n1 = ncell[1]
    n2 = ncell[2] if three else 1
    ax0 = axis_cells(c0, ncell[0], periodic)
    ax1 = axis_cells(c1, n1, periodic)
    ax2 = axis_cells(c2, n2, periodic) if three else (1, 0, 0, 0)
    for a in range(1, ax0[0] + 1):
        for e in range(1, ax1[0] + 1):
            row = (ax0[a] * n1 + ax1[e]) * n2
            for c in range(1, ax2[0] + 1):
                index = row + ax2[c]
                if candidates:
                    for q in range(min(cell_count[index], cell_body.shape[1])):
                        prefetch_row(shell, cell_body[index, q])
                else:
                    prefetch_row(cell_count, index)
                    prefetch_row(cell_body, index)


@njit_inlined
def ask_for_next(  # type: ignore[no-untyped-def]
    b, kin, nbr, list_line, nbr_count, sched, ev_time, cal_body, shell, last_coll, counter,
    material, inv_mass, radius, cell_count, cell_body, box, periodic, cell_size, ncell, mark,
) -> None:  # fmt: skip
    """What body ``b``'s coming event reads past its own rows (in cache: asked for when its
    bucket was poured): its neighbours' records, and its partner's rows or, for a shell exit,
    the shell records of the bodies in the cells around it (the cells asked for at the pour)
    and its neighbours' marks."""
    ask_for_neighbours(b, kin, nbr, nbr_count, counter)
    kind = sched[b, SCHED_KIND]
    if kind == EV_PAIR:
        ask_for_body(sched[b, SCHED_OTHER], kin, nbr, list_line, nbr_count, sched, ev_time,
                     cal_body, shell, last_coll, counter, material, inv_mass, radius)  # fmt: skip
    elif kind == EV_SHELL:
        ask_for_cells(b, kin, ev_time, cell_count, cell_body, shell, box, periodic, cell_size,
                      ncell, True)  # fmt: skip
        for slot in range(nbr_count[b]):
            prefetch_row(mark, nbr[b, slot])


@njit_inlined
def ask_for_pour(  # type: ignore[no-untyped-def]
    bucket: int, body: int, cal_body, ev_time, sched, kin, cal
) -> tuple[int, int]:
    """One step of a walk along the list of the bucket after the current one: prefetch the
    calendar record, event time, schedule row and kinematic record of the body after
    ``body`` (whose record was asked for a step ago), so that pouring the bucket into the
    heap, a dependent read a body, finds them in cache, and the pour can ask for what its
    events will need. Returns the walk's new ``(bucket, body)``; start it at ``(-1, -1)``.
    Only a hint: a walk whose body was filed elsewhere since starts again at the list's head,
    and one at the list's end (body -1) waits for the next bucket."""
    cal_head, cal_next, _prev, cal_loc, _heap, _key, _where, _f, cal_i = cal
    following = cal_i[I_CUR] + 1
    if following >= cal_head.shape[0] - 1:
        return following, -1
    if bucket != following or (body >= 0 and cal_loc[body] != following):
        body = cal_head[following]
    elif body >= 0:
        body = cal_next[body]
    else:
        return following, -1
    if body >= 0:
        prefetch_row(cal_body, body)
        prefetch_row(ev_time, body)
        prefetch_row(sched, body)
        prefetch_row(kin, body)
    return following, body


@njit_inlined
def asked_already(b, ev_time, asked, asked_t) -> bool:  # type: ignore[no-untyped-def]
    """Whether body ``b``'s coming event's data were asked for already: ``asked`` (2,) int64
    and ``asked_t`` (2,) float64 hold the last two bodies asked for and their events' times
    [s]."""
    return bool(
        (b == asked[0] and ev_time[b] == asked_t[0]) or (b == asked[1] and ev_time[b] == asked_t[1])
    )
