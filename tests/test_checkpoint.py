"""Checkpoints (carom/checkpoint.py): what is not one, older formats and damage are refused by
name; what the file holds; the round trip itself is tested in tests/engines/edmd/test_driver.py
and tests/cli."""

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


def _as_version_12(path) -> None:  # type: ignore[no-untyped-def]
    # Version 12 (carom at bf234ab) wrote the same arrays; its meta kept the event-driven
    # engine's settings under "settings" and the rigid engine's under "rigid", where 13 keeps
    # every engine's under "engine_settings" (a file written by bf234ab was checked to load
    # and run on with the same bits as bf234ab gives, when this reader was written)
    with np.load(path) as data:
        arrays = dict(data)
    meta = json.loads(str(arrays["meta"]))
    kept = meta.pop("engine_settings")
    meta |= {"version": 12, "settings": kept["edmd"], "rigid": kept["rigid"]}
    arrays["meta"] = np.array(json.dumps(meta))
    np.savez(path, **arrays)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_version_12_checkpoint_still_loads_and_runs_on_bit_for_bit(tmp_path, dim) -> None:  # type: ignore[no-untyped-def]
    from carom.engines.stepped.settings import RigidSettings
    from carom.shapes3d import Box

    gas = carom.World(2, [1.0, 1.0], gravity=[0.0, -9.81], t_c=2e-6)
    gas.add_spheres([[0.3, 0.5], [0.7, 0.52]], [[1.0, 0.0], [-1.0, 0.0]], radius=0.05)
    boxes = carom.World(3, [1.0, 1.0, 1.0], gravity=[0, 0, -9.81], rigid=RigidSettings(rate=120.0))
    boxes.add_body(Box([0.1, 0.1, 0.1]), [0.5, 0.5, 0.3], angular_velocity=[1.0, 2.0, 0.0])
    world = gas if dim == 2 else boxes
    world.run(0.25)
    path = tmp_path / "v12.npz"
    world.save(path)
    _as_version_12(path)
    loaded = carom.World.load(path)
    assert loaded.settings.t_c == world.settings.t_c
    assert loaded.rigid_settings == world.rigid_settings
    loaded.run(0.5)
    world.run(0.5)
    np.testing.assert_array_equal(loaded.positions, world.positions)
    np.testing.assert_array_equal(loaded.orientations, world.orientations)


def _as_version_13(path) -> None:  # type: ignore[no-untyped-def]
    # Version 13 (carom at 6865a30) kept each body's collision counter as the event-driven
    # engine's schedule's fourth column, and its calendar's links, place and heap node in four
    # arrays (a file written by 6865a30 was checked to load and run on with the same bits as
    # 6865a30 gives, when this reader was written)
    with np.load(path) as data:
        arrays = dict(data)
    meta = json.loads(str(arrays["meta"]))
    meta["version"] = 13
    arrays["meta"] = np.array(json.dumps(meta))
    counter = arrays.pop("engine.state.counter")
    arrays["engine.state.sched"] = np.column_stack(
        (arrays["engine.state.sched"], counter.astype(np.int64))
    )
    records = arrays.pop("engine.state.cal_body")
    for k, name in enumerate(("cal_next", "cal_prev", "cal_loc", "cur_where")):
        arrays[f"engine.state.{name}"] = records[:, k].copy()
    np.savez(path, **arrays)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_version_13_gas_still_loads_and_runs_on_bit_for_bit(tmp_path, dim) -> None:  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(7)
    side = 8.0
    grid = np.stack(np.meshgrid(*[np.arange(4)] * dim, indexing="ij"), -1).reshape(-1, dim)
    world = carom.World(dim, [side] * dim, "periodic")
    world.add_spheres((grid + 0.5) * side / 4, rng.standard_normal(grid.shape), radius=0.9)
    world.run(2.0)  # (collisions made: the counters and stamps are not all zero)
    assert world.stats.collisions > 100
    path = tmp_path / "v13.npz"
    world.save(path)
    _as_version_13(path)
    loaded = carom.World.load(path)
    loaded.run(6.0)
    world.run(6.0)
    assert loaded.stats.collisions == world.stats.collisions
    np.testing.assert_array_equal(loaded.positions, world.positions)
    np.testing.assert_array_equal(loaded.velocities, world.velocities)


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


