"""State: everything that changes during a simulation, as plain arrays.

Positions and velocities are stored at each body's own clock ``t`` (lazy clocks); the event
schedule, neighbour lists and cell grid are part of the state too, so a checkpoint of these
arrays resumes a run bit for bit.
"""

from __future__ import annotations

from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from contextlib import nullcontext
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from carom.bodies import Bodies
from carom.engines.edmd.calendar import CAL_EMPTY, CAL_WIDTH
from carom.engines.edmd.model import Model
from carom.engines.edmd.neighbours import SCAN_ROWS, scan_size

__all__ = [
    "KIN_R",
    "KIN_T",
    "KIN_V",
    "KIN_WIDTH",
    "SCHED_KIND",
    "SCHED_OTHER",
    "SCHED_STAMP",
    "SCHED_WIDTH",
    "Records",
    "State",
    "aligned_records",
    "aligned_rows",
    "allocate_state",
    "scratch",
]

N_COUNTS = 8
N_SUMS = 4

# Columns of the kinematic record ``State.kin``: position (x, y, z), clock, velocity, radius.
# One body's record is one 64-byte cache line, which is what a prediction reads of each
# neighbour; in 2D the z columns stay zero.
KIN_T = 3
KIN_V = 4
KIN_R = 7
KIN_WIDTH = 8

# Columns of the schedule record ``State.sched``.
SCHED_KIND = 0
SCHED_OTHER = 1
SCHED_STAMP = 2
SCHED_WIDTH = 3


