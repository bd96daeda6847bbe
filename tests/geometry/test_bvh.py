"""carom.geometry.bvh: the tree over a mesh's triangles finds exactly the triangles whose boxes
meet a query box, as a brute-force scan does."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from carom.geometry.bvh import LEAF, Bvh, build_bvh, query_bvh


def _query(
    tree: Bvh, lo: np.ndarray, hi: np.ndarray, box_lo: np.ndarray, box_hi: np.ndarray
) -> np.ndarray:
    out = np.zeros(4, np.int64)
    while True:
        args = (tree.lo, tree.hi, tree.left, tree.first, tree.count, tree.order)
        found = query_bvh(*args, lo, hi, box_lo, box_hi, out)
        if found <= out.shape[0]:
            return out[:found]
        out = np.zeros(found, np.int64)  # too small: grow and ask again


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(0, 300))
def test_the_tree_finds_what_a_scan_finds(seed: int, n: int) -> None:
    rng = np.random.default_rng(seed)
    corners = rng.uniform(-10.0, 10.0, size=(n, 3, 3)) * [1.0, 1.0, 0.1]
    corners = corners[:, :1] + 0.5 * (corners - corners[:, :1])  # small triangles
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    tree = build_bvh(lo, hi)
    assert np.array_equal(np.sort(tree.order), np.arange(n))
    leaves = tree.count[tree.count > 0]
    assert np.all(leaves <= LEAF)
    for _ in range(20):
        centre = rng.uniform(-10.0, 10.0, size=3)
        half = rng.uniform(0.0, 3.0, size=3)
        box_lo, box_hi = centre - half, centre + half
        found = _query(tree, lo, hi, box_lo, box_hi)
        scan = np.flatnonzero(np.all((lo <= box_hi) & (hi >= box_lo), axis=1))
        assert np.array_equal(np.sort(found), scan)
        assert len(set(found.tolist())) == found.size  # each once


def test_a_query_on_a_large_terrain_finds_the_triangle_under_the_box() -> None:
    # a 200 x 200 grid of triangles on the floor: a small box finds only the one under it
    x, y = np.meshgrid(np.arange(200.0), np.arange(200.0), indexing="ij")
    base = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    corners = np.stack(
        [base, base + np.array([1.0, 0.0, 0.0]), base + np.array([0.0, 1.0, 0.0])], axis=1
    )
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    tree = build_bvh(lo, hi)
    found = _query(tree, lo, hi, np.array([50.2, 60.2, -0.5]), np.array([50.8, 60.8, 0.5]))
    # the triangle at (50, 60) only: its box [50, 51] x [60, 61] holds the query's
    assert found.tolist() == [50 * 200 + 60]
