"""Joints in the trajectory file (H5MD): written once, read back for the film (issue 43)."""

from __future__ import annotations

import numpy as np
import pytest

import carom
from carom.joints import Distance, Revolute
from carom.shapes import Box, Circle


def test_the_trajectory_keeps_the_joints_and_the_film_reads_them(tmp_path) -> None:  # type: ignore[no-untyped-def]
    h5py = pytest.importorskip("h5py", reason="the io extra is missing")
    from carom.io.h5md import OBSERVABLES, H5MDWriter
    from carom.viz.animate import TrajectoryScene

    world = carom.World(2, [10.0, 10.0], gravity=[0.0, -9.81], boundary="open")
    bar = world.add_body(Box(1.0, 0.1), [5.5, 8.0])
    ball = world.add_body(Circle(0.1), [6.0, 7.0])
    world.add_joint(Revolute(None, bar, [5.0, 8.0]))
    world.add_joint(Distance(bar, ball, [6.0, 8.0], [6.0, 7.0]))
    path = tmp_path / "trajectory.h5"
    with H5MDWriter(path, world) as writer:
        for frame in world.frames(until=0.5, frame_interval=0.25):
            writer.write(frame, {name: np.zeros(shape) for name, (shape, _) in OBSERVABLES.items()})
    with h5py.File(path, "r") as f:
        joints = f["particles/all/joints"]
        assert [k.decode() for k in joints["kind"][:]] == ["revolute", "distance"]
        assert joints["bodies"][:].tolist() == [[-1, 0], [0, 1]]
        # the pin in the world's frame; the bar's anchors 0.5 m from its centre, in its frame
        assert np.allclose(joints["anchors"][0], [[5.0, 8.0], [-0.5, 0.0]], atol=1e-15)
        assert np.allclose(joints["anchors"][1], [[0.5, 0.0], [0.0, 0.0]], atol=1e-15)
        scene = TrajectoryScene.read(f)
    assert scene.joints is not None
    ints, local = scene.joints
    assert ints[:, 1:3].tolist() == [[-1, 0], [0, 1]]
    assert local.shape == (2, 4)
