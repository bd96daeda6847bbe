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
from carom.engines.edmd.threads import in_ranges

FITS = 0
LIST_FULL = 1
CELL_FULL = 2

# bodies of a cell's row copied by a loop of fixed length in a scan (a cell holds about 5
# in 3D at packing 0.3, 3 in 2D at 0.5; the engine's rows hold at least 8)
HEAD = 8

SCAN_ROWS = 5  # rows of the scan scratch: a candidate's shell record, and whether it is kept


def scan_size(dim: int, cell_capacity: int) -> int:
    """Columns of the scan scratch: every body of the 3^dim cells a scan visits."""
    return int(3**dim * cell_capacity)


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
def axis_cells(c: int, n: int, periodic: bool) -> tuple[int, int, int, int]:
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
def _axis_gaps(o: float, c: int, h: float, n: int, periodic: bool) -> tuple[float, float, float]:
    """How far a point at ``o`` [m] in cell ``c`` (of side ``h``, ``n`` on the axis) lies from
    each cell :func:`axis_cells` gives, in its order (0 for its own cell, and for every cell
    of a periodic axis of fewer than 3)."""
    if periodic and n < 3:
        return 0.0, 0.0, 0.0
    below = max(o - c * h, 0.0)
    above = max((c + 1) * h - o, 0.0)
    if not periodic and c == 0:
        return 0.0, above, 0.0
    return below, 0.0, above


@njit_inlined
def _gather_candidates(
    i: int,
    shell: np.ndarray,
    cell_count: np.ndarray,
    cell_body: np.ndarray,
    cell: np.ndarray,
    box: np.ndarray,
    periodic: bool,
    delta: float,
    ncell: np.ndarray,
    scan_body: np.ndarray,
) -> int:
    """Copy into ``scan_body`` (M,) int32, M = 27 times the cell capacity, every body filed in
    the cells around ``i``'s (``i`` itself among them) that a shell overlapping ``i``'s could
    be centred in, cell by cell in order, each row in its order; returns how many.

    A cell is skipped when it lies farther from ``i``'s shell centre than ``i``'s radius,
    twice the shell thickness and the largest radius: cells are at least a shell diameter
    wide (``grid_cells``), so half a cell bounds the largest radius and a thickness. About
    a quarter of the cells and their candidates go in 3D (a corner cell is needed half the
    time, an edge cell four times in five); the lists are the same, in the same order.

    A loop per cell whose length is the cell's count mispredicts its exit at every cell, 27
    times a rebuild in 3D (measured: half the rebuild's time), so each cell's row is copied
    with a loop of fixed length (``HEAD`` bodies, and the rest only for a fuller cell). On a
    periodic axis of 3 cells or more each cell is reached once.
    """
    three = ncell.shape[0] == 3
    # cell coordinates of i's cell, and the neighbouring coordinates on each axis
    rest = cell[i]
    n1 = ncell[1]
    n2 = ncell[2] if three else 1
    c2 = rest % n2
    rest //= n2
    c1 = rest % n1
    c0 = rest // n1
    ax0 = axis_cells(c0, ncell[0], periodic)
    ax1 = axis_cells(c1, n1, periodic)
    ax2 = axis_cells(c2, n2, periodic) if three else (1, 0, 0, 0)
    # the gaps from i's shell centre to each, and the farthest a listed centre can be
    h0, h1 = box[0] / ncell[0], box[1] / n1
    h2 = box[2] / n2 if three else h0
    g0 = _axis_gaps(shell[i, 0], c0, h0, ncell[0], periodic)
    g1 = _axis_gaps(shell[i, 1], c1, h1, n1, periodic)
    g2 = _axis_gaps(shell[i, 2], c2, h2, n2, periodic) if three else (0.0, 0.0, 0.0)
    far = (shell[i, 3] + delta + 0.5 * min(h0, h1, h2)) * (1.0 + 1e-9)  # (round-off)
    far2 = far * far
    # the candidates, cell by cell (a fixed-length copy; only the first cell_count count)
    head = min(HEAD, cell_body.shape[1])
    m = 0
    for a in range(1, ax0[0] + 1):
        for b in range(1, ax1[0] + 1):
            row = (ax0[a] * n1 + ax1[b]) * n2
            gap2 = g0[a - 1] * g0[a - 1] + g1[b - 1] * g1[b - 1]
            for c in range(1, ax2[0] + 1):
                if gap2 + g2[c - 1] * g2[c - 1] > far2:
                    continue
                index = row + ax2[c]
                k = cell_count[index]
                for s in range(head):
                    scan_body[m + s] = cell_body[index, s]
                if k > head:
                    for s in range(head, k):
                        scan_body[m + s] = cell_body[index, s]
                m += k
    return m


