"""Checkpoints (carom/checkpoint.py): what is not one, older formats and damage are refused by
name; the round trip itself is tested in tests/engines/edmd/test_driver.py and tests/cli."""

from __future__ import annotations

import json

import numpy as np
import pytest

import carom
from carom import CaromError


def test_checkpoint_that_is_not_one(tmp_path) -> None:  # type: ignore[no-untyped-def]
    bad = tmp_path / "notes.npz"
    bad.write_text("hello")
    with pytest.raises(CaromError, match=r"cannot read checkpoint"):
        carom.World.load(bad)


def test_checkpoint_from_another_state_layout(tmp_path) -> None:  # type: ignore[no-untyped-def]
    # A checkpoint whose version differs (an older engine layout) is refused by name, not with
    # a KeyError from a missing array.
    world = carom.World(2, [2.0, 2.0])
    world.add_spheres([[0.5, 0.5], [1.5, 1.5]], [[1.0, 0.0], [0.0, 1.0]], radius=0.1)
    world.run(until=0.5)
    path = tmp_path / "old.npz"
    world.save(path)
    with np.load(path) as data:
        arrays = dict(data)
    meta = json.loads(str(arrays["meta"]))
    meta["version"] = 1
    arrays["meta"] = np.array(json.dumps(meta))
    np.savez(path, **arrays)
    with pytest.raises(CaromError, match=r"format version 1, this carom reads version \d"):
        carom.World.load(path)


def test_checkpoint_of_the_older_format_is_refused_by_name(tmp_path) -> None:  # type: ignore[no-untyped-def]
    # carom before the two-engine layout wrote format 'carom-world' version 3 (no orientations)
    path = tmp_path / "v3.npz"
    np.savez(path, meta=np.array(json.dumps({"format": "carom-world", "version": 3})))
    with pytest.raises(CaromError, match=r"written by an older carom .*'carom-world', version 3"):
        carom.World.load(path)


def test_truncated_checkpoint_is_refused(tmp_path) -> None:  # type: ignore[no-untyped-def]
    world = carom.World(2, [2.0, 2.0])
    world.add_spheres([[0.5, 0.5], [1.5, 1.5]], [[1.0, 0.0], [0.0, 1.0]], radius=0.1)
    world.run(until=0.5)
    path = tmp_path / "cut.npz"
    world.save(path)
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    with pytest.raises(CaromError, match=r"checkpoint .*cut.npz"):
        carom.World.load(path)


@pytest.mark.parametrize("drop", ["state.orient", "state.support"])
def test_checkpoint_with_half_of_a_group_of_arrays_is_refused(tmp_path, drop) -> None:  # type: ignore[no-untyped-def]
    # spins, orientations and their clocks are written together or not at all (a state
    # without spins has none), as are accelerations and supports (none without gravity): a
    # file with one of a group missing is damaged
    world = carom.World(2, [2.0, 2.0], gravity=[0.0, -1.0])
    x, v = [[0.5, 0.5], [1.5, 1.5]], [[1.0, 0.0], [0.0, 1.0]]
    world.add_spheres(x, v, angular_velocities=[1.0, 0.0], radius=0.1)
    world.run(until=0.5)
    path = tmp_path / "half.npz"
    world.save(path)
    with np.load(path) as data:
        arrays = {name: data[name] for name in data.files if not name.endswith(drop)}
    assert len(arrays) < len(np.load(path).files)
    np.savez(path, **arrays)
    with pytest.raises(CaromError, match=r"damaged|missing"):
        carom.World.load(path)
