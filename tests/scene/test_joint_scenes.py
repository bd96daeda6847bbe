"""Joints in scene files (issue 43, item 6): [[joints]], the built-in scenes with joints,
and bad joints named by file and line."""

from __future__ import annotations

import math
import textwrap

import numpy as np
import pytest

import carom
from carom.scene import find_scene, load_scene
from carom.scene.schema import SceneError
from tests.worlds import scene_world

HEAD = """
[[bodies]]
shape = "box"
size = [0.5, 0.1]
positions = [[5.25, 8.0], [5.75, 8.0], [6.25, 8.0]]
"""


def scene(joints: str) -> carom.World:
    return scene_world(HEAD + textwrap.dedent(joints))


def gaps(world: carom.World) -> np.ndarray:
    anchors = world.joint_anchors()
    return np.linalg.norm(anchors[:, 0] - anchors[:, 1], axis=1)


def test_joints_table_makes_one_joint_per_pair_with_its_own_anchor() -> None:
    world = scene(
        """
        [[joints]]
        type = "revolute"
        bodies = [[-1, 0], [0, 1], [1, 2]]
        anchor = [[5.0, 8.0], [5.5, 8.0], [6.0, 8.0]]
        limits = [-1.0, 1.0]
        """
    )
    assert world.n_joints == 3
    ints, _ = world.joint_rows
    assert ints[:, 1].tolist() == [-1, 0, 1]
    assert ints[:, 2].tolist() == [0, 1, 2]
    world.run(until=1.0)
    # a chain of three planks hanging from a pin: each pin holds within the soft step's give
    assert np.max(gaps(world)) < 5e-3
    assert float(world.positions[2, 1]) < 8.0


def test_a_distance_joint_in_a_scene_is_a_rope() -> None:
    world = scene(
        """
        [[joints]]
        type = "distance"
        bodies = [-1, 0]
        anchors = [[5.25, 9.0], [5.25, 8.0]]
        min_length = 0.0
        max_length = 1.5
        """
    )
    world.run(until=1.0)
    # the rope goes taut at 1.5 m below its anchor (a 0.5 m drop takes 0.32 s)
    assert float(world.positions[0, 1]) == pytest.approx(7.5, abs=2e-3)


@pytest.mark.parametrize(
    ("joints", "message"),
    [
        ('type = "hinge"\nbodies = [-1, 0]', "type: must be one of"),
        ('type = "revolute"\nbodies = [-1, 0]', "anchor is required"),
        ('type = "revolute"\nbodies = [-1, 7]\nanchor = [5.0, 8.0]', "b = 7 is not in the world"),
        ('type = "revolute"\nbodies = [0, 0]\nanchor = [5.0, 8.0]', "two different bodies"),
        ('type = "revolute"\nbodies = [0.5, 1]\nanchor = [5.0, 8.0]', "pair of body indices"),
        (
            'type = "revolute"\nbodies = [[-1, 0], [0, 1]]\nanchor = [[5, 8], [5, 8], [6, 8]]',
            "3 rows for 2 joints",
        ),
        ('type = "prismatic"\nbodies = [-1, 0]\nanchor = [5.0, 8.0]', "axis is required"),
        ('type = "revolute"\nbodies = [-1, 0]\nanchor = [5.0, 8.0]\nlimits = [1.0]', "two numbers"),
    ],
)
def test_bad_joints_are_named_by_file_line_and_table(joints: str, message: str) -> None:
    with pytest.raises(SceneError, match=message) as caught:
        scene("[[joints]]\n" + joints + "\n")
    assert "scene.toml:" in str(caught.value)
    assert "[[joints]] #1" in str(caught.value)


@pytest.mark.parametrize("name", ["pendulums", "chain-bridge", "ragdoll-pile", "car", "rope-3d"])
def test_the_built_in_jointed_scenes_run_and_hold_together(name: str) -> None:
    world = load_scene(find_scene(name)).build()
    world.run(until=1.5)
    assert np.all(np.isfinite(world.positions))
    ints, _ = world.joint_rows
    # the joints whose two anchors are one point: revolute (0), spherical (6), weld (3)
    pinned = np.isin(ints[:, 0], [0, 3, 6])
    # (measured at most 1.3 cm over these scenes' first seconds: 4 cm allows their worst)
    assert np.max(gaps(world)[pinned], initial=0.0) < 0.04


def test_the_car_drives_over_the_bumps() -> None:
    world = load_scene(find_scene("car")).build()
    world.run(until=4.0)
    # its motors roll it right along the ground (measured 18 m in 4 s), upright
    assert float(world.positions[1, 0]) > 10.0
    assert abs(math.remainder(float(world.orientations[1]), 2 * math.pi)) < 1.0


def test_the_cradle_on_strings_sends_out_one_ball() -> None:
    world = load_scene(find_scene("cradle-on-strings")).build()
    v0 = math.sqrt(2 * 9.81 * 0.5 * (1 - math.cos(0.4)))  # the striker at the bottom
    fastest = np.zeros(5)
    for _ in range(40):  # the impact near step 21, and the next quarter swing
        world.step()
        fastest = np.maximum(fastest, np.hypot(*world.velocities[:, :2].T))
    assert fastest[4] >= 0.99 * v0
    assert np.all(fastest[1:4] <= 0.01 * v0)