@njit_inlined
def _list_overlapping(
    i: int,
    m: int,
    shell: np.ndarray,
    nbr: np.ndarray,
    box: np.ndarray,
    periodic: bool,
    delta: float,
    scan: np.ndarray,
    scan_body: np.ndarray,
) -> int:
    """Write into ``i``'s row of ``nbr`` each of the ``m`` candidates ``scan_body[:m]``
    (:func:`_gather_candidates`) whose shell overlaps ``i``'s, in their order; returns how
    many, or -1 when they do not fit the row. ``scan`` (5, M) float64 is scratch.

    The candidates' shell records are asked for all at once, copied column by column, and
    the distances computed in one loop LLVM vectorises. On a periodic axis each pair takes
    the nearest image by ``floor``: for a pair whose shells can overlap that is the image of
    the cell it was found in, since an axis of 3 cells or more reaches each cell once and a
    shell is narrower than a cell. Every candidate is written to the row, and only a kept one
    advances it (a mispredicted branch per candidate costs more than the write), so the row
    may hold one more candidate after the last kept.
    """
    three = box.shape[0] == 3
    capacity = nbr.shape[1]
    # ask for every candidate's record before reading any (their misses then overlap)
    for q in range(m):
        prefetch_row(shell, scan_body[q])
    for q in range(m):
        j = scan_body[q]
        scan[0, q] = shell[j, 0]
        scan[1, q] = shell[j, 1]
        scan[2, q] = shell[j, 2]
        scan[3, q] = shell[j, 3]
    L0, L1 = box[0], box[1]
    L2 = box[2] if three else 1.0
    inv0, inv1, inv2 = 1.0 / L0, 1.0 / L1, 1.0 / L2
    o0, o1, o2 = shell[i, 0], shell[i, 1], shell[i, 2]
    reach_i = shell[i, 3] + 2.0 * delta
    for q in range(m):
        d0 = o0 - scan[0, q]
        d1 = o1 - scan[1, q]
        d2 = o2 - scan[2, q]
        if periodic:
            d0 -= L0 * np.floor(d0 * inv0 + 0.5)
            d1 -= L1 * np.floor(d1 * inv1 + 0.5)
            d2 -= L2 * np.floor(d2 * inv2 + 0.5)
        reach = reach_i + scan[3, q]
        scan[4, q] = 1.0 if d0 * d0 + d1 * d1 + d2 * d2 < reach * reach else 0.0
    found = 0
    for q in range(m):
        j = scan_body[q]
        nbr[i, found] = j
        found += (scan[4, q] != 0.0) & (j != i)
        if found == capacity:
            return -1  # no room for the next candidate
    return found


@njit(cache=True, error_model="numpy")
def fill_cells(
    shell: np.ndarray,
    cell_count: np.ndarray,
    cell_body: np.ndarray,
    slot: np.ndarray,
    cell: np.ndarray,
    cell_size: np.ndarray,
    ncell: np.ndarray,
) -> int:
    """File every body in an emptied grid, in the order of their numbers (so each row holds
    its bodies in increasing numbers). Returns ``FITS`` or ``CELL_FULL``."""
    cell_count[:] = 0
    for i in range(shell.shape[0]):
        if not cell_insert(
            i, cell_of(shell, i, cell_size, ncell), cell_count, cell_body, slot, cell
        ):
            return CELL_FULL
    return FITS


@njit(cache=True, error_model="numpy", nogil=True)
def link_earlier(
    lo: int,
    hi: int,
    shell: np.ndarray,
    nbr: np.ndarray,
    count: np.ndarray,
    cell_count: np.ndarray,
    cell_body: np.ndarray,
    cell: np.ndarray,
    box: np.ndarray,
    periodic: bool,
    delta: float,
    ncell: np.ndarray,
) -> int:
    """For each body ``i`` of ``lo <= i < hi``, list in its row the bodies numbered below it
    whose shells overlap its own (``count[i]`` of them), in the order in which a grid filled
    with the bodies up to ``i`` gives them: its rows are the first entries of the rows of a
    grid filled in the order of the numbers (:func:`fill_cells`). Returns ``FITS`` or
    ``LIST_FULL``.

    Reads the grid and the shells and writes only rows ``lo`` to ``hi``, each zeroed first
    (a fresh state's rows are unwritten memory): ranges of bodies run on threads at once
    (the GIL released), each writing its own part of the largest array. Its scratch is its
    own.
    """
    size = 3 ** ncell.shape[0] * cell_body.shape[1]  # (scan_size)
    scan = np.empty((SCAN_ROWS, size))
    scan_body = np.empty(size, np.int32)
    for i in range(lo, hi):
        for s in range(nbr.shape[1]):
            nbr[i, s] = 0  # (the row's first write: a fresh state leaves it unwritten)
        m = _gather_candidates(
            i, shell, cell_count, cell_body, cell, box, periodic, delta, ncell, scan_body
        )
        # only those numbered up to i (the first of each row), in the same order: one flat
        # pass without a branch (a count per cell was 1.5x slower)
        kept = 0
        for q in range(m):
            j = scan_body[q]
            scan_body[kept] = j
            kept += j <= i
        found = _list_overlapping(i, kept, shell, nbr, box, periodic, delta, scan, scan_body)
        if found < 0:
            return LIST_FULL
        count[i] = found
    return FITS


