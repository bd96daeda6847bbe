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


def test_3d_joints_are_kept_and_drawn_through_the_camera(tmp_path) -> None:  # type: ignore[no-untyped-def]
    h5py = pytest.importorskip("h5py", reason="the io extra is missing")
    pytest.importorskip("matplotlib", reason="the viz extra is missing")
    from carom.io.h5md import OBSERVABLES, H5MDWriter
    from carom.joints import Spherical, joint_lines
    from carom.shapes3d import Box as Box3D
    from carom.viz.animate import TrajectoryScene, _Painter

    world = carom.World(3, [10.0, 10.0, 10.0], gravity=[0.0, 0.0, -9.81], boundary="open")
    link = world.add_body(Box3D([1.0, 0.2, 0.2]), [5.5, 5.0, 8.0])
    tip = world.add_body(Box3D([0.2, 0.2, 0.2]), [6.2, 5.0, 8.0])
    world.add_joint(Spherical(None, link, [5.0, 5.0, 8.0]))
    world.add_joint(Spherical(link, tip, [6.0, 5.0, 8.0]))
    path = tmp_path / "trajectory.h5"
    with H5MDWriter(path, world) as writer:
        for frame in world.frames(until=0.2, frame_interval=0.1):
            writer.write(frame, {name: np.zeros(shape) for name, (shape, _) in OBSERVABLES.items()})
    with h5py.File(path, "r") as f:
        anchors = f["particles/all/joints/anchors"][:]
        # the socket in the world's frame; the link's ends 0.5 m from its centre, in its frame
        assert np.allclose(anchors[0], [[5.0, 5.0, 8.0], [-0.5, 0.0, 0.0]], atol=1e-15)
        assert np.allclose(anchors[1], [[0.5, 0.0, 0.0], [-0.2, 0.0, 0.0]], atol=1e-15)
        scene = TrajectoryScene.read(f)
    assert scene.joints is not None
    assert scene.joints[1].shape == (2, 6)
    # the film draws each joint's four points seen through its camera
    x = np.array([[5.5, 5.0, 8.0], [6.2, 5.0, 8.0]])
    q = np.array([[1.0, 0.0, 0.0, 0.0]] * 2)
    painter = _Painter(scene, "joints", (320, 240))
    try:
        painter.draw(0.0, x, np.zeros((2, 3)), q)
        drawn = np.array(painter.joints.get_segments())
        world_lines = joint_lines(*scene.joints, x, q)
        assert np.allclose(world_lines[1, 1], [6.0, 5.0, 8.0], atol=1e-15)
        assert painter.camera is not None
        expect, _ = painter.camera.project(world_lines.reshape(-1, 3))
        assert np.allclose(drawn, expect.reshape(-1, 4, 2), atol=1e-12)
    finally:
        painter.close()
