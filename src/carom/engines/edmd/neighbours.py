"""Neighbour shells and the cell grid that finds them (Smallenburg, EPJ E 45, 22, 2022).

Each moving body ``i`` owns a shell: a sphere of radius ``a_i + delta`` about its centre, the
body's position when the shell was made. While the body stays within ``delta`` of the centre
it stays inside its shell, so it can only touch bodies whose shells overlap its own:
``|c_i - c_j| < a_i + a_j + 2 delta``. Those are its neighbours; the lists are symmetric
between moving bodies. Leaving the shell is an event (:mod:`carom.engines.edmd.loop`) that rebuilds
that one body's shell and list; nothing else is ever rebuilt.

Shells are records ``shell[i] = (cx, cy, cz, a_i)`` (z zero in 2D). The cell grid holds
their bodies in a fixed-capacity row per cell (``cell_body[c, :cell_count[c]]``, with
``slot[i]`` the place of ``i`` in its row), so scanning a cell reads contiguous memory and its
bodies' records can be loaded in parallel. Cells are at least one largest shell diameter wide,
so overlapping shells are always in adjacent cells. Static bodies have a shell (their own
sphere plus ``delta``) but no list: they never move.

Kernels that can run out of room return a status: ``FITS``, ``LIST_FULL`` (a neighbour list)
or ``CELL_FULL`` (a cell row); the caller grows the arrays and rebuilds.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.edmd.jitflags import njit_inlined
from carom.engines.edmd.prefetch import prefetch_row

FITS = 0
LIST_FULL = 1
CELL_FULL = 2


@njit_inlined
def cell_of(shell: np.ndarray, i: int, cell_size: np.ndarray, ncell: np.ndarray) -> int:
    """Linear index of the cell holding shell ``i``'s centre (clamped to the grid)."""
    index = 0
    for k in range(ncell.shape[0]):
        c = math.floor(shell[i, k] / cell_size[k])
        if c < 0:
            c = 0
        elif c >= ncell[k]:
            c = ncell[k] - 1
        index = index * ncell[k] + c
    return index


@njit_inlined
def cell_insert(
    i: int,
    c: int,
    cell_count: np.ndarray,
    cell_body: np.ndarray,
    slot: np.ndarray,
    cell: np.ndarray,
) -> bool:
    """Put body ``i`` at the end of cell ``c``'s row; False if the row is full."""
    n = cell_count[c]
    if n >= cell_body.shape[1]:
        return False
    cell_body[c, n] = i
    cell_count[c] = n + 1
    slot[i] = n
    cell[i] = c
    return True


@njit_inlined
def cell_remove(
    i: int, cell_count: np.ndarray, cell_body: np.ndarray, slot: np.ndarray, cell: np.ndarray
) -> None:
    """Take body ``i`` out of its cell's row (the row's last body fills the gap)."""
    c = cell[i]
    last = cell_count[c] - 1
    moved = cell_body[c, last]
    cell_body[c, slot[i]] = moved
    slot[moved] = slot[i]
    cell_count[c] = last


@njit_inlined
def _list_remove(nbr: np.ndarray, count: np.ndarray, owner: int, body: int) -> None:
    n = count[owner]
    for s in range(n):
        if nbr[owner, s] == body:
            nbr[owner, s] = nbr[owner, n - 1]
            count[owner] = n - 1
            return


@njit_inlined
def _axis_cells(c: int, n: int, periodic: bool) -> tuple[int, int, int, int]:
    """The cell coordinates next to ``c`` (itself included) on an axis of ``n`` cells.

    Returns ``(m, first, second, third)``, the first ``m`` being meant: 3 inside, 2 at a
    wall, every cell once when a periodic axis has fewer than 3 (no cell may be visited twice).
    """
    if periodic and n < 3:
        return n, 0, 1, 2
    lo = c - 1
    hi = c + 1
    if periodic:
        return 3, (lo + n if lo < 0 else lo), c, (hi - n if hi >= n else hi)
    if lo < 0:
        return (2 if hi < n else 1), c, hi, -1
    return (3 if hi < n else 2), lo, c, hi


@njit_inlined
def _axis_images(c: int, n: int, length: float, periodic: bool) -> tuple[float, float, float]:
    """The periodic image shift [m] to add to ``c_i - c_j`` for a body ``j`` in each cell of
    :func:`_axis_cells` (the same order): ``+length`` for the cell reached by wrapping below
    0, ``-length`` above n - 1, else 0.

    For a pair whose shells can overlap this is the nearest image, and the same floating-point
    result as subtracting ``length * floor(d / length + 0.5)``, with no rounding per pair.
    Only valid on periodic axes of at least 3 cells (smaller ones wrap each pair by floor).
    """
    if not periodic or n < 3:
        return 0.0, 0.0, 0.0
    return (length if c == 0 else 0.0), 0.0, (-length if c == n - 1 else 0.0)


