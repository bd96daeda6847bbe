"""Event-driven dynamics of spheres and disks: the exact engine's main loop.

Bodies fly freely (straight lines, or parabolas under gravity) between events, and each
carries its own clock: it is advanced only when an event involves it (lazy clocks, Lubachevsky
1991). Every moving body has exactly one scheduled event, its earliest of: a collision with a
neighbour, with a wall or plane, or leaving its neighbour shell (Smallenburg 2022). The events
sit in an event calendar (:mod:`carom.engines.edmd.calendar`, after Paul 2007). A predicted
collision with ``j`` stores ``j``'s collision counter; if ``j`` has collided since, the event is
stale and the body is simply re-predicted (Rapaport 1980).

Dissipation and round-off:

* TC model (Luding & McNamara 1998): a collision within ``t_c`` of the previous collision of
  either body is elastic, which stops inelastic collapse.
* Rest: a body pulled by gravity onto a wall or plane that would leave it again for less than
  ``t_c`` (or that the TC model would bounce elastically) comes to rest on it: its normal
  velocity and normal acceleration are set to zero and it slides until a collision lifts it.
  This ends the Zeno sequence of a settling ball in a finite number of events.
* Overlap by round-off: an approaching pair that already touches collides now; a separating
  one never does (Bannerman et al. 2014). Overlaps therefore cannot grow.

The model ``m`` and state ``s`` are the named tuples of :mod:`carom.engines.edmd.model` and
:mod:`carom.engines.edmd.state`, reached through the engine's handle
(:mod:`carom.engines.edmd.handle`). :func:`run_frames` unpacks them once: the functions of the
hot loop take the arrays they need one by one, because Numba passes a named tuple of arrays
into a call by reference-counting every array in it (measured: 95 ns a call, against under 1 ns
for a few plain arrays, which LLVM inlines), and copies the whole tuple into a call it does not
inline. The helpers are compiled without reference counting and inlined by LLVM
(:mod:`carom.engines.edmd.jitflags` says why); the loop itself counts references only where it
reads the handle, once a call (measured: no slower than the loop compiled without counting,
in an interleaved A/B). Being the call from Python, it is compiled once: a wrapper that read
the handle and called it re-optimised its whole machine code, 2 s of every cold start.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.edmd.calendar import (
    I_CUR,
    I_SIZE,
    calendar_next,
    calendar_top,
    calendar_update,
)
from carom.engines.edmd.codes import (
    C_EVENTS,
    C_SHELL,
    C_STALE,
    CELLS_FULL,
    DONE,
    EV_PAIR,
    EV_SHELL,
    EV_WALL,
    LISTS_FULL,
    LOG_FULL,
    MAX_EVENTS,
)
from carom.engines.edmd.collide import collide_face, collide_pair
from carom.engines.edmd.jitflags import njit_inlined, njit_without_refcounting
from carom.engines.edmd.lookahead import (
    ask_for_body,
    ask_for_cells,
    ask_for_neighbours,
    ask_for_next,
    ask_for_pour,
    asked_already,
)
from carom.engines.edmd.neighbours import FITS, LIST_FULL, rebuild_shell
from carom.engines.edmd.predict import (
    calendar_of,
    free_flight,
    kinematic_views,
    predict,
    schedule_views,
)
from carom.engines.edmd.prefetch import prefetch_item, prefetch_row
from carom.geometry.rotation import turn
from carom.geometry.toi import INF

# bodies above which the loop prefetches the next events' data (the state, ~500 bytes a body,
# no longer fits a core's 2 MB cache)
LOOKAHEAD_BODIES = 4096
# bodies above which it asks for each level of the next events' data a step ahead (the state
# no longer fits the last-level cache; measured, concurrent A/B on melted gases: 1.06 and
# 1.13x at 10^6 spheres, 1.11x at 256000, and 0.88x at 32000, where the misses it hides are
# hits in that cache)
DEEP_LOOKAHEAD_BODIES = 1 << 17
# 4-byte entries of a neighbour list on one 64-byte cache line (a 3D list of 32 is two lines)
LIST_LINE = 16


@njit(cache=True, error_model="numpy", nogil=True)
def initialise(lo: int, hi: int, m, s) -> int:  # type: ignore[no-untyped-def]
    """Predict the first event of every body ``i``, ``lo <= i < hi``, once the lists are
    built (:func:`carom.engines.edmd.neighbours.build_all`); the caller then files the events
    (:func:`carom.engines.edmd.calendar.calendar_build`). Returns ``DONE``.

    Every body's clock reads the engine's (a fresh state), so no body moves before it is
    predicted: a prediction reads only records no range writes, and ranges of bodies run on
    threads at once (the GIL released; :func:`carom.engines.edmd.threads.in_ranges`). Its
    scratch is its own.
    """
    x, v, t = kinematic_views(s.kin, m.box.shape[0])
    ev_kind, ev_other, ev_stamp = schedule_views(s.sched)
    counter = s.counter
    near = np.empty_like(s.near)
    T = s.clock[0]
    for i in range(lo, hi):
        predict(
            i,
            T,
            s.kin,
            x,
            v,
            s.acc,
            m.gravity,
            t,
            s.shell,
            s.support,
            s.nbr,
            s.nbr_count,
            near,
            counter,
            m.radius,
            m.mobile,
            m.box,
            m.inv_box,
            m.periodic,
            m.shell_thickness,
            m.plane_point,
            m.plane_normal,
            s.ev_time,
            ev_kind,
            ev_other,
            ev_stamp,
        )
    return DONE


@njit(cache=True, error_model="numpy")
def run_frames(  # type: ignore[no-untyped-def]
    h,
    times,
    max_events: int,
    log_on: bool,
    sample: bool,
    done,
    t_out,
    x_out,
    v_out,
    orient_out,
    w_out,
) -> int:
    """Process the events of the engine behind handle ``h``
    (:mod:`carom.engines.edmd.handle`) in time order up to each of ``times`` in turn, from
    frame ``done[0]`` on; with ``sample``, write every body's state at each into that frame
    of the outputs (:func:`write_frame`); count each frame done in ``done[0]``. Return why it
    stopped.

    ``DONE``: every frame is done (the clock reads the last time); ``LOG_FULL``: the event
    log needs emptying; ``MAX_EVENTS``: ``max_events`` processed in this call;
    ``LISTS_FULL`` / ``CELLS_FULL``: a neighbour list or a cell row is full (grow them and
    rebuild them all; the schedule stays valid, and the event that overflowed runs again).
    Called again with the same ``done``, it goes on where it stopped.
    """
    # unpack once: the hot functions take plain arrays (see the module docstring); reading the
    # handle is the only reference counting the loop does
    m, s, order = h.model, h.state, h.order
    kin = s.kin
    x, v, t = kinematic_views(kin, m.box.shape[0])
    acc, pull, wraps = s.acc, s.pull, s.wraps
    rot = (s.w, s.orient, s.orient_t)
    shell, support, last_coll = s.shell, s.support, s.last_coll
    nbr, nbr_count, nbr_mark, nbr_old, near = s.nbr, s.nbr_count, s.nbr_mark, s.nbr_old, s.near
    scan, scan_body = s.scan, s.scan_body
    ev_time = s.ev_time
    cal_body = s.cal_body
    # a list's entry on its second cache line (rows start on lines: 16 4-byte entries a line)
    list_line = min(LIST_LINE, nbr.shape[1] - 1)
    sched = s.sched
    ev_kind, ev_other, ev_stamp = schedule_views(sched)
    counter = s.counter
    cal = calendar_of(s)
    counts, sums = s.counts, s.sums
    # grouped as tuples for the inlined callees (a call takes at most 30 arguments there)
    logbuf = (
        s.log_time, s.log_a, s.log_b, s.log_impulse, s.log_un, s.log_point, s.log_normal,
        s.log_n,
    )  # fmt: skip
    log_time, log_n = s.log_time, s.log_n
    cell, slot, cell_count, cell_body = s.cell, s.slot, s.cell_count, s.cell_body
    radius, mass, inv_mass, q, mobile = m.radius, m.mass, m.inv_mass, m.q, m.mobile
    material, face_e = m.material, m.face_e
    pair_table = (m.pair_law, m.pair_e, m.pair_beta, m.pair_friction)
    gravity, box, periodic, delta, t_c = m.gravity, m.box, m.periodic, m.shell_thickness, m.t_c
    inv_box = m.inv_box
    plane_point, plane_normal = m.plane_point, m.plane_normal
    cell_size, ncell = m.cell_size, m.ncell

    dim = x.shape[1]
    # prefetch the next events' data only where it misses the core's own caches (measured:
    # 1.06 to 1.13x from 1e5 bodies on, 4% slower at 1e3, where everything is in cache)
    lookahead = x.shape[0] > LOOKAHEAD_BODIES
    deep = x.shape[0] > DEEP_LOOKAHEAD_BODIES
    pour_bucket, pour_body = -1, -1  # a walk along the list of the bucket poured next
    poured = -1  # the last bucket whose bodies' rows were asked for
    # the bodies, and their events' times, whose events' data were last asked for
    asked, asked_t = np.full(2, -1, np.int64), np.full(2, -1.0)
    cal_i, cur_heap = cal[8], cal[4]
    processed = 0
    log_cap = log_time.shape[0]
    if done[0] >= times.shape[0]:
        return DONE
    t_stop = times[done[0]]
    while True:
        i = calendar_top(ev_time, cal)
        T = ev_time[i] if i >= 0 else INF
        if t_stop < T or math.isinf(T):
            if t_stop < INF:
                s.clock[0] = t_stop
            f = done[0]
            if sample:
                write_frame(
                    kin, acc, s.orient, s.orient_t, s.w, box, periodic, order, t_stop, f,
                    t_out, x_out, v_out, orient_out, w_out,
                )  # fmt: skip
            done[0] = f + 1
            if f + 1 >= times.shape[0]:
                return DONE
            t_stop = times[f + 1]
            continue
        if processed >= max_events:
            return MAX_EVENTS
        if log_on and log_n[0] + 1 > log_cap:
            return LOG_FULL
        processed += 1
        # what this event will read, asked for at once rather than miss by miss
        prefetch_row(sched, i)
        prefetch_row(kin, i)
        prefetch_row(nbr, i)
        prefetch_item(nbr, i, list_line)
        if deep:
            # and what the next events will read (carom.engines.edmd.lookahead)
            if cal_i[I_CUR] != poured:  # a bucket was just poured: its bodies' rows
                poured = cal_i[I_CUR]
                for node in range(cal_i[I_SIZE]):
                    b = cur_heap[node]
                    ask_for_body(b, kin, nbr, list_line, nbr_count, sched, ev_time, cal_body,
                                 shell, last_coll, counter, material, inv_mass, radius)  # fmt: skip
                    if ev_kind[b] == EV_SHELL:
                        ask_for_cells(b, kin, ev_time, cell_count, cell_body, shell, box,
                                      periodic, cell_size, ncell, False)  # fmt: skip
            if not asked_already(i, ev_time, asked, asked_t):  # (its rows are, since the pour)
                ask_for_neighbours(i, kin, nbr, nbr_count, counter)
            for k in range(1, 3):
                b = calendar_next(cal, k)
                if b >= 0 and not asked_already(b, ev_time, asked, asked_t):
                    ask_for_next(
                        b, kin, nbr, list_line, nbr_count, sched, ev_time, cal_body, shell,
                        last_coll, counter, material, inv_mass, radius, cell_count, cell_body,
                        box, periodic, cell_size, ncell, nbr_mark,
                    )  # fmt: skip
                    asked[k - 1] = b
                    asked_t[k - 1] = ev_time[b]
            pour_bucket, pour_body = ask_for_pour(
                pour_bucket, pour_body, cal_body, ev_time, sched, kin, cal
            )
        elif lookahead:  # the next events' rows, and this one's neighbours' records
            for k in range(1, 3):
                b = calendar_next(cal, k)
                if b >= 0:
                    ask_for_body(b, kin, nbr, list_line, nbr_count, sched, ev_time, cal_body,
                                 shell, last_coll, counter, material, inv_mass, radius)  # fmt: skip
            ask_for_neighbours(i, kin, nbr, nbr_count, counter)
        s.clock[0] = T
        counts[C_EVENTS] += 1
        kind = ev_kind[i]
        j = -1
        free_flight(x, v, acc, gravity, t, i, T)  # every event moves its own body to now
        if kind == EV_PAIR:
            j = ev_other[i]
            prefetch_row(kin, j)
            prefetch_row(nbr, j)
            prefetch_item(nbr, j, list_line)
            prefetch_row(cal_body, j)
            prefetch_row(last_coll, j)
            prefetch_row(inv_mass, j)
            if counter[j] != ev_stamp[i]:
                counts[C_STALE] += 1
                j = -1  # stale: the partner collided since; just re-predict
            else:
                free_flight(x, v, acc, gravity, t, j, T)
                collide_pair(
                    i,
                    j,
                    T,
                    log_on,
                    x,
                    v,
                    acc,
                    rot,
                    counter,
                    last_coll,
                    support,
                    radius,
                    mass,
                    inv_mass,
                    q,
                    material,
                    pair_table,
                    face_e,
                    pull,
                    plane_normal,
                    box,
                    periodic,
                    t_c,
                    counts,
                    sums,
                    logbuf,
                )
        elif kind == EV_WALL:
            collide_face(
                i,
                ev_other[i],
                T,
                log_on,
                x,
                v,
                acc,
                counter,
                last_coll,
                support,
                radius,
                mass,
                face_e,
                pull,
                plane_normal,
                t_c,
                counts,
                sums,
                logbuf,
            )
        else:  # EV_SHELL
            counts[C_SHELL] += 1
            if periodic:
                wrap_into_box(x, wraps, box, i)
            for k in range(dim):
                shell[i, k] = x[i, k]
            status = rebuild_shell(
                i,
                shell,
                mobile,
                nbr,
                nbr_count,
                cell_count,
                cell_body,
                slot,
                cell,
                box,
                periodic,
                delta,
                cell_size,
                ncell,
                nbr_mark,
                nbr_old,
                counts[C_SHELL],  # a stamp no earlier rebuild used
                scan,
                scan_body,
            )
            if status != FITS:
                return LISTS_FULL if status == LIST_FULL else CELLS_FULL
        # re-schedule the bodies whose motion changed: i, and its partner j if it had one
        for body in (i, j):
            if body < 0:
                continue
            predict(
                body, T, kin, x, v, acc, gravity, t, shell, support, nbr, nbr_count, near,
                counter, radius, mobile, box, inv_box, periodic, delta, plane_point, plane_normal,
                ev_time, ev_kind, ev_other, ev_stamp,
            )  # fmt: skip
            calendar_update(ev_time, body, cal)


@njit_inlined
def wrap_into_box(x, wraps, box, i) -> None:  # type: ignore[no-untyped-def]
    """Body ``i``'s position moved back into the periodic box, each move counted in
    ``wraps`` once it has rows (a force has acted: ``State.wraps``)."""
    counted = wraps.shape[0] > 0
    for k in range(box.shape[0]):
        back = np.floor(x[i, k] / box[k])
        if back != 0.0:
            x[i, k] -= box[k] * back
            if counted:
                wraps[i, k] += back


@njit_inlined
def motion_at(x, v, t, acc, box, periodic, t_f, f, i, r, x_out, v_out) -> None:  # type: ignore[no-untyped-def]
    """Body ``i``'s position and velocity at ``t_f`` [s] into ``[f, r]`` of ``x_out`` and
    ``v_out`` (periodic positions wrapped into the box)."""
    dt = t_f - t[i]
    for k in range(box.shape[0]):
        a = 0.0 if acc is None else acc[i, k]  # (None without gravity)
        x_out[f, r, k] = x[i, k] + (v[i, k] + 0.5 * a * dt) * dt
        v_out[f, r, k] = v[i, k] + a * dt
        if periodic:
            x_out[f, r, k] -= box[k] * np.floor(x_out[f, r, k] / box[k])


@njit_without_refcounting
def write_frame(  # type: ignore[no-untyped-def]
    kin, acc, orient, orient_t, w, box, periodic, order, t_f, f, t_out, x_out, v_out,
    orient_out, w_out,
) -> None:  # fmt: skip
    """Write each body's position, velocity, orientation (a 2D angle in column 0, a 3D
    quaternion) and spin at ``t_f`` [s] into ``[f, order[i]]`` of the outputs (periodic
    positions wrapped into the box), and ``t_f`` into ``t_out[f]``. ``t_f`` is at or after
    every body's own clock."""
    t_out[f] = t_f
    dim = box.shape[0]
    x, v, t = kinematic_views(kin, dim)
    frame = orient_out[f]
    for i in range(x.shape[0]):
        r = order[i]
        motion_at(x, v, t, acc, box, periodic, t_f, f, i, r, x_out, v_out)
        if w is None:  # no spins: every orientation is the identity (pruned otherwise)
            for k in range(frame.shape[1]):
                frame[r, k] = 1.0 if k == 0 and dim == 3 else 0.0
            for k in range(3):
                w_out[f, r, k] = 0.0
        else:
            for k in range(frame.shape[1]):
                frame[r, k] = orient[i, k]
            turn(frame, r, w[i, 0], w[i, 1], w[i, 2], t_f - orient_t[i], dim)
            for k in range(3):
                w_out[f, r, k] = w[i, k]


@njit_without_refcounting
def write_motion(kin, acc, box, periodic, order, t_f, f, t_out, x_out, v_out) -> None:  # type: ignore[no-untyped-def]
    """:func:`write_frame`'s positions and velocities alone, the same numbers."""
    t_out[f] = t_f
    x, v, t = kinematic_views(kin, box.shape[0])
    for i in range(x.shape[0]):
        motion_at(x, v, t, acc, box, periodic, t_f, f, i, order[i], x_out, v_out)
