"""Sensor pieces (issue 43, item 3): ``World.set_sensor(i, pieces=[...])`` makes some pieces of
a body sensors (a character's foot sensor), the body solid in the others.

The body here is a unit box with a foot, a 0.6 x 0.2 box whose centre is 0.55 m below the
box's: the foot sticks out 0.15 m under the box. Its pieces are placed about the body's
centre of mass, ``c = -0.55 * 0.12 / 1.12`` m below the box's centre (areas 1 and 0.12 m^2,
uniform density), so the box's bottom is ``0.5 + c`` below the centre of mass and the foot's
``0.65 + c``. Resting on the ground the body stands on its box when the foot is a sensor
(its centre ``0.5 + c`` above the ground) and on its foot when it is solid (``0.65 + c``); the
solver holds a resting contact to within the linear slop (0.005 m).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import carom
from carom.errors import CaromError
from carom.materials import Material
from tests.worlds import scene_world

C = -0.55 * 0.12 / 1.12  # the box's centre above the body's centre of mass [m]
BOX_BOTTOM = 0.5 + C  # below the centre of mass [m]
FOOT_BOTTOM = 0.65 + C
GROUND_TOP = 1.0  # [m]
SLOP = 0.005  # the rigid engines' linear slop [m]


def _character(dim: int, foot_sensor: bool) -> carom.World:
    """Static ground (body 0), its top at 1 m, and the character (body 1) dropped from 3 m
    (centre), its foot (piece 1) a sensor or solid; no bounce (restitution 0)."""
    dull = Material(restitution=0.0, friction=0.6)
    if dim == 2:
        from carom.shapes import Box, Compound

        world = carom.World(2, [10.0, 10.0], gravity=[0.0, -9.81], boundary="open")
        world.add_body(Box(8.0, 1.0), [5.0, 0.5], kind="static", material=dull)
        world.add_body(
            Compound([Box(1.0, 1.0), (Box(0.6, 0.2), [0.0, -0.55])]), [5.0, 3.0], material=dull
        )
    else:
        from carom.shapes3d import Box as Box3D
        from carom.shapes3d import Compound as Compound3D

        world = carom.World(3, [10.0] * 3, gravity=[0.0, -9.81, 0.0], boundary="open")
        world.add_body(Box3D([8.0, 1.0, 8.0]), [5.0, 0.5, 5.0], kind="static", material=dull)
        # (depth 1 and 0.6: volumes 1 and 0.072; the centre of mass shifts by 0.55 * 0.072 /
        # 1.072 instead)
        foot = (Box3D([0.6, 0.2, 0.6]), [0.0, -0.55, 0.0])
        world.add_body(Compound3D([Box3D([1.0, 1.0, 1.0]), foot]), [5.0, 3.0, 5.0], material=dull)
    if foot_sensor:
        world.set_sensor(1, pieces=[1])
    return world


def _shift(dim: int) -> float:
    """How far the box's centre is above the body's centre of mass [m] (module docstring)."""
    return C if dim == 2 else -0.55 * 0.072 / 1.072


@pytest.mark.parametrize("dim", [2, 3])
def test_a_foot_sensor_reports_the_ground_and_the_body_stands_on_its_box(dim: int) -> None:
    world = _character(dim, foot_sensor=True)
    began = []
    for _ in range(120):  # 2 s: falls 2 m in 0.6 s, then rests
        world.step()
        began += world.sensor_events().begin.tolist()
    c = _shift(dim)
    np.testing.assert_allclose(world.positions[1, 1], GROUND_TOP + 0.5 + c, atol=SLOP)
    assert began == [(1, 0)]  # (the sensor's body, the body it overlaps)
    assert world.sensor_overlaps(1).tolist() == [0]
    # the same body with a solid foot stands on the foot, 0.15 m higher
    solid = _character(dim, foot_sensor=False)
    for _ in range(120):
        solid.step()
    np.testing.assert_allclose(solid.positions[1, 1], GROUND_TOP + 0.65 + c, atol=SLOP)


@pytest.mark.parametrize("dim", [2, 3])
def test_rays_pass_through_a_sensor_piece_and_meet_the_solid_ones(dim: int) -> None:
    world = _character(dim, foot_sensor=True)
    world.build()
    centre = np.array([5.0, 3.0, 5.0][:dim])  # (the box's centre: where it was placed)
    along = np.eye(dim)[0]
    # through the foot alone, 0.58 m under the box's centre (its bottom is 0.5 m under, the
    # foot's 0.65 m): a sensor piece is seen by no ray
    foot_line = centre - along * 5.0 - np.eye(dim)[1] * 0.58
    assert world.ray_cast(foot_line, along) is None
    # through the box: it meets its side, 0.5 m before the centre
    hit = world.ray_cast(centre - along * 5.0, along)
    assert hit is not None
    assert hit.body == 1
    assert hit.distance == pytest.approx(4.5, abs=1e-12)
    solid = _character(dim, foot_sensor=False)
    solid.build()
    seen = solid.ray_cast(foot_line, along)
    assert seen is not None
    assert seen.distance == pytest.approx(4.7, abs=1e-12)  # the foot's side, 0.3 m out


def test_bad_pieces_are_refused_and_change_nothing() -> None:
    world = _character(2, foot_sensor=False)
    world.step()
    with pytest.raises(CaromError, match="pieces 0 to 1"):
        world.set_sensor(1, pieces=[2])
    with pytest.raises(CaromError, match="one body"):
        world.set_sensor([0, 1], pieces=[0])
    with pytest.raises(CaromError, match="piece indices"):
        world.set_sensor(1, pieces=[0.5])
    assert world.sensor_pieces.shape == (0, 2)
    world.set_sensor(1, pieces=[1])
    assert world.sensor_pieces.tolist() == [[1, 1]]
    world.set_sensor(1, False, pieces=[1])  # solid again
    assert world.sensor_pieces.shape == (0, 2)


def test_sensor_pieces_outlive_a_checkpoint(tmp_path: Path) -> None:
    world = _character(2, foot_sensor=True)
    for _ in range(30):
        world.step()
    world.save(tmp_path / "foot.npz")
    loaded = carom.World.load(tmp_path / "foot.npz")
    assert loaded.sensor_pieces.tolist() == [[1, 1]]
    for w in (world, loaded):
        for _ in range(90):
            w.step()
    assert loaded.positions.tobytes() == world.positions.tobytes()
    assert loaded.sensor_overlaps(1).tolist() == [0]


SCENE = """
[[bodies]]
shape = "compound"
pieces = [{shape = "box", size = [1.0, 1.0]},
          {shape = "circle", radius = 0.3, offset = [0.0, 0.7]},
          {shape = "box", size = [0.6, 0.2], offset = [0.0, -0.55], sensor = true}]
positions = [[5.0, 5.0], [5.0, 8.0]]
"""


def test_a_scene_marks_a_compounds_sensor_pieces() -> None:
    world = scene_world(SCENE)
    # the foot, the third part (piece 2), of each of the two bodies; the bodies solid else
    assert [len(pieces) for pieces in world.bodies.pieces] == [3, 3]
    assert world.sensor_pieces.tolist() == [[0, 2], [1, 2]]
    assert not world.sensors.any()