@njit_inlined
def _link_overlapping(
    i: int,
    shell: np.ndarray,
    mobile: np.ndarray,
    nbr: np.ndarray,
    count: np.ndarray,
    cell_count: np.ndarray,
    cell_body: np.ndarray,
    cell: np.ndarray,
    box: np.ndarray,
    periodic: bool,
    delta: float,
    ncell: np.ndarray,
    mark: np.ndarray,
    stamp: int,
) -> int:
    """Link ``i`` with every body in the grid whose shell overlaps its shell.

    Each link goes into the list of each moving side, except for bodies marked ``stamp``
    (``i`` is in their lists already; their mark is cleared). Returns ``FITS`` or
    ``LIST_FULL``.
    """
    three = ncell.shape[0] == 3
    capacity = nbr.shape[1]
    # cell coordinates of i's cell, and the neighbouring coordinates on each axis
    rest = cell[i]
    n1 = ncell[1]
    n2 = ncell[2] if three else 1
    c2 = rest % n2
    rest //= n2
    c1 = rest % n1
    c0 = rest // n1
    ax0 = _axis_cells(c0, ncell[0], periodic)
    ax1 = _axis_cells(c1, n1, periodic)
    ax2 = _axis_cells(c2, n2, periodic) if three else (1, 0, 0, 0)
    L0, L1 = box[0], box[1]
    L2 = box[2] if three else 1.0
    inv0, inv1, inv2 = 1.0 / L0, 1.0 / L1, 1.0 / L2
    im0 = _axis_images(c0, ncell[0], L0, periodic)
    im1 = _axis_images(c1, n1, L1, periodic)
    im2 = _axis_images(c2, n2, L2, periodic) if three else (0.0, 0.0, 0.0)
    # wrap each pair by floor only on a periodic axis too short for per-cell images
    wrap0 = periodic and ncell[0] < 3
    wrap1 = periodic and n1 < 3
    wrap2 = periodic and three and n2 < 3
    o0, o1, o2 = shell[i, 0], shell[i, 1], shell[i, 2]
    reach_i = shell[i, 3] + 2.0 * delta
    i_moves = mobile[i]
    # ask for every candidate's record before reading any (their misses then overlap)
    for a in range(1, ax0[0] + 1):
        for b in range(1, ax1[0] + 1):
            row = (ax0[a] * n1 + ax1[b]) * n2
            for c in range(1, ax2[0] + 1):
                index = row + ax2[c]
                for s in range(cell_count[index]):
                    prefetch_row(shell, cell_body[index, s])
    # pass 1, without branches on the candidates: every candidate is written to i's row and
    # kept (found += 1) only if the shells overlap (a mispredicted branch per candidate costs
    # more than the write)
    found = 0
    for a in range(1, ax0[0] + 1):
        s0 = im0[a - 1]
        for b in range(1, ax1[0] + 1):
            s1 = im1[b - 1]
            row = (ax0[a] * n1 + ax1[b]) * n2
            for c in range(1, ax2[0] + 1):
                s2 = im2[c - 1]
                index = row + ax2[c]
                for s in range(cell_count[index]):
                    j = cell_body[index, s]
                    d0 = (o0 - shell[j, 0]) + s0
                    d1 = (o1 - shell[j, 1]) + s1
                    d2 = (o2 - shell[j, 2]) + s2
                    if wrap0:
                        d0 -= L0 * np.floor(d0 * inv0 + 0.5)
                    if wrap1:
                        d1 -= L1 * np.floor(d1 * inv1 + 0.5)
                    if wrap2:
                        d2 -= L2 * np.floor(d2 * inv2 + 0.5)
                    reach = reach_i + shell[j, 3]
                    nbr[i, found] = j
                    found += (d0 * d0 + d1 * d1 + d2 * d2 < reach * reach) & (j != i)
                    if found == capacity:
                        return LIST_FULL  # no room for the next candidate
    # pass 2: i goes into the list of each moving neighbour
    for q in range(found):
        j = nbr[i, q]
        if mark[j] == stamp:
            mark[j] = 0  # a neighbour before and after
        elif mobile[j]:
            if count[j] >= capacity:
                return LIST_FULL
            nbr[j, count[j]] = i
            count[j] += 1
    count[i] = found if i_moves else 0  # a static body's row was only scratch
    return FITS


