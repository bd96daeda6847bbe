"""The engine's Morton numbering of bodies: a permutation that keeps neighbours close."""

from __future__ import annotations

import numpy as np
import pytest

from carom.engines.edmd.ordering import spatial_order


@pytest.mark.parametrize("dim", [2, 3])
def test_morton_order_is_a_permutation_that_keeps_neighbours_close(dim: int) -> None:
    rng = np.random.default_rng(0)
    n_side = 32 if dim == 2 else 12
    grid = np.stack(np.meshgrid(*([np.arange(n_side) + 0.5] * dim), indexing="ij"), -1)
    x = rng.permutation(grid.reshape(-1, dim))  # a shuffled numbering
    order = spatial_order(x, np.ones(dim), np.full(dim, n_side, np.int64))
    assert np.array_equal(np.sort(order), np.arange(len(x)))
    # mean distance between bodies adjacent in the new numbering: a Z-curve steps to a
    # neighbouring cell most of the time (mean below 2 cells); a shuffled one jumps ~n/2
    step = np.linalg.norm(np.diff(x[order], axis=0), axis=1).mean()
    shuffled = np.linalg.norm(np.diff(x, axis=0), axis=1).mean()
    assert step < 2.0
    assert shuffled > 5 * step