@njit(cache=True, error_model="numpy")
def link_later(mobile: np.ndarray, nbr: np.ndarray, count: np.ndarray) -> int:
    """Complete the lists that :func:`link_earlier` began: each body, in the order of their
    numbers, goes into the list of each moving neighbour numbered below it, after the
    bodies already there; a static body's row was only scratch (``count`` 0). Returns
    ``FITS`` or ``LIST_FULL``."""
    capacity = nbr.shape[1]
    for i in range(nbr.shape[0]):
        for q in range(count[i]):  # (the bodies below i: none has been added to i's list)
            j = nbr[i, q]
            if mobile[j]:
                if count[j] >= capacity:
                    return LIST_FULL
                nbr[j, count[j]] = i
                count[j] += 1
        if not mobile[i]:
            count[i] = 0
    return FITS


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
) -> int:
    """File every body in an empty grid and link each overlapping pair.

    The lists are those of inserting the bodies one by one in the order of their numbers,
    each linked with the bodies already in the grid (in the order of the scan) and then
    appended to each moving one's list, to the last entry. The scans, nearly all the work,
    run on threads over ranges of bodies (:func:`carom.engines.edmd.threads.in_ranges`):
    each body's own scan reads only the grid, the appends follow in one pass, so the lists
    are the same whatever the number of threads. Returns ``FITS``, ``LIST_FULL`` or
    ``CELL_FULL``.
    """
    if fill_cells(shell, cell_count, cell_body, slot, cell, cell_size, ncell) != FITS:
        return CELL_FULL
    linked = in_ranges(
        link_earlier,
        shell.shape[0],
        shell,
        nbr,
        count,
        cell_count,
        cell_body,
        cell,
        box,
        periodic,
        delta,
        ncell,
    )
    if any(status != FITS for status in linked):
        return LIST_FULL
    return int(link_later(mobile, nbr, count))


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
    scan: np.ndarray,
    scan_body: np.ndarray,
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
    capacity = nbr.shape[1]
    m = _gather_candidates(
        i, shell, cell_count, cell_body, cell, box, periodic, delta, ncell, scan_body
    )
    found = _list_overlapping(i, m, shell, nbr, box, periodic, delta, scan, scan_body)
    if found < 0:
        return LIST_FULL
    # i goes into the list of each moving neighbour not marked (a neighbour before and after)
    for q in range(found):
        j = nbr[i, q]
        if mark[j] == stamp:
            mark[j] = 0
        elif mobile[j]:
            if count[j] >= capacity:
                return LIST_FULL
            nbr[j, count[j]] = i
            count[j] += 1
    count[i] = found if mobile[i] else 0  # (a static body's row would be only scratch)
    for s in range(n_old):
        j = old[s]
        if mark[j] == stamp:  # no longer a neighbour
            prefetch_row(nbr, j)
    for s in range(n_old):
        j = old[s]
        if mark[j] == stamp and mobile[j]:
            _list_remove(nbr, count, j, i)
    return FITS


@njit(cache=True, error_model="numpy", nogil=True)
def first_overlap(
    lo: int,
    hi: int,
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
    radii, scanning the list of each moving body ``i``, ``lo <= i < hi``, in order:
    ``(i, j, overlap [m])``, or ``(-1, -1, 0.0)`` when none does (ranges of bodies may run
    on threads at once). Every overlapping pair shares a list (their shells
    overlap), so this finds any overlap there is. A pair of moving bodies is in both their
    lists and is measured once, from the first body's."""
    dim = box.shape[0]
    for i in range(lo, hi):
        if not mobile[i]:
            continue
        for s in range(nbr_count[i]):
            j = nbr[i, s]
            if j < i and mobile[j]:
                continue  # measured from j's list
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
