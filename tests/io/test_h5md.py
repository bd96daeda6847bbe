"""The H5MD writer (carom.io.h5md), tested directly: the groups and units of H5MD 1.1, the
orientation, angular velocity and shape elements, frames as written, and reopening."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import carom
from carom.io.h5md import ELEMENTS, OBSERVABLES, H5MDWriter, check_trajectory

h5py = pytest.importorskip("h5py")


def _spinning_world(dim: int) -> carom.World:
    world = carom.World(dim, [1.0] * dim)
    world.add_spheres(
        [[0.3] + [0.5] * (dim - 1), [0.7] + [0.5] * (dim - 1)],
        [[1.0] + [0.0] * (dim - 1), [-1.0] + [0.0] * (dim - 1)],
        radius=0.1,
        material=carom.Material(0.8, beta=0.2),
        angular_velocities=[1.0, -2.0] if dim == 2 else [[0.0, 0.0, 1.0], [1.0, 2.0, 3.0]],
    )
    world.add_static_spheres([[0.5] * dim], radius=0.05)
    return world


@pytest.mark.parametrize("dim", [2, 3])
def test_every_frame_is_written_as_the_world_had_it(tmp_path: Path, dim: int) -> None:
    world = _spinning_world(dim)
    path = tmp_path / "t.h5"
    frames = []
    with H5MDWriter(path, world) as writer:
        for frame in [world.frame(), *world.frames(0.5, 0.25)]:
            writer.write(frame, dict.fromkeys(OBSERVABLES, 1.5))
            frames.append(frame)
    check_trajectory(path, world, len(frames))
    with h5py.File(path, "r") as f:
        assert tuple(f["h5md"].attrs["version"]) == (1, 1)
        particles = f["particles/all"]
        assert [s.decode() for s in particles["shape"][()]] == ["sphere"] * 3
        assert particles["radius"].attrs["unit"] == "m"
        assert particles["angular_velocity/value"].attrs["unit"] == "rad s-1"
        orientation = particles["orientation/value"]
        assert orientation.shape == ((3, 3) if dim == 2 else (3, 3, 4))
        for k, frame in enumerate(frames):
            assert particles["position/time"][k] == frame.time
            for name, value in zip(
                ELEMENTS,
                (frame.positions, frame.velocities, frame.orientations, frame.angular_velocities),
                strict=True,
            ):
                assert particles[f"{name}/value"][k].tobytes() == value.tobytes()
        assert np.all(f["observables/kinetic_energy/value"][()] == 1.5)
        assert f["observables/angular_momentum/value"].shape == (len(frames), 3)


def test_frames_held_in_batches_reach_the_file_in_order(
    tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # frames go to the file three at a time; flush() writes the ones held (a checkpoint names
    # them next), close() the rest: every frame once, in order, with its step and time
    monkeypatch.setattr("carom.io.h5md.BATCH_FRAMES", 3)
    world = _spinning_world(3)
    path = tmp_path / "t.h5"
    frames = [world.frame(), *world.frames(0.6, 0.1)]
    with H5MDWriter(path, world) as writer:
        for k, frame in enumerate(frames[:4]):
            writer.write(frame, dict.fromkeys(OBSERVABLES, float(k)))
        assert writer.frames == 4
        assert writer.written == 3
        writer.flush()
        assert writer.written == 4
        assert writer.file["particles/all/position/value"].shape[0] == 4  # in the file
        for k, frame in enumerate(frames[4:], start=4):
            writer.write(frame, dict.fromkeys(OBSERVABLES, float(k)))
    count = len(frames)
    check_trajectory(path, world, count)
    with h5py.File(path, "r") as f:
        for name in ELEMENTS:
            assert list(f[f"particles/all/{name}/step"][()]) == list(range(count))
        assert list(f["particles/all/velocity/time"][()]) == [frame.time for frame in frames]
        assert list(f["observables/kinetic_energy/value"][()]) == [float(k) for k in range(count)]
        for k, frame in enumerate(frames):
            assert f["particles/all/orientation/value"][k].tobytes() == frame.orientations.tobytes()


def test_reopen_keeps_the_frames_a_checkpoint_knows(tmp_path: Path) -> None:
    world = _spinning_world(2)
    path = tmp_path / "t.h5"
    with H5MDWriter(path, world) as writer:
        for frame in world.frames(0.4, 0.1):
            writer.write(frame, dict.fromkeys(OBSERVABLES, 0.0))
    with H5MDWriter.reopen(path, world, 2) as writer:  # frames 3 and 4 came after the checkpoint
        assert writer.frames == 2
    with h5py.File(path, "r") as f:
        assert all(f[f"particles/all/{name}/value"].shape[0] == 2 for name in ELEMENTS)
    with pytest.raises(carom.CaromError, match=r"fewer frames than its checkpoint"):
        H5MDWriter.reopen(path, world, 5)