@njit(cache=True, error_model="numpy")
def build_all(
    shell: np.ndarray,
    mobile: np.ndarray,
    nbr: np.ndarray,
    count: np.ndarray,
    cell_count: np.ndarray,
    cell_body: np.ndarray,
    slot: np.ndarray,
    cell: np.ndarray,
    box: np.ndarray,
    periodic: bool,
    delta: float,
    cell_size: np.ndarray,
    ncell: np.ndarray,
    mark: np.ndarray,
) -> int:
    """Insert every body into an empty grid, linking each overlapping pair once.

    Returns ``FITS``, ``LIST_FULL`` or ``CELL_FULL``.
    """
    cell_count[:] = 0
    count[:] = 0
    for i in range(shell.shape[0]):
        if not cell_insert(
            i, cell_of(shell, i, cell_size, ncell), cell_count, cell_body, slot, cell
        ):
            return CELL_FULL
        # only bodies inserted before i are in the grid: each pair is met once
        status = _link_overlapping(
            i,
            shell,
            mobile,
            nbr,
            count,
            cell_count,
            cell_body,
            cell,
            box,
            periodic,
            delta,
            ncell,
            mark,
            np.int64(-1),  # type: ignore[arg-type]  # none is marked -1; typed, not a literal
        )
        if status != FITS:
            return status
    return FITS


@njit_inlined
def rebuild_shell(
    i: int,
    shell: np.ndarray,
    mobile: np.ndarray,
    nbr: np.ndarray,
    count: np.ndarray,
    cell_count: np.ndarray,
    cell_body: np.ndarray,
    slot: np.ndarray,
    cell: np.ndarray,
    box: np.ndarray,
    periodic: bool,
    delta: float,
    cell_size: np.ndarray,
    ncell: np.ndarray,
    mark: np.ndarray,
    old: np.ndarray,
    stamp: int,
) -> int:
    """Re-centre moving body ``i``'s shell (``shell[i]`` already holds the new centre) and
    rebuild its neighbour list.

    Only the lists of bodies that enter or leave ``i``'s list change: the old neighbours are
    copied to ``old`` and marked ``stamp`` (a number no earlier rebuild used, >= 1), those
    found again are unmarked and left alone, and ``i`` leaves the lists of the rest. Returns
    ``FITS``, ``LIST_FULL`` or ``CELL_FULL`` (the caller grows the arrays and rebuilds them
    all).
    """
    n_old = count[i]
    for s in range(n_old):
        j = nbr[i, s]
        old[s] = j
        mark[j] = stamp
    count[i] = 0
    c = cell_of(shell, i, cell_size, ncell)
    if c != cell[i]:
        cell_remove(i, cell_count, cell_body, slot, cell)
        if not cell_insert(i, c, cell_count, cell_body, slot, cell):
            return CELL_FULL
    status = _link_overlapping(
        i,
        shell,
        mobile,
        nbr,
        count,
        cell_count,
        cell_body,
        cell,
        box,
        periodic,
        delta,
        ncell,
        mark,
        stamp,
    )
    if status != FITS:
        return status
    for s in range(n_old):
        j = old[s]
        if mark[j] == stamp:  # no longer a neighbour
            prefetch_row(nbr, j)
    for s in range(n_old):
        j = old[s]
        if mark[j] == stamp and mobile[j]:
            _list_remove(nbr, count, j, i)
    return FITS


@njit(cache=True, error_model="numpy")
def first_overlap(
    kin: np.ndarray,
    nbr: np.ndarray,
    nbr_count: np.ndarray,
    mobile: np.ndarray,
    radius: np.ndarray,
    box: np.ndarray,
    periodic: bool,
    tolerance: float,
) -> tuple[int, int, float]:
    """The first pair of bodies that overlap by more than ``tolerance`` of the sum of their
    radii, scanning each moving body's list in order: ``(i, j, overlap [m])``, or
    ``(-1, -1, 0.0)`` when none does. Every overlapping pair shares a list (their shells
    overlap), so this finds any overlap there is."""
    dim = box.shape[0]
    for i in range(nbr.shape[0]):
        if not mobile[i]:
            continue
        for s in range(nbr_count[i]):
            j = nbr[i, s]
            d2 = 0.0
            for k in range(dim):
                d = kin[i, k] - kin[j, k]
                if periodic:
                    d -= box[k] * math.floor(d / box[k] + 0.5)
                d2 += d * d
            reach = radius[i] + radius[j]
            overlap = reach - math.sqrt(d2)
            if overlap > tolerance * reach:
                return i, int(j), overlap
    return -1, -1, 0.0
