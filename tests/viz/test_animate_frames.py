"""The film's frames: moved outlines and the blitted picture."""

from __future__ import annotations

import math

import numpy as np
import pytest

from carom.shapes import Box, Capsule, Circle
from carom.shapes3d import Box as Box3D
from carom.viz.animate import Outlines, TrajectoryScene, _Painter


def test_an_outline_is_turned_about_its_body_and_moved_with_it() -> None:
    outlines = Outlines([Box(0.4, 0.2).pieces(), Capsule(0.3, 0.05).pieces()])
    positions = np.array([[1.0, 2.0], [-0.5, 0.25]])
    angles = np.array([math.pi / 2, -0.3])
    placement = outlines.placements(positions, angles)
    for polygon, body, m in zip(
        outlines.polygons(outlines.points), outlines.body, placement, strict=True
    ):
        c, s = math.cos(angles[body]), math.sin(angles[body])
        # x' = R(angle) x + position, the rotation written out
        expect = polygon @ np.array([[c, s], [-s, c]]) + positions[body]
        got = polygon @ m[:2, :2].T + m[:2, 2]
        assert np.allclose(got, expect, rtol=0.0, atol=1e-15)
        assert np.array_equal(m[2], [0.0, 0.0, 1.0])


def _scene(dim: int) -> TrajectoryScene:
    if dim == 2:
        pieces = [Box(0.4, 0.2).pieces(), Circle(0.1).pieces(), ()]
        box = np.array([2.0, 2.0])
    else:
        pieces = [Box3D([0.4, 0.2, 0.3]).pieces(), Box3D([0.2, 0.2, 0.2]).pieces(), ()]
        box = np.array([2.0, 2.0, 2.0])
    return TrajectoryScene(
        dim, box, False, np.array([0.2, 0.1, 0.15]), np.array([1.0, np.inf, 2.0]), pieces
    )


@pytest.mark.parametrize("dim", [2, 3])
def test_a_blitted_frame_is_the_full_redraw(dim: int) -> None:
    # each frame draws what moves over a stored picture of what does not: the same pixels as
    # drawing the whole figure again (matplotlib's Agg renderer is deterministic)
    pytest.importorskip("matplotlib", reason="the viz extra is missing")
    scene = _scene(dim)
    painter = _Painter(scene, "a title", (320, 240))
    try:
        rng = np.random.default_rng(7)
        x = 0.5 + rng.random((3, dim))
        v = rng.normal(size=(3, dim))
        turn = rng.normal(size=3) if dim == 2 else rng.normal(size=(3, 4))
        if dim == 3:
            turn /= np.linalg.norm(turn, axis=1, keepdims=True)
        blitted = painter.draw(1.25, x, v, turn)
        for artist in [*painter.moving_parts, painter.stamp]:
            artist.set_animated(False)
        painter.fig.canvas.draw()
        whole = np.asarray(painter.fig.canvas.buffer_rgba())[..., :3]
        assert np.array_equal(blitted, whole)
        # and the bodies are in it: the frame is not the empty picture
        assert np.count_nonzero(np.any(blitted != np.asarray(painter.still)[..., :3], axis=2))
    finally:
        painter.close()


def test_joints_are_drawn_from_each_centre_through_the_anchors() -> None:
    # (Box2D's debug draw of a joint: A's centre, A's anchor, B's anchor, B's centre)
    pytest.importorskip("matplotlib", reason="the viz extra is missing")
    from carom.joints import joint_lines

    ints = np.array([[0, -1, 0, 0], [0, 0, 1, 0], [-1, 0, 1, 0]])  # the last one removed
    local = np.array([[1.0, 1.5, -0.2, 0.0], [0.2, 0.0, -0.1, 0.0], [9.0, 9.0, 9.0, 9.0]])
    x = np.array([[1.2, 1.5], [1.0, 1.0]])
    angle = np.array([0.0, math.pi / 2])
    lines = joint_lines(ints, local, x, angle)
    assert lines.shape == (2, 4, 2)
    assert np.allclose(lines[0], [[1.0, 1.5], [1.0, 1.5], [1.0, 1.5], [1.2, 1.5]], atol=1e-15)
    # body 1 turned a quarter: its anchor (-0.1, 0) in its frame is (0, -0.1) in the world
    assert np.allclose(lines[1], [[1.2, 1.5], [1.4, 1.5], [1.0, 0.9], [1.0, 1.0]], atol=1e-15)
    scene = _scene(2)
    scene.joints = (ints, local)
    painter = _Painter(scene, "joints", (320, 240))
    try:
        painter.draw(
            0.0,
            np.array([[1.2, 1.5], [1.0, 1.0], [0.5, 0.5]]),
            np.zeros((3, 2)),
            np.array([0.0, math.pi / 2, 0.0]),
        )
        assert len(painter.joints.get_segments()) == 2
    finally:
        painter.close()
