"""Reaching the event-driven engine's bodies between two calls: their motion read at the
engine's clock, and new motion given to them, with their events predicted again.

A body given a new velocity, spin or position is first flown to the clock (its own lags: lazy
clocks), takes the new motion there, leaves its support if it no longer slides on it, and has
its collision counter raised: every event a neighbour predicted with it is stale from then on
(Rapaport's rule, as after a collision), and its own next event is predicted afresh from its new
motion. From there it follows the new free flight exactly: a sphere kicked in flight takes the
new parabola from the clock on, to round-off.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from carom.engines.edmd.calendar import calendar_update
from carom.engines.edmd.codes import C_SHELL
from carom.engines.edmd.loop import motion_at
from carom.engines.edmd.neighbours import FITS, rebuild_shell
from carom.engines.edmd.predict import (
    calendar_of,
    face_normal,
    free_flight,
    kinematic_views,
    predict,
    schedule_views,
    set_support,
)
from carom.geometry.rotation import turn

__all__ = ["bodies_now", "retire_bodies", "set_bodies", "set_pulls"]


@njit(cache=True, error_model="numpy")
def bodies_now(h, rows, x_out, v_out, orient_out, w_out) -> None:  # type: ignore[no-untyped-def]
    """Engine rows ``rows`` (k,): position and velocity (1, k, d) (as frame 0 of a sample,
    :func:`carom.engines.edmd.loop.write_frame`), orientation (k, 1) or (k, 4) and spin
    (k, 3) at the engine's clock, into the outputs (nothing moves)."""
    m, s = h.model, h.state
    _now(
        rows, s.kin, s.acc, s.w, s.orient, s.orient_t, m.box, m.periodic, s.clock[0], x_out,
        v_out, orient_out, w_out,
    )  # fmt: skip


@njit(cache=True, error_model="numpy")
def _now(  # type: ignore[no-untyped-def]
    rows, kin, acc, w, orient, orient_t, box, periodic, T, x_out, v_out, orient_out, w_out
) -> None:  # fmt: skip
    """:func:`bodies_now` on the arrays (``acc`` and ``w`` None when the engine has none:
    a branch on an argument that is None is pruned as it compiles)."""
    dim = box.shape[0]
    x, v, t = kinematic_views(kin, dim)
    for r in range(rows.shape[0]):
        i = rows[r]
        motion_at(x, v, t, acc, box, periodic, T, 0, i, r, x_out, v_out)
        if w is None:
            for k in range(orient_out.shape[1]):
                orient_out[r, k] = 1.0 if k == 0 and dim == 3 else 0.0
            for k in range(3):
                w_out[r, k] = 0.0
        else:
            for k in range(orient_out.shape[1]):
                orient_out[r, k] = orient[i, k]
            turn(orient_out, r, w[i, 0], w[i, 1], w[i, 2], T - orient_t[i], dim)
            for k in range(3):
                w_out[r, k] = w[i, k]


