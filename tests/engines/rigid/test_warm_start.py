"""The warm start: each contact point starts a step with the impulse the same point (same
pieces, same feature id) ended the last step with, found in the sorted impulse cache by a walk
in step with the sorted pairs."""

from __future__ import annotations

import numpy as np

import carom
from carom.engines.rigid import contacts
from carom.shapes import Box


def test_each_contact_finds_its_own_impulses_among_stale_and_missing_keys() -> None:
    world = carom.World(2, [20.0, 10.0], boundary="open", gravity=[0.0, -9.81])
    world.add_body(Box(20.0, 1.0), [10.0, -0.5], kind="static")
    for k in range(4):  # a row of boxes on the ground, side by side
        world.add_body(Box(1.0, 1.0), [8.0 + 1.0 * k, 0.5], density=1.0)
    world.prepare()
    world.run(0.5)  # 30 steps: the boxes rest, the cache holds every pair's impulses
    engine = world._engine
    s = engine.state
    count = int(s.cache_count[0])
    keys = s.cache_keys[:count].copy()
    ids = s.cache_ids[:count].copy()
    impulses = s.cache_impulses[:count].copy()
    # four boxes on the ground (bearing their weight) and three side-by-side touches
    assert count == 7
    assert np.count_nonzero(impulses[:, 0] > 0.0) == 4
    # A cache of distinct made-up impulses, with a stale key before, between and after the
    # real ones and the second real key missing: the walk must skip the stale keys, give
    # the missing pair nothing, and find every other pair its own row.
    gap = int(np.flatnonzero(np.diff(keys) > 1)[0])  # a key between two real ones
    stale = np.array([keys[0] - 1, keys[gap] + 1, keys[-1] + 1])
    assert not np.isin(stale, keys).any()
    kept = np.delete(np.arange(count), 1)
    new_keys = np.concatenate([keys[kept], stale])
    order = np.argsort(new_keys)
    new_impulses = np.concatenate(
        [np.arange(1.0, 1.0 + 4 * kept.size).reshape(-1, 4), np.full((3, 4), 99.0)]
    )
    new_ids = np.concatenate([ids[kept], np.full((3, 2), -1)])
    engine.state = s._replace(
        cache_keys=new_keys[order],
        cache_ids=new_ids[order],
        cache_impulses=new_impulses[order],
        cache_count=np.array([new_keys.size]),
    )
    nc = engine._contacts()
    ci, cf = engine._ci[:nc], engine._cf[:nc]
    n_pieces = engine.model.piece_start.shape[0]
    found = set()
    for m in range(nc):
        key = ci[m, contacts.I_PIECE_A] * n_pieces + ci[m, contacts.I_PIECE_B]
        for j in range(ci[m, contacts.I_COUNT]):
            o = contacts.point_offset(j)
            got = (cf[m, o + contacts.P_JN], cf[m, o + contacts.P_JT])
            if key == keys[1] or key not in keys:
                assert got == (0.0, 0.0)  # no cached impulse for this pair
                continue
            row = int(np.flatnonzero(keys[kept] == key)[0])
            q = int(np.flatnonzero(ids[kept][row] == ci[m, contacts.I_ID0 + j])[0])
            assert got == (new_impulses[row, 2 * q], new_impulses[row, 2 * q + 1])
            found.add(int(key))
    now = {int(ci[m, contacts.I_PIECE_A] * n_pieces + ci[m, contacts.I_PIECE_B]) for m in range(nc)}
    assert found == now & set(keys[kept].tolist())  # every pair kept found its impulses
    assert len(found) == count - 1
