"""The table of engines (issue 42, item 1): an engine plugs in through its entry alone. A toy
engine (tests/engines/toy.py: free flight, no collisions) is registered here and runs a World,
a scene file with its H5MD trajectory, and a checkpoint, with nothing else in carom naming it;
its positions are the closed form of free flight, so every check is exact."""

from __future__ import annotations

import json
import textwrap
from collections.abc import Iterator
from pathlib import Path

import numpy as np
import pytest

import carom
from carom.engines import registry
from carom.engines.registry import EngineEntry
from carom.errors import CaromError
from carom.io.h5md import read_trajectory
from carom.run.runner import Outputs, run_scene

TOY = "tests.engines.toy"
X0 = np.array([[0.2, 0.5], [0.8, 0.5], [0.5, 0.9]])
V0 = np.array([[1.0, 0.0], [-1.0, 0.0], [0.0, 0.25]])
G = np.array([0.0, -9.81])


@pytest.fixture
def toy() -> Iterator[EngineEntry]:
    entry = registry.register(EngineEntry("toy", "free-flight toy", {2: TOY, 3: TOY}))
    try:
        yield entry
    finally:
        registry.unregister("toy")


def flight(t: float) -> tuple[np.ndarray, np.ndarray]:
    # free flight from t = 0, written as the toy engine computes it, so equal bit for bit
    return X0 + V0 * t + 0.5 * G * t * t, V0 + G * t


def toy_world() -> carom.World:
    world = carom.World(2, [1.0, 1.0], gravity=G, engine="toy")
    world.add_spheres(X0, V0, radius=0.05)
    return world


def test_the_built_in_engines_are_the_tables_first_rows() -> None:
    names = [entry.name for entry in registry.engines()]
    assert names[:2] == ["edmd", "rigid"]
    assert registry.find("event-driven").name == "edmd"  # scene files before the table
    assert registry.find("rigid3d").name == "rigid"  # checkpoints before the table
    with pytest.raises(CaromError, match=r"no engine 'warp'; the engines are 'edmd', 'rigid'"):
        registry.find("warp")


@pytest.mark.usefixtures("toy")
def test_a_registered_engine_runs_a_world() -> None:
    world = toy_world()
    assert world.engine_name == "toy"
    frames = world.run(0.5, frame_interval=0.25)
    assert frames is not None
    for frame in frames:
        x, v = flight(frame.time)
        np.testing.assert_array_equal(frame.positions, x)  # through each other: no collision
        np.testing.assert_array_equal(frame.velocities, v)
    assert [f.time for f in frames] == [0.25, 0.5]


def test_a_name_is_registered_once(toy: EngineEntry) -> None:
    with pytest.raises(CaromError, match=r"engine name 'toy' is taken"):
        registry.register(toy)
    with pytest.raises(CaromError, match=r"engine name 'event-driven' is taken"):
        registry.register(EngineEntry("other", "other", {2: TOY}, aliases=("event-driven",)))
    with pytest.raises(CaromError, match=r"built-in engine 'edmd' cannot be removed"):
        registry.unregister("edmd")


@pytest.mark.usefixtures("toy")
def test_auto_takes_the_first_engine_that_takes_the_world() -> None:
    # the built-in engines come first: spheres in walls are the event-driven engine's
    world = carom.World(2, [1.0, 1.0])
    world.add_spheres(X0, V0, radius=0.05)
    assert world.engine_name == "edmd"
    with pytest.raises(CaromError, match=r"engine must be one of \('auto', 'edmd', 'rigid', 'toy'"):
        carom.World(2, [1.0, 1.0], engine="warp")


@pytest.mark.usefixtures("toy")
def test_a_registered_engine_checkpoints_and_continues_bit_for_bit(tmp_path: Path) -> None:
    world = toy_world()
    world.run(0.3)
    world.save(tmp_path / "toy.npz")
    loaded = carom.World.load(tmp_path / "toy.npz")
    assert loaded.engine is not None
    assert loaded.engine.name == "toy"
    assert loaded.time == 0.3
    loaded.run(0.7)
    world.run(0.7)
    np.testing.assert_array_equal(loaded.positions, world.positions)
    np.testing.assert_array_equal(loaded.positions, flight(0.7)[0])


@pytest.mark.usefixtures("toy")
def test_a_registered_engine_runs_a_scene_file_into_h5md(tmp_path: Path) -> None:
    scene = tmp_path / "toy.toml"
    scene.write_text(
        textwrap.dedent(
            f"""
            [world]
            dimension = 2
            box = [1.0, 1.0]
            gravity = {G.tolist()}
            engine = "toy"

            [[bodies]]
            positions = {X0.tolist()}
            velocities = {V0.tolist()}
            radius = 0.05

            [run]
            until = 0.5
            frame_interval = 0.125
            """
        )
    )
    outputs = Outputs(trajectory=True, events=True, plots=False, animation="none")
    run_scene(scene, tmp_path / "out", outputs=outputs, progress=False)
    with read_trajectory(tmp_path / "out" / "trajectory.h5") as f:
        times = f["particles/all/position/time"][:]
        positions = f["particles/all/position/value"][:]
    assert times.tolist() == [0.0, 0.125, 0.25, 0.375, 0.5]
    for t, x in zip(times, positions, strict=True):
        np.testing.assert_array_equal(x, flight(float(t))[0])
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["collisions"] == 0