@njit(cache=True, error_model="numpy")
def set_bodies(h, rows, x_new, v_new, orient_new, w_new, moved) -> int:  # type: ignore[no-untyped-def]
    """Give engine rows ``rows`` (k,) the positions ``x_new`` (k, d) (when ``moved``),
    velocities ``v_new`` (k, d), orientations ``orient_new`` and spins ``w_new`` (k, 3)
    (when the engine keeps spins) at the engine's clock, and predict their events again.

    Every value replaces the old one, so a call that returns early can be made again whole.
    Returns ``FITS``, or why a moved body's neighbour list or cell row did not fit (the
    caller grows them, rebuilds them all and calls again)."""
    m, s = h.model, h.state
    dim = m.box.shape[0]
    kin = s.kin
    x, v, t = kinematic_views(kin, dim)
    counter = s.counter
    T = s.clock[0]
    for r in range(rows.shape[0]):
        i = rows[r]
        free_flight(x, v, s.acc, m.gravity, t, i, T)
        _turn_to(i, r, T, s.w, s.orient, s.orient_t, orient_new, w_new, dim)
        for k in range(dim):
            v[i, k] = v_new[r, k]
        _leave_support(i, moved, v, s.pull, s.support, s.acc, m.plane_normal)
        if moved:
            s.counts[C_SHELL] += 1  # (a stamp no earlier rebuild used, as a shell event's)
            for k in range(dim):
                x[i, k] = x_new[r, k]
                s.shell[i, k] = x[i, k]
            status = rebuild_shell(
                i, s.shell, m.mobile, s.nbr, s.nbr_count, s.cell_count, s.cell_body, s.slot,
                s.cell, m.box, m.periodic, m.shell_thickness, m.cell_size, m.ncell, s.nbr_mark,
                s.nbr_old, s.counts[C_SHELL], s.scan, s.scan_body,
            )  # fmt: skip
            if status != FITS:
                return status
        counter[i] += 1  # every event a neighbour predicted with it is stale
    _predict_rows(h, rows)
    return FITS


@njit(cache=True, error_model="numpy")
def set_pulls(h, rows, extra) -> None:  # type: ignore[no-untyped-def]
    """Give engine rows ``rows`` (k,) the pull gravity plus ``extra`` (k, d) [m/s^2] (a
    force over the mass; zero to end one) from the engine's clock on, and predict their
    events again. Each row is first flown to the clock; one resting on a face stays on it
    while the new pull presses it onto the face or along it (the face bears the normal
    part) and lifts off when it pulls it away. Needs an engine with accelerations (``pull``
    not None)."""
    m, s = h.model, h.state
    dim = m.box.shape[0]
    x, v, t = kinematic_views(s.kin, dim)
    counter = s.counter
    pull, support, acc, gravity = s.pull, s.support, s.acc, m.gravity
    T = s.clock[0]
    for r in range(rows.shape[0]):
        i = rows[r]
        free_flight(x, v, acc, gravity, t, i, T)
        for k in range(dim):
            pull[i, k] = gravity[k] + extra[r, k]
        face = support[i]
        if face >= 0:
            p_n = 0.0
            for k in range(dim):
                p_n += pull[i, k] * face_normal(m.plane_normal, dim, face, k)
            if p_n > 0.0:
                face = -1  # (pulled off: it flies)
        set_support(pull, m.plane_normal, support, acc, i, face)
        counter[i] += 1  # every event a neighbour predicted with it is stale
    _predict_rows(h, rows)


@njit(cache=True, error_model="numpy")
def _predict_rows(h, rows) -> None:  # type: ignore[no-untyped-def]
    """Predict the next event of engine rows ``rows`` (k,), each at the clock, and file it in
    the calendar."""
    m, s = h.model, h.state
    x, v, t = kinematic_views(s.kin, m.box.shape[0])
    ev_kind, ev_other, ev_stamp = schedule_views(s.sched)
    counter = s.counter
    T = s.clock[0]
    cal = calendar_of(s)
    for r in range(rows.shape[0]):
        i = rows[r]
        predict(
            i, T, s.kin, x, v, s.acc, m.gravity, t, s.shell, s.support, s.nbr, s.nbr_count,
            s.near, counter, m.radius, m.mobile, m.box, m.inv_box, m.periodic,
            m.shell_thickness, m.plane_point, m.plane_normal, s.ev_time, ev_kind, ev_other,
            ev_stamp,
        )  # fmt: skip
        calendar_update(s.ev_time, i, cal)


