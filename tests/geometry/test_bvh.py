"""carom.geometry.bvh: the tree over a mesh's triangles finds exactly the triangles whose boxes
meet a query box, as a brute-force scan does."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from carom.geometry.bvh import LEAF, STACK, Bvh, build_bvh, query_bvh


def _query(tree: Bvh, boxes: np.ndarray, query: np.ndarray) -> np.ndarray:
    out = np.zeros(4, np.int64)
    while True:
        args = (tree.box, tree.left, tree.first, tree.count, tree.order)
        found = query_bvh(*args, boxes, query, out, np.empty(STACK, np.int64))
        if found <= out.shape[0]:
            return out[:found]
        out = np.zeros(found, np.int64)  # too small: grow and ask again


@settings(max_examples=60, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(0, 300), dims=st.sampled_from([2, 3]))
def test_the_tree_finds_what_a_scan_finds(seed: int, n: int, dims: int) -> None:
    rng = np.random.default_rng(seed)
    corners = rng.uniform(-10.0, 10.0, size=(n, 3, dims)) * ([1.0, 1.0, 0.1][:dims])
    corners = corners[:, :1] + 0.5 * (corners - corners[:, :1])  # small triangles
    lo, hi = corners.min(axis=1), corners.max(axis=1)
    boxes = np.concatenate([lo, hi], axis=1)
    # some boxes left out of the tree: the query never finds them
    which = np.flatnonzero(rng.random(n) < 0.8)
    tree = build_bvh(boxes, which)
    assert np.array_equal(np.sort(tree.order), which)
    leaves = tree.count[tree.count > 0]
    assert np.all(leaves <= LEAF)
    for _ in range(20):
        centre = rng.uniform(-10.0, 10.0, size=dims)
        half = rng.uniform(0.0, 3.0, size=dims)
        query = np.concatenate([centre - half, centre + half])
        found = _query(tree, boxes, query)
        meets = np.all((lo <= centre + half) & (hi >= centre - half), axis=1)
        scan = np.intersect1d(np.flatnonzero(meets), which)
        assert np.array_equal(np.sort(found), scan)
        assert len(set(found.tolist())) == found.size  # each once
    # every node's box holds its children's (or its leaf's boxes)
    for node in range(tree.box.shape[0]):
        if tree.count[node] > 0:
            members = boxes[tree.order[tree.first[node] : tree.first[node] + tree.count[node]]]
        elif tree.left[node] > 0:
            members = tree.box[[tree.left[node], tree.left[node] + 1]]
        else:
            continue
        assert np.all(tree.box[node, :dims] <= members[:, :dims].min(axis=0))
        assert np.all(tree.box[node, dims:] >= members[:, dims:].max(axis=0))


def test_a_query_on_a_large_terrain_finds_the_triangle_under_the_box() -> None:
    # a 200 x 200 grid of triangles on the floor: a small box finds only the one under it
    x, y = np.meshgrid(np.arange(200.0), np.arange(200.0), indexing="ij")
    base = np.column_stack([x.ravel(), y.ravel(), np.zeros(x.size)])
    corners = np.stack(
        [base, base + np.array([1.0, 0.0, 0.0]), base + np.array([0.0, 1.0, 0.0])], axis=1
    )
    boxes = np.concatenate([corners.min(axis=1), corners.max(axis=1)], axis=1)
    tree = build_bvh(boxes)
    found = _query(tree, boxes, np.array([50.2, 60.2, -0.5, 50.8, 60.8, 0.5]))
    # the triangle at (50, 60) only: its box [50, 51] x [60, 61] holds the query's
    assert found.tolist() == [50 * 200 + 60]


def test_a_plane_cannot_go_in_the_tree() -> None:
    boxes = np.array([[0.0, 0.0, 1.0, 1.0], [-np.inf, -np.inf, np.inf, 0.0]])
    with pytest.raises(ValueError, match="finite"):
        build_bvh(boxes)
    assert build_bvh(boxes, np.array([0])).order.tolist() == [0]
