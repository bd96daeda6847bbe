"""The warm start's cache search: each contact point starts a step with the impulse the same
point ended the last step with, found in the sorted impulse cache by one walk in step with the
sorted pairs (:func:`carom.engines.stepped.contacts.find_cached`)."""

from __future__ import annotations

import numpy as np

from carom.engines.stepped.contacts import find_cached


def _walk(keys: np.ndarray, queries: np.ndarray) -> list[int]:
    """Rows of the increasing ``queries`` in ``keys``, as the narrow phase asks for them."""
    rows = []
    cursor = 0
    for key in queries.tolist():
        row, cursor = find_cached(keys, keys.size, key, cursor)
        rows.append(row)
    return rows


def _search(keys: np.ndarray, queries: np.ndarray) -> list[int]:
    """The same rows by a binary search per key (the reference)."""
    if keys.size == 0:
        return [-1] * queries.size
    at = np.searchsorted(keys, queries)
    hit = (at < keys.size) & (keys[np.minimum(at, keys.size - 1)] == queries)
    return np.where(hit, at, -1).tolist()


def test_stale_keys_are_skipped_missing_keys_get_nothing_and_present_keys_their_row() -> None:
    # the cache from the last step: 2 and 9 are stale (no pair now), the pair 5 is new
    keys = np.array([2, 3, 4, 7, 9, 12, 20])
    queries = np.array([3, 4, 5, 7, 12, 20])
    assert _walk(keys, queries) == [1, 2, -1, 3, 5, 6]
    assert _walk(keys, np.array([0, 1, 21])) == [-1, -1, -1]  # before and after every key
    assert _walk(keys[:0], queries) == [-1] * queries.size  # an empty cache


def test_the_walk_finds_what_a_binary_search_finds() -> None:
    rng = np.random.default_rng(13)
    for _ in range(200):
        keys = np.unique(rng.integers(0, 60, rng.integers(0, 30)))
        queries = np.unique(rng.integers(0, 60, rng.integers(0, 30)))
        assert _walk(keys, queries) == _search(keys, queries)