@njit(cache=True, error_model="numpy")
def _turn_to(i, r, T, w, orient, orient_t, orient_new, w_new, dim) -> None:  # type: ignore[no-untyped-def]
    """Row ``i`` turned to the clock ``T``, then given orientation and spin row ``r`` of the
    new ones (nothing when the engine keeps no spins, ``w`` None)."""
    if w is not None:
        turn(orient, i, w[i, 0], w[i, 1], w[i, 2], T - orient_t[i], dim)
        orient_t[i] = T
        for k in range(orient_new.shape[1]):
            orient[i, k] = orient_new[r, k]
        for k in range(3):
            w[i, k] = w_new[r, k]


@njit(cache=True, error_model="numpy")
def _leave_support(i, moved, v, pull, support, acc, plane_normal) -> None:  # type: ignore[no-untyped-def]
    """Row ``i`` leaves the face it rests on when moved or given a speed along its normal
    (it then flies, or meets the face at once); it slides on along it otherwise."""
    if pull is not None and support[i] >= 0:
        dim = v.shape[1]
        un = 0.0
        for k in range(dim):
            un += v[i, k] * face_normal(plane_normal, dim, support[i], k)
        if moved or un != 0.0:
            set_support(pull, plane_normal, support, acc, i, -1)


@njit(cache=True, error_model="numpy")
def retire_bodies(h, rows) -> int:  # type: ignore[no-untyped-def]
    """Take engine rows ``rows`` (k,) out of the world for good: each is flown to the clock
    and stopped there (no speed, no spin, no acceleration: it rests on nothing), its shell
    made to overlap no other (its reach NaN: every test of a distance against it fails, so no
    list ever holds it again, whatever is rebuilt), it leaves every neighbour's list, its
    collision counter is raised (every event predicted with it is stale) and its own next
    event is none.

    Returns ``FITS``, or why a neighbour list or cell row did not fit (the caller grows them,
    rebuilds them all and calls again: every value set here is set again the same)."""
    m, s = h.model, h.state
    dim = m.box.shape[0]
    kin = s.kin
    x, v, t = kinematic_views(kin, dim)
    counter = s.counter
    T = s.clock[0]
    for r in range(rows.shape[0]):
        i = rows[r]
        free_flight(x, v, s.acc, m.gravity, t, i, T)
        _stop_turning(i, T, s.w, s.orient, s.orient_t, dim)
        for k in range(dim):
            v[i, k] = 0.0
        _rest_nowhere(i, s.pull, s.support, s.acc)
        s.shell[i, 3] = np.nan  # (every overlap test against its shell fails, both ways)
        s.counts[C_SHELL] += 1  # (a stamp no earlier rebuild used)
        status = rebuild_shell(
            i, s.shell, m.mobile, s.nbr, s.nbr_count, s.cell_count, s.cell_body, s.slot,
            s.cell, m.box, m.periodic, m.shell_thickness, m.cell_size, m.ncell, s.nbr_mark,
            s.nbr_old, s.counts[C_SHELL], s.scan, s.scan_body,
        )  # fmt: skip
        if status != FITS:
            return status
        counter[i] += 1
    _predict_rows(h, rows)  # (at rest on nothing, with no neighbour: no event, ever)
    return FITS


@njit(cache=True, error_model="numpy")
def _stop_turning(i, T, w, orient, orient_t, dim) -> None:  # type: ignore[no-untyped-def]
    """Row ``i`` turned to the clock ``T`` and its spin stopped (nothing when the engine
    keeps no spins, ``w`` None)."""
    if w is not None:
        turn(orient, i, w[i, 0], w[i, 1], w[i, 2], T - orient_t[i], dim)
        orient_t[i] = T
        for k in range(3):
            w[i, k] = 0.0


@njit(cache=True, error_model="numpy")
def _rest_nowhere(i, pull, support, acc) -> None:  # type: ignore[no-untyped-def]
    """Row ``i`` on no face, with no pull and no acceleration: it stays where it is (nothing
    when the world has no gravity: every acceleration is nil already)."""
    if pull is not None:
        support[i] = -1
        for k in range(acc.shape[1]):
            acc[i, k] = 0.0
            pull[i, k] = 0.0
