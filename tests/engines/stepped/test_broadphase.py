"""The broad phase (:func:`carom.engines.stepped.broadphase.find_pairs`, one grid for 2D and
3D): every pair of pieces whose boxes overlap, of two bodies, one active and one dynamic, reported
once and sorted by ``(a, b)``; checked against the brute-force O(P^2) answer. Kept fat boxes
(:func:`refit`, :func:`select_pairs`, :class:`KeptPairs` of :mod:`carom.engines.stepped`,
which both engines use) give the same pairs while rebuilding only when a piece leaves its fat
box, in 2D and 3D."""

from __future__ import annotations

import numpy as np
import pytest

from carom.engines.stepped import broadphase
from carom.engines.stepped.broadphase import (
    FAT,
    KeptPairs,
    find_pairs,
    max_cells_of,
    refit,
    repair_pairs,
    select_pairs,
)
from carom.geometry.bvh import Bvh, build_bvh, empty_bvh


def _brute(
    boxes: np.ndarray, body: np.ndarray, active: np.ndarray, dynamic: np.ndarray
) -> list[tuple[int, int]]:
    d = boxes.shape[1] // 2  # 2D or 3D boxes: lower corner, then upper
    found = []
    for a in range(boxes.shape[0]):
        for b in range(a + 1, boxes.shape[0]):
            ba, bb = body[a], body[b]
            if ba == bb or not (active[ba] or active[bb]) or not (dynamic[ba] or dynamic[bb]):
                continue
            if all(boxes[a, k] <= boxes[b, d + k] and boxes[b, k] <= boxes[a, d + k]
                   for k in range(d)):  # fmt: skip
                found.append((a, b))
    return found