class State(NamedTuple):
    """The changing part of a simulation of ``N`` bodies (see :mod:`carom.engines.edmd.loop`).

    Attributes
    ----------
    kin : (N, 8) float64
        One record per body: position [m] in columns 0-2, its own clock ``t`` [s] in column
        ``KIN_T``, velocity [m/s] in ``KIN_V`` .. ``KIN_V + 2`` (position and velocity as of
        ``t``: lazy clocks; z zero in 2D), and the radius [m] in ``KIN_R`` (a copy of
        ``Model.radius``, kept here so that a neighbour's data is one cache line).
    acc : (N, d) float64 or None
        Acceleration [m/s^2]: gravity, less the normal part a support bears; zero if static.
        None without gravity (``Model.gravity`` None: every acceleration is zero).
    pull : (N, d) float64 or None
        The acceleration [m/s^2] each body would have flying free: gravity, plus a force's
        over the body's mass through a step that applies one (``World.apply_forces``); zero
        if static or taken out. A support bears its normal part when it presses the body
        onto the support (``acc`` is then the rest). None with ``acc``.
    wraps : (N, d) or (0, d) float64
        How many box lengths each body's position was moved back into a periodic box, per
        axis, since the first force acted (its path unwrapped is ``x + wraps * box``: the
        work a force does through a step). No rows, and no count kept, until then and in a
        box with walls (an array all the same: every kind of box has one set of kernel
        types; a gas never pushed keeps no 24 bytes a body for it).
    w : (N, 3) float64 or None
        Spin [rad/s] (2D: about z, in column 2).
    orient : (N, 4) float64 or None; orient_t : (N,) float64 or None
        Orientation as of the clock ``orient_t`` [s] (2D: angle [rad] in column 0; 3D: unit
        quaternion ``w, x, y, z``): spins change only in rough or frictional collisions,
        which bring it up to date first (:mod:`carom.geometry.rotation`). ``w``, ``orient``
        and ``orient_t`` are None when no body ever spins (``Model.q`` None): every spin
        stays zero and every orientation the identity.
    last_coll : (N,) float64
        Time of each body's last collision [s] (TC model).
    support : (N,) int64 or None
        Wall face or plane a body rests on, -1 when flying. None without gravity (nothing
        rests).
    shell : (N, 4) float64
        Each body's neighbour shell: centre [m] in columns 0-2 (z zero in 2D), the body's
        radius [m] in column 3.
    nbr : (N, K) int32; nbr_count : (N,) int32
        Neighbour lists.
    nbr_mark : (N,) int64; nbr_old : (K,) int32
        Scratch for rebuilding one list (:func:`carom.engines.edmd.neighbours.rebuild_shell`).
    near : (KIN_WIDTH + 1, K) float64
        Scratch for one prediction: the records of a body's neighbours, column by column, and
        their times of impact (:mod:`carom.engines.edmd.predict`).
    scan : (5, M) float64; scan_body : (M,) int32
        Scratch for one scan of the cell grid, M = 3^d B: the candidates' shell records,
        column by column, and the candidates (:mod:`carom.engines.edmd.neighbours`).
    cell, slot : (N,) int32; cell_count : (C,) int32; cell_body : (C, B) int32
        The cell grid of shell centres: cell ``c`` holds bodies ``cell_body[c, :cell_count[c]]``;
        body ``i`` is in cell ``cell[i]`` at place ``slot[i]``.
    ev_time : (N,) float64
        Each body's next event time [s].
    sched : (N, 3) int64
        One record per body: its next event's kind, partner (or face), and the partner's
        collision counter when predicted (columns ``SCHED_KIND``, ``SCHED_OTHER``,
        ``SCHED_STAMP``).
    counter : (N,) int32
        Each body's collision counter: a prediction whose stamp no longer matches its
        partner's counter is stale. Kept apart from ``sched`` and 4 bytes wide, so that the
        counters of a body's neighbours (read for the best partner of each prediction, and
        for the partner of each event taken) share a few cache lines; it wraps after 2^32
        collisions of one body, and is only ever compared for equality.
    cal_head, cal_body, cur_heap, cur_key, cal_f, cal_i
        The event calendar (:mod:`carom.engines.edmd.calendar` describes each array;
        ``cal_body`` (N, 4) int32 holds each body's ``cal_next``, ``cal_prev``, ``cal_loc``
        and ``cur_where``, one record a body).
    clock : (1,) float64
        Simulation time [s].
    counts : (8,) int64; sums : (4,) float64
        Running statistics (:mod:`carom.engines.edmd.codes` names the slots).
    log_time, log_a, log_b, log_impulse, log_un, log_point, log_normal, log_n
        The event log buffer, emptied by :class:`carom.World` as it fills (``log_normal``: the
        unit normal at the contact, from the body to its partner or face).
    """

    kin: NDArray[np.float64]
    acc: NDArray[np.float64] | None
    pull: NDArray[np.float64] | None
    wraps: NDArray[np.float64]
    w: NDArray[np.float64] | None
    orient: NDArray[np.float64] | None
    orient_t: NDArray[np.float64] | None
    last_coll: NDArray[np.float64]
    support: NDArray[np.int64] | None
    shell: NDArray[np.float64]
    nbr: NDArray[np.int32]
    nbr_count: NDArray[np.int32]
    nbr_mark: NDArray[np.int64]
    nbr_old: NDArray[np.int32]
    near: NDArray[np.float64]
    scan: NDArray[np.float64]
    scan_body: NDArray[np.int32]
    cell: NDArray[np.int32]
    slot: NDArray[np.int32]
    cell_count: NDArray[np.int32]
    cell_body: NDArray[np.int32]
    ev_time: NDArray[np.float64]
    sched: NDArray[np.int64]
    counter: NDArray[np.int32]
    cal_head: NDArray[np.int32]
    cal_body: NDArray[np.int32]
    cur_heap: NDArray[np.int32]
    cur_key: NDArray[np.float64]
    cal_f: NDArray[np.float64]
    cal_i: NDArray[np.int64]
    clock: NDArray[np.float64]
    counts: NDArray[np.int64]
    sums: NDArray[np.float64]
    log_time: NDArray[np.float64]
    log_a: NDArray[np.int64]
    log_b: NDArray[np.int64]
    log_impulse: NDArray[np.float64]
    log_un: NDArray[np.float64]
    log_point: NDArray[np.float64]
    log_normal: NDArray[np.float64]
    log_n: NDArray[np.int64]