def test_checkpoint_without_the_bodies_motion_is_refused(tmp_path) -> None:  # type: ignore[no-untyped-def]
    # a world not yet run has no engine: its positions and velocities are the table's, and a
    # file without them is damaged (orientations and spins may be absent: none are stored)
    world = carom.World(2, [2.0, 2.0])
    world.add_spheres([[0.5, 0.5], [1.5, 1.5]], [[1.0, 0.0], [0.0, 1.0]], radius=0.1)
    path = tmp_path / "still.npz"
    world.save(path)
    assert carom.World.load(path).positions.tolist() == [[0.5, 0.5], [1.5, 1.5]]
    with np.load(path) as data:
        arrays = {name: data[name] for name in data.files if name != "body.velocity"}
    np.savez(path, **arrays)
    with pytest.raises(CaromError, match=r"damaged"):
        carom.World.load(path)


def _members(path) -> set[str]:  # type: ignore[no-untyped-def]
    with np.load(path) as data:
        return set(data.files)


def test_a_gas_of_smooth_spheres_writes_no_identities_or_zeros(tmp_path) -> None:  # type: ignore[no-untyped-def]
    # every sphere unrotated, none spinning, every tensor a sphere's: the table stores none of
    # them, so the file holds none, and the loaded table stores none either; its motion is the
    # engine's (lent), so the file holds no copy of the positions and velocities either (the
    # engine's state has them); the same to the bit as the saved world's, and runs on as it
    # would have
    rng = np.random.default_rng(7)
    world = carom.World(3, [3.0, 3.0, 3.0])
    grid = (np.stack(np.meshgrid(*[np.arange(4)] * 3), -1).reshape(-1, 3) + 0.5) * 0.75
    world.add_spheres(grid, rng.normal(size=(64, 3)), radius=0.1)
    world.run(until=0.3)
    path = tmp_path / "gas.npz"
    world.save(path)
    names = _members(path)
    assert "engine.state.kin" in names
    table = {"body.position", "body.velocity", "body.orientation", "body.angular_velocity"}
    assert not (table | {"body.inertia_tensor"}) & names
    loaded = carom.World.load(path)
    bodies = loaded.bodies
    assert bodies.lent
    assert bodies.unrotated
    assert bodies.still
    assert bodies.stored_tensors is None
    assert np.array_equal(bodies.inertia_tensor, world.bodies.inertia_tensor)
    for name in ("positions", "velocities", "orientations", "angular_velocities"):
        assert np.array_equal(getattr(loaded, name), getattr(world, name)), name
    world.run(until=0.6)
    loaded.run(until=0.6)
    assert np.array_equal(loaded.positions, world.positions)
    assert np.array_equal(loaded.velocities, world.velocities)


def test_spins_turns_and_tensors_are_written_when_there_are_some(tmp_path) -> None:  # type: ignore[no-untyped-def]
    # one spinning sphere among still ones (event-driven), and a turned box (rigid, 3D): what
    # the table stores is written and read back as it was; the spheres' spins and turns are
    # in the event-driven engine's state (the table's motion is lent to it: no copy written)
    world = carom.World(2, [2.0, 2.0])
    world.add_spheres([[0.5, 0.5], [1.5, 1.5]], [[1.0, 0.0], [0.0, 1.0]],
                      angular_velocities=[0.0, -2.5], radius=0.1)  # fmt: skip
    world.run(until=0.5)
    world.save(tmp_path / "spin.npz")
    names = _members(tmp_path / "spin.npz")
    assert {"engine.state.w", "engine.state.orient"} <= names
    assert not {"body.angular_velocity", "body.orientation"} & names
    still = carom.World(2, [2.0, 2.0])  # not run: no engine, the table's own motion
    still.add_spheres([[0.5, 0.5]], angular_velocities=[-2.5], radius=0.1)
    still.save(tmp_path / "still.npz")
    assert {"body.position", "body.angular_velocity"} <= _members(tmp_path / "still.npz")
    assert carom.World.load(tmp_path / "still.npz").angular_velocities[0, 2] == -2.5
    loaded = carom.World.load(tmp_path / "spin.npz")
    assert np.array_equal(loaded.angular_velocities, world.angular_velocities)
    assert np.array_equal(loaded.orientations, world.orientations)

    from carom.shapes3d import Box

    rigid = carom.World(3, box=[4, 4, 4], boundary="open")
    q = np.array([0.8, 0.2, -0.4, 0.4])
    rigid.add_body(Box([1.0, 2.0, 3.0]), [1, 2, 3], orientation=q / np.linalg.norm(q),
                   angular_velocity=[0.3, -1.2, 2.0], mass=6.0)  # fmt: skip
    rigid.save(tmp_path / "box.npz")
    assert {"body.inertia_tensor", "body.orientation"} <= _members(tmp_path / "box.npz")
    back = carom.World.load(tmp_path / "box.npz")
    assert np.array_equal(back.bodies.inertia_tensor, rigid.bodies.inertia_tensor)
    assert np.array_equal(back.orientations, rigid.orientations)
    assert np.array_equal(back.angular_velocities, rigid.angular_velocities)
