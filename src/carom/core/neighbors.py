"""Neighbour shells and the cell grid that finds them (Smallenburg, EPJ E 45, 22, 2022).

Each moving body ``i`` owns a shell: a sphere of radius ``a_i + delta`` about ``origin[i]``,
its position when the shell was made. While the body stays within ``delta`` of the origin it
stays inside its shell, so it can only touch bodies whose shells overlap its own:
``|origin_i - origin_j| < a_i + a_j + 2 delta``. Those are its neighbours; the lists are
symmetric between moving bodies. Leaving the shell is an event (:mod:`carom.core.edmd`) that
rebuilds that one body's shell and list; nothing else is ever rebuilt.

The cell grid holds shell origins, in doubly linked lists per cell; cells are at least one
largest shell diameter wide, so overlapping shells are always in adjacent cells. Static
bodies have a shell (their own sphere plus ``delta``) but no list: they never move.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy", inline="always")
def cell_of(p: np.ndarray, cell_size: np.ndarray, ncell: np.ndarray) -> int:
    """Linear index of the cell holding point ``p`` (clamped to the grid)."""
    index = 0
    for k in range(p.shape[0]):
        c = math.floor(p[k] / cell_size[k])
        if c < 0:
            c = 0
        elif c >= ncell[k]:
            c = ncell[k] - 1
        index = index * ncell[k] + c
    return index


@njit(cache=True, error_model="numpy", inline="always")
def cell_insert(
    i: int, c: int, head: np.ndarray, nxt: np.ndarray, prv: np.ndarray, cell: np.ndarray
) -> None:
    first = head[c]
    nxt[i] = first
    prv[i] = -1
    if first >= 0:
        prv[first] = i
    head[c] = i
    cell[i] = c


@njit(cache=True, error_model="numpy", inline="always")
def cell_remove(
    i: int, head: np.ndarray, nxt: np.ndarray, prv: np.ndarray, cell: np.ndarray
) -> None:
    c = cell[i]
    if prv[i] >= 0:
        nxt[prv[i]] = nxt[i]
    else:
        head[c] = nxt[i]
    if nxt[i] >= 0:
        prv[nxt[i]] = prv[i]
    nxt[i] = -1
    prv[i] = -1


@njit(cache=True, error_model="numpy", inline="always")
def _list_remove(nbr: np.ndarray, count: np.ndarray, owner: int, body: int) -> None:
    n = count[owner]
    for s in range(n):
        if nbr[owner, s] == body:
            nbr[owner, s] = nbr[owner, n - 1]
            count[owner] = n - 1
            return


@njit(cache=True, error_model="numpy", inline="always")
def _scan_range(c: int, n: int, periodic: bool) -> tuple[int, int]:
    if periodic and n < 3:
        return -c, n - 1 - c
    return -1, 1


@njit(cache=True, error_model="numpy", inline="always")
def _link_overlapping(
    i: int,
    origin: np.ndarray,
    radius: np.ndarray,
    mobile: np.ndarray,
    nbr: np.ndarray,
    count: np.ndarray,
    head: np.ndarray,
    nxt: np.ndarray,
    cell: np.ndarray,
    box: np.ndarray,
    periodic: bool,
    delta: float,
    ncell: np.ndarray,
) -> bool:
    """Link ``i`` with every body in the grid whose shell overlaps its shell.

    Each link goes into the list of each moving side. Returns False when a list is full.
    """
    dim = origin.shape[1]
    capacity = nbr.shape[1]
    # cell coordinates of i's cell, and the offsets to scan on each axis: -1..1, or every
    # cell when a periodic axis has fewer than 3 (no cell may be visited twice)
    rest = cell[i]
    c2 = rest % ncell[2] if dim == 3 else 0
    if dim == 3:
        rest //= ncell[2]
    c1 = rest % ncell[1]
    c0 = rest // ncell[1]
    lo0, hi0 = _scan_range(c0, ncell[0], periodic)
    lo1, hi1 = _scan_range(c1, ncell[1], periodic)
    lo2, hi2 = _scan_range(c2, ncell[2], periodic) if dim == 3 else (0, 0)
    reach_i = radius[i] + 2.0 * delta
    inv0 = 1.0 / box[0]
    inv1 = 1.0 / box[1]
    inv2 = 1.0 / box[2] if dim == 3 else 0.0
    for o0 in range(lo0, hi0 + 1):
        for o1 in range(lo1, hi1 + 1):
            for o2 in range(lo2, hi2 + 1):
                index = 0
                inside = True
                for k in range(dim):
                    base = c0 if k == 0 else (c1 if k == 1 else c2)
                    off = o0 if k == 0 else (o1 if k == 1 else o2)
                    c = base + off
                    if periodic:
                        c %= ncell[k]
                    elif c < 0 or c >= ncell[k]:
                        inside = False
                        break
                    index = index * ncell[k] + c
                if not inside:
                    continue
                j = head[index]
                while j >= 0:
                    if j != i:
                        reach = reach_i + radius[j]
                        d2 = 0.0
                        for k in range(dim):
                            d = origin[i, k] - origin[j, k]
                            if periodic:
                                inv = inv0 if k == 0 else (inv1 if k == 1 else inv2)
                                d -= box[k] * math.floor(d * inv + 0.5)
                            d2 += d * d
                        if d2 < reach * reach:
                            if (mobile[i] and count[i] >= capacity) or (
                                mobile[j] and count[j] >= capacity
                            ):
                                return False
                            if mobile[i]:
                                nbr[i, count[i]] = j
                                count[i] += 1
                            if mobile[j]:
                                nbr[j, count[j]] = i
                                count[j] += 1
                    j = nxt[j]
    return True


@njit(cache=True, error_model="numpy")
def build_all(
    origin: np.ndarray,
    radius: np.ndarray,
    mobile: np.ndarray,
    nbr: np.ndarray,
    count: np.ndarray,
    head: np.ndarray,
    nxt: np.ndarray,
    prv: np.ndarray,
    cell: np.ndarray,
    box: np.ndarray,
    periodic: bool,
    delta: float,
    cell_size: np.ndarray,
    ncell: np.ndarray,
) -> bool:
    """Insert every body into an empty grid, linking each overlapping pair once."""
    head[:] = -1
    count[:] = 0
    for i in range(origin.shape[0]):
        cell_insert(i, cell_of(origin[i], cell_size, ncell), head, nxt, prv, cell)
        # only bodies inserted before i are in the grid: each pair is met once
        if not _link_overlapping(
            i,
            origin,
            radius,
            mobile,
            nbr,
            count,
            head,
            nxt,
            cell,
            box,
            periodic,
            delta,
            ncell,
        ):
            return False
    return True


@njit(cache=True, error_model="numpy", inline="always")
def rebuild_shell(
    i: int,
    origin: np.ndarray,
    radius: np.ndarray,
    mobile: np.ndarray,
    nbr: np.ndarray,
    count: np.ndarray,
    head: np.ndarray,
    nxt: np.ndarray,
    prv: np.ndarray,
    cell: np.ndarray,
    box: np.ndarray,
    periodic: bool,
    delta: float,
    cell_size: np.ndarray,
    ncell: np.ndarray,
) -> bool:
    """Re-centre moving body ``i``'s shell on ``origin[i]`` and rebuild its neighbour list.

    Returns False when a list is full (the caller grows the lists and rebuilds them all).
    """
    for s in range(count[i]):
        j = nbr[i, s]
        if mobile[j]:
            _list_remove(nbr, count, j, i)
    count[i] = 0
    cell_remove(i, head, nxt, prv, cell)
    cell_insert(i, cell_of(origin[i], cell_size, ncell), head, nxt, prv, cell)
    return _link_overlapping(
        i, origin, radius, mobile, nbr, count, head, nxt, cell, box, periodic, delta, ncell
    )