def aligned_rows(n: int, width: int, dtype: Any, zeroed: bool = False) -> NDArray[Any]:
    """An (n, width) array whose first row starts on a 64-byte cache line, uninitialised
    (or zeros): a neighbour list of 32 4-byte entries is then two lines, never three."""
    item = np.dtype(dtype).itemsize
    buffer = (np.zeros if zeroed else np.empty)(n * width + 64 // item, dtype)
    start = (-buffer.ctypes.data % 64) // item
    rows: NDArray[Any] = buffer[start : start + n * width].reshape(n, width)
    return rows


def aligned_records(n: int, values: NDArray[np.float64] | None = None) -> NDArray[np.float64]:
    """An (n, KIN_WIDTH) float64 array whose rows start on 64-byte cache lines (zeros, or a
    copy of ``values``)."""
    kin = aligned_rows(n, KIN_WIDTH, np.float64, zeroed=values is None)
    if values is not None:
        kin[...] = values
    return kin


#: a new state's kinematic records, spins and orientations (``State.kin``, ``w``, ``orient``)
Records = tuple[NDArray[np.float64], NDArray[np.float64] | None, NDArray[np.float64] | None]

#: Rows filled at a time when a state is built from the bodies: each block's records are
#: written while in cache, and no array of all the bodies is made on the way
FILL_ROWS = 8192
#: Bodies from which a second thread writes the state's constant-filled arrays
FILL_THREAD_BODIES = 1 << 16


def allocate_state(
    bodies: Bodies,
    order: NDArray[np.int64],
    model: Model,
    time: float,
    cell_capacity: int,
    capacity: int,
    log_capacity: int,
    copied: Callable[[Records], None] | None = None,
) -> State:
    """A fresh state at time ``time`` (lists and schedule still empty: the neighbour lists
    ``nbr``, the largest array, are not even written until the build fills them, row by row
    on its threads: :func:`carom.engines.edmd.neighbours.build_all`).

    Parameters
    ----------
    bodies : Bodies
        Their positions and velocities (positions are wrapped into a periodic box here), and
        their spins and orientations unless ``model.q`` is None (no body spins: the state
        has none), in the caller's numbering.
    order : (N,) int64
        Engine row ``e`` holds the caller's body ``order[e]``.
    model : Model
        The model in engine order (radii, which bodies move, gravity, box, grid).
    time : float
        The clock of every body [s].
    cell_capacity, capacity, log_capacity : int
        Bodies per cell row, neighbours per list, collisions the log buffer holds.
    copied : callable, optional
        Called with the state's ``kin``, ``w`` and ``orient`` once the bodies' motion is
        copied into them, before the neighbour lists' memory is first written: the caller
        may drop the bodies' own copy of the motion then (``Bodies.lend``: this function
        holds no reference to it by then), so that the two are never in memory together
        with the lists, and get it back from these if the build fails.
    """
    position, velocity = bodies.position, bodies.velocity
    spinning = model.q is not None  # (as Model.q: None when no body spins)
    angular_velocity = bodies.angular_velocity if spinning else None
    orientation = bodies.orientation if spinning else None
    n, dim = position.shape
    box = model.box
    n_cells = int(np.prod(model.ncell))
    kin = aligned_records(n)
    shell = np.zeros((n, 4))
    gravity = model.gravity
    acc = np.empty((n, dim)) if gravity is not None else None  # (as Model.gravity: a type)
    w = np.empty((n, 3)) if spinning else None
    orient = np.zeros((n, 4)) if spinning else None
    orient_t = np.empty(n) if spinning else None
    nbr = aligned_rows(n, capacity, np.int32)  # first written by the build, row by row
    # the arrays that start at one value each and are written through at the build, filled
    # beside the records (below); nbr_mark and cur_heap stay untouched zeros until
    # used (a rebuild's marks; the heap holds a bucket's few events)
    constant: dict[str, tuple[NDArray[Any], float]] = {
        "last_coll": (np.empty(n), -np.inf),
        "nbr_count": (np.empty(n, np.int32), 0),
        "cell": (np.empty(n, np.int32), 0),
        "slot": (np.empty(n, np.int32), 0),
        "cell_count": (np.empty(n_cells, np.int32), 0),
        "cell_body": (np.empty((n_cells, cell_capacity), np.int32), 0),
        "ev_time": (np.empty(n), np.inf),
        "sched": (np.empty((n, SCHED_WIDTH), np.int64), 0),
        "counter": (np.empty(n, np.int32), 0),
        "cal_head": (np.empty(n + 1, np.int32), -1),
        "cal_body": (np.empty((n, CAL_WIDTH), np.int32), 0),
        "cur_key": (np.empty(n), np.inf),
    }

    def fill_constant() -> None:
        for array, value in constant.values():
            array.fill(value)
        constant["sched"][0][:, SCHED_OTHER] = -1
        constant["cal_body"][0][:] = np.array(CAL_EMPTY, np.int32)

    # Above FILL_THREAD_BODIES a second thread fills those while this one copies the bodies
    # in: a build's first writes to new memory are much of its time (on a virtual machine
    # each new page can cost microseconds), and NumPy's fills run without the GIL.
    with ThreadPoolExecutor(1) if n >= FILL_THREAD_BODIES else nullcontext() as pool:
        filling = pool.submit(fill_constant) if pool is not None else None
        x = position[:0]  # (each block's positions, below)
        for a in range(0, n, FILL_ROWS):
            rows = order[a : a + FILL_ROWS]
            b = a + rows.shape[0]
            x = position[rows]
            if model.periodic:
                x -= box * np.floor(x / box)
            radius = model.radius[a:b]
            kin[a:b, :dim] = x
            kin[a:b, KIN_T] = time
            kin[a:b, KIN_V : KIN_V + dim] = velocity[rows]
            kin[a:b, KIN_R] = radius
            shell[a:b, :dim] = x
            shell[a:b, 3] = radius
            if acc is not None and gravity is not None:
                acc[a:b] = np.where(model.mobile[a:b, None], gravity[None, :], 0.0)
            if w is not None and orient is not None and orient_t is not None:
                assert angular_velocity is not None and orientation is not None
                w[a:b] = angular_velocity[rows]
                orient[a:b, : orientation.shape[1]] = orientation[rows]
                orient_t[a:b] = time
        del position, velocity, angular_velocity, orientation, x  # (copied: see `copied`)
        if copied is not None:
            copied((kin, w, orient))
        if filling is not None:
            filling.result()  # (its error, if any, raised here)
        else:
            fill_constant()
    return State(
        kin=kin,
        acc=acc,
        pull=None if acc is None else acc.copy(),
        wraps=np.zeros((0, dim)),
        support=np.full(n, -1, np.int64) if gravity is not None else None,
        w=w,
        orient=orient,
        orient_t=orient_t,
        shell=shell,
        nbr=nbr,
        **{name: array for name, (array, _) in constant.items()},
        nbr_mark=np.zeros(n, np.int64),
        cur_heap=np.zeros(n, np.int32),
        **scratch(dim, capacity, cell_capacity),
        cal_f=np.array([0.0, 1.0]),
        cal_i=np.zeros(4, np.int64),
        clock=np.array([time]),
        counts=np.zeros(N_COUNTS, np.int64),
        sums=np.zeros(N_SUMS),
        log_time=np.zeros(log_capacity),
        log_a=np.zeros(log_capacity, np.int64),
        log_b=np.zeros(log_capacity, np.int64),
        log_impulse=np.zeros((log_capacity, 3)),
        log_un=np.zeros((log_capacity, 2)),
        log_point=np.zeros((log_capacity, 3)),
        log_normal=np.zeros((log_capacity, 3)),
        log_n=np.zeros(1, np.int64),
    )


def scratch(dim: int, capacity: int, cell_capacity: int) -> dict[str, NDArray[Any]]:
    """The state's scratch arrays for lists of ``capacity`` and cell rows of
    ``cell_capacity``, by field name: ``nbr_old``, ``near``, ``scan`` and ``scan_body``
    (sized again whenever either capacity grows)."""
    size = scan_size(dim, cell_capacity)
    return {
        "nbr_old": np.zeros(capacity, np.int32),
        "near": np.zeros((KIN_WIDTH + 1, capacity)),
        "scan": np.zeros((SCAN_ROWS, size)),
        "scan_body": np.zeros(size, np.int32),
    }