def _find(
    boxes: np.ndarray,
    body: np.ndarray,
    active: np.ndarray,
    dynamic: np.ndarray,
    cell: float,
    out: np.ndarray,
    tree: Bvh | None = None,
) -> int:
    """find_pairs with the pieces of ``tree`` (none, by default) out of the grid."""
    if tree is None:
        tree = empty_bvh(boxes.shape[1] // 2)
    keep = np.ones(boxes.shape[0], np.bool_)
    keep[tree.order] = False
    loose = np.flatnonzero(keep)
    return int(find_pairs(boxes, body, active, dynamic, cell, loose, tree.box, tree.left,
                          tree.first, tree.count, tree.order, out))  # fmt: skip


def _pairs(
    boxes: np.ndarray,
    body: np.ndarray,
    active: np.ndarray,
    dynamic: np.ndarray,
    cell: float,
    tree: Bvh | None = None,
) -> list[tuple[int, int]]:
    pairs = np.zeros((1, 2), np.int64)
    count = _find(boxes, body, active, dynamic, cell, pairs, tree)
    if count < 0:  # too many for the buffer: it says how many, the caller grows it
        pairs = np.zeros((-count, 2), np.int64)
        count = _find(boxes, body, active, dynamic, cell, pairs, tree)
    return [(int(a), int(b)) for a, b in pairs[:count]]


@pytest.mark.parametrize("dims", [2, 3])
def test_random_boxes_give_the_brute_force_pairs_in_order(dims: int) -> None:
    rng = np.random.default_rng(11)
    for trial in range(60):
        pieces = int(rng.integers(0, 120))
        bodies = max(1, pieces // 2)
        body = np.sort(rng.integers(0, bodies, pieces))  # a body's pieces are consecutive
        corner = rng.uniform(-5.0, 5.0, (pieces, dims))
        size = rng.exponential(0.4, (pieces, dims))
        size[rng.random(pieces) < 0.05] *= 30.0  # a few span more than max_cells_of(dims) cells
        boxes = np.hstack([corner, corner + size])
        active = rng.random(bodies) < 0.7
        dynamic = rng.random(bodies) < 0.8
        cell = float(rng.choice([0.25, 0.5, 1.0, 3.0]))
        found = _pairs(boxes, body, active, dynamic, cell)
        assert found == _brute(boxes, body, active, dynamic), trial
        # the same with most pieces of bodies that are not dynamic in a tree, out of the grid
        # (as the engines keep their static bodies' pieces)
        settled = np.flatnonzero(~dynamic[body] & (rng.random(pieces) < 0.8))
        tree = build_bvh(boxes, settled)
        assert _pairs(boxes, body, active, dynamic, cell, tree) == found, trial


def test_a_pair_sharing_many_cells_is_reported_once_and_big_pieces_meet_each_other() -> None:
    # two long overlapping bars over many cells (big pieces, tested against every box), a
    # small box inside both, and a far one touching nothing
    boxes = np.array(
        [
            [0.0, 0.0, 10.0, 1.0],
            [0.5, 0.5, 9.0, 0.8],
            [2.0, 0.2, 2.5, 0.7],
            [20.0, 20.0, 20.5, 20.5],
        ]
    )
    assert max_cells_of(2) < 10.0 / 0.5  # bar 0 covers 20 x 2 cells of 0.5 m
    body = np.arange(4)
    yes = np.ones(4, np.bool_)
    assert _pairs(boxes, body, yes, yes, 0.5) == [(0, 1), (0, 2), (1, 2)]
    assert _pairs(boxes, body, yes, yes, 4.0) == [(0, 1), (0, 2), (1, 2)]  # no big piece


def test_an_unbounded_box_meets_every_box_it_overlaps() -> None:
    # a 3D floor's box: unbounded but below z = 0 (rigid3d.broadphase.piece_boxes); a box
    # resting on it, one above it, and a whole-space box (a tilted plane) meeting both
    inf = np.inf
    boxes = np.array(
        [
            [-inf, -inf, -inf, inf, inf, 0.0],
            [0.0, 0.0, -0.1, 1.0, 1.0, 0.9],
            [0.0, 0.0, 2.0, 1.0, 1.0, 3.0],
            [-inf, -inf, -inf, inf, inf, inf],
        ]
    )
    body = np.arange(4)
    dynamic = np.array([False, True, True, False])
    yes = np.ones(4, np.bool_)
    assert _pairs(boxes, body, yes, dynamic, 0.5) == [(0, 1), (1, 3), (2, 3)]


@pytest.mark.parametrize("few", [0, 64])
@pytest.mark.parametrize("dims", [2, 3])
def test_fat_boxes_give_the_same_pairs_and_rebuild_only_when_a_piece_leaves_its_own(
    dims: int, few: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    # Both engines keep their pairs through fat boxes (KeptPairs, refit, select_pairs); the
    # pairs of pieces that left their fat boxes are mended one by one (repair_pairs) when
    # they are FEW or fewer (64: here always, 55 pieces move) or made again from the grid
    # (FEW = 0: always)
    monkeypatch.setattr(broadphase, "FEW", few)
    rng = np.random.default_rng(5)
    pieces = 60
    body = np.arange(pieces)
    dynamic = np.ones(pieces, np.bool_)
    dynamic[:5] = False  # static pieces: never paired with each other
    everyone = np.ones(pieces, np.bool_)
    reach = rng.uniform(0.1, 0.5, pieces)
    centre = rng.uniform(0.0, 6.0, (pieces, dims))
    fat = np.zeros((pieces, 2 * dims))
    fat[:, :dims] = np.inf  # empty: every piece gets a fat box at the first step
    fat[:, dims:] = -np.inf
    candidates = np.zeros((pieces * pieces, 2), np.int64)
    n_candidates = 0
    rebuilds = 0
    finds: list[int] = []  # the keeper's calls of find_pairs
    kept = KeptPairs(
        pieces, dims, pieces,
        lambda boxes, active, out: finds.append(1) or _find(
            boxes, body, active, dynamic, 0.5, out, tree
        ),
        lambda fat, active, moved, n_moved, old, n_old, out: repair_pairs(
            fat, moved, n_moved, body, active, dynamic, kept.loose,
            (tree.box, tree.left, tree.first, tree.count, tree.order), old, n_old, out,
        ),
    )  # fmt: skip
    # the static pieces never move: settled once (their fat boxes their boxes), in a tree,
    # out of the grid and never refitted (as the engines do)
    kept.settle(np.hstack([centre - reach[:, None], centre + reach[:, None]]), np.arange(5))
    tree = build_bvh(kept.fat, np.arange(5))
    assert kept.loose.tolist() == list(range(5, pieces))
    loose = np.arange(pieces)
    for step in range(200):
        # pieces drift at random, some steps not at all; some sleep now and then
        if step % 3:
            centre[5:] += rng.normal(0.0, 0.02, (pieces - 5, dims))
        active = dynamic & (rng.random(pieces) < 0.9)
        boxes = np.hstack([centre - reach[:, None], centre + reach[:, None]])
        before = fat.copy()
        which = np.zeros(pieces, np.int64)
        moved = refit(boxes, fat, reach, loose, which)
        left = np.any((boxes[:, :dims] < before[:, :dims]) | (boxes[:, dims:] > before[:, dims:]),
                      axis=1)  # fmt: skip
        assert which[:moved].tolist() == np.flatnonzero(left).tolist()
        np.testing.assert_array_equal(fat[~left], before[~left])  # the others keep theirs
        np.testing.assert_allclose(fat[left, :dims], boxes[left, :dims] - FAT * reach[left, None])
        if moved:
            rebuilds += 1
            n_candidates = _find(fat, body, everyone, dynamic, 0.5, candidates)
        pairs = np.zeros((max(n_candidates, 1), 2), np.int64)
        count = select_pairs(candidates, n_candidates, boxes, body, active, dynamic, pairs)
        found = [(int(a), int(b)) for a, b in pairs[:count]]
        assert found == _brute(boxes, body, active, dynamic), step
        # the engines' keeper gives the same, whether it pairs the fat boxes or the swept ones
        count = kept.update(boxes, reach, body, active, dynamic)
        assert [(int(a), int(b)) for a, b in kept.pairs[:count]] == found, step
        if kept._n_fat >= 0:  # the fat pairs it keeps (mended or not) are the grid's
            grid = _pairs(kept.fat, body, everyone, dynamic, 0.5, tree)
            assert kept._fat_pairs[: kept._n_fat].tolist() == [list(p) for p in grid], step
    assert rebuilds <= 200 - 66  # the 66 steps moving nothing (step % 3 == 0, after the first)
    # mended, the grid is used at the first step only (every fat box new then); else at least
    # at every step a piece left its fat box
    assert len(finds) == 1 if few else len(finds) >= rebuilds
