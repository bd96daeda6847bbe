"""The order in which the event-driven engine numbers bodies: along a Morton (Z-order) curve
through the cells of its grid, so that bodies near in space are near in memory."""

from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

__all__ = ["morton_keys", "spatial_order"]

FloatArray = NDArray[np.float64]

#: Bodies whose Morton keys are computed at a time
KEY_ROWS = 1 << 16


def _spread_bits(c: NDArray[np.uint64], dim: int) -> NDArray[np.uint64]:
    """Insert ``dim - 1`` zero bits between the low bits of ``c`` (Morton encoding)."""
    c = c.copy()
    if dim == 2:
        for shift, mask in (
            (16, 0x0000FFFF0000FFFF),
            (8, 0x00FF00FF00FF00FF),
            (4, 0x0F0F0F0F0F0F0F0F),
            (2, 0x3333333333333333),
            (1, 0x5555555555555555),
        ):
            c = (c | (c << np.uint64(shift))) & np.uint64(mask)
        return c
    c &= np.uint64(0x1FFFFF)
    for shift, mask in (
        (32, 0x1F00000000FFFF),
        (16, 0x1F0000FF0000FF),
        (8, 0x100F00F00F00F00F),
        (4, 0x10C30C30C30C30C3),
        (2, 0x1249249249249249),
    ):
        c = (c | (c << np.uint64(shift))) & np.uint64(mask)
    return c


def morton_keys(cells: NDArray[np.integer]) -> NDArray[np.uint64]:
    """The Morton (Z-order) key of each cell of integer coordinates ``cells`` (M, d) (its
    temporaries are a few times ``cells``: callers pass blocks of :data:`KEY_ROWS`)."""
    m, dim = cells.shape
    key = np.zeros(m, np.uint64)
    for k in range(dim):
        key |= _spread_bits(cells[:, k].astype(np.uint64), dim) << np.uint64(k)
    return key


def spatial_order(
    x: FloatArray, cell_size: FloatArray, ncell: NDArray[np.int64]
) -> NDArray[np.int64]:
    """Bodies sorted along a Morton (Z-order) curve through the cells of the grid.

    Neighbours in space get nearby indices, so the engine's random accesses to neighbours
    mostly hit cache lines it has just used. Bodies in one cell keep their order.
    """
    n = x.shape[0]
    key = np.empty(n, np.uint64)
    for a in range(0, n, KEY_ROWS):  # (a block at a time: the temporaries stay small)
        cells = np.clip(np.floor(x[a : a + KEY_ROWS] / cell_size).astype(np.int64), 0, ncell - 1)
        key[a : a + KEY_ROWS] = morton_keys(cells)
    order: NDArray[np.int64] = np.argsort(key, kind="stable").astype(np.int64, copy=False)
    return order
