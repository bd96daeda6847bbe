"""Sensors (issue 43, item 3): ``World.set_sensor`` and ``World.sensor_events()``.

A sensor touches nothing and reports the bodies overlapping it at the end of each step. The
closed forms: a ball dropped from rest through a sensor box flies on the free-fall parabola
``y(t) = y0 - g t^2 / 2`` (the rigid engines fly a free body exactly: to round-off), so it
begins to overlap at the first step whose end has ``y - r <= top`` and stops at the first
whose end has ``y + r < bottom``.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import carom
from carom.errors import CaromError
from tests.worlds import scene_world

G = 9.81
R = 0.25  # the ball's radius [m]
Y0 = 4.0  # where it starts [m]
TOP, BOTTOM = 2.5, 1.5  # the sensor box's faces [m]


def _ball_through_a_sensor(dim: int) -> carom.World:
    """A static box sensor (body 0) 1 m thick, its top at 2.5 m, and a ball (body 1) at rest
    4 m up, above its middle."""
    if dim == 2:
        from carom.shapes import Box, Circle

        world = carom.World(2, [10.0, 10.0], gravity=[0.0, -G], boundary="open")
        world.add_body(Box(2.0, 1.0), [5.0, 2.0], kind="static")
        world.add_body(Circle(R), [5.0, Y0])
    else:
        from carom.shapes3d import Box as Box3D
        from carom.shapes3d import Sphere

        world = carom.World(3, [10.0] * 3, gravity=[0.0, -G, 0.0], boundary="open")
        world.add_body(Box3D([2.0, 1.0, 2.0]), [5.0, 2.0, 5.0], kind="static")
        world.add_body(Sphere(R), [5.0, Y0, 5.0])
    world.set_sensor(0)
    return world


def _steps_of_events(world: carom.World, steps: int) -> tuple[list[int], list[int]]:
    """The steps (1-based) whose events hold a begin and an end of (sensor 0, body 1)."""
    began, ended = [], []
    for k in range(1, steps + 1):
        world.step()
        events = world.sensor_events()
        if (0, 1) in events.begin.tolist():
            began.append(k)
        if (0, 1) in events.end.tolist():
            ended.append(k)
    return began, ended


@pytest.mark.parametrize("dim", [2, 3])
def test_a_ball_falls_through_a_sensor_on_the_parabola_and_is_reported_in_and_out(
    dim: int,
) -> None:
    world = _ball_through_a_sensor(dim)
    dt = 1.0 / 60.0
    began, ended = _steps_of_events(world, 60)
    # in: y(t) - R <= TOP first at t = sqrt(2 (Y0 - R - TOP) / g) = 0.5048 s -> step 31;
    # out: y(t) + R < BOTTOM first after sqrt(2 (Y0 + R - BOTTOM) / g) = 0.7488 s -> step 45
    t_in = math.sqrt(2.0 * (Y0 - R - TOP) / G)
    t_out = math.sqrt(2.0 * (Y0 + R - BOTTOM) / G)
    assert began == [math.ceil(t_in / dt)] == [31]
    assert ended == [math.ceil(t_out / dt)] == [45]
    # the sensor never pushed: free fall to round-off (1 s, 60 exact flights)
    t = world.time
    assert abs(world.positions[1, 1] - (Y0 - 0.5 * G * t * t)) < 1e-12
    assert np.all(world.velocities[1][[0, *range(2, dim)]] == 0.0)
    assert world.contact_events().begin.size == 0


@pytest.mark.parametrize("dim", [2, 3])
def test_the_overlapping_bodies_are_listed_while_inside(dim: int) -> None:
    world = _ball_through_a_sensor(dim)
    for _ in range(31):
        world.step()
    np.testing.assert_array_equal(world.sensor_overlaps(0), [1])
    for _ in range(14):
        world.step()
    assert world.sensor_overlaps(0).size == 0
    with pytest.raises(CaromError, match="body 1 is not a sensor"):
        world.sensor_overlaps(1)


def test_a_dynamic_sensor_falls_through_the_floor_and_reports_what_it_passes() -> None:
    from carom.shapes import Box

    world = carom.World(2, [10.0, 10.0], gravity=[0.0, -G], boundary="open")
    floor = world.add_body(Box(10.0, 1.0), [5.0, -0.5], kind="static", restitution=0.0)
    crate = world.add_body(Box(1.0, 1.0), [5.0, 0.5], restitution=0.0)
    probe = world.add_body(Box(0.5, 0.5), [5.0, 2.0])
    world.set_sensor(probe)
    seen: set[tuple[int, int]] = set()
    for _ in range(90):
        world.step()
        seen |= set(world.sensor_events().begin.tolist())
    # it passed the crate and the floor, pushing neither: free fall for 1.5 s
    assert seen == {(probe, crate), (probe, floor)}
    t = world.time
    assert abs(world.positions[probe, 1] - (2.0 - 0.5 * G * t * t)) < 1e-12
    assert abs(world.positions[crate, 1] - 0.5) < 0.01  # the crate rests where it was


def test_a_sensor_sees_what_its_filter_lets_it_touch_and_no_other_sensor() -> None:
    from carom.shapes import Box, Circle

    world = carom.World(2, [10.0, 10.0], gravity=[0.0, -G], boundary="open")
    zone = world.add_body(Box(8.0, 1.0), [5.0, 2.0], kind="static")
    balls = [world.add_body(Circle(R), [x, Y0]) for x in (2.0, 5.0, 8.0)]
    world.set_sensor(zone)
    world.set_sensor(balls[2])  # a sensor ball: sensors do not see sensors
    world.set_filter(balls[1], category=0b100)
    world.set_filter(zone, mask=~0b100 & (2**64 - 1))  # the zone ignores category 4
    seen: set[tuple[int, int]] = set()
    for _ in range(40):
        world.step()
        seen |= set(world.sensor_events().begin.tolist())
    assert seen == {(zone, balls[0])}
    np.testing.assert_array_equal(world.sensors, [True, False, False, True])


def test_a_sensor_made_solid_again_is_landed_on() -> None:
    world = _ball_through_a_sensor(2)
    world.set_sensor(0, False)
    world.run(until=1.0)
    # solid: the ball (restitution 1 against the box) never gets below the top face
    assert world.positions[1, 1] >= TOP + R - 5e-3


def test_a_sleeping_body_in_a_sensor_stays_in_it_and_a_removed_one_leaves() -> None:
    from carom.shapes import Box

    world = carom.World(2, [10.0, 10.0], gravity=[0.0, -G], boundary="open")
    world.add_body(Box(10.0, 1.0), [5.0, -0.5], kind="static", restitution=0.0)
    crate = world.add_body(Box(1.0, 1.0), [5.0, 0.5], restitution=0.0)
    zone = world.add_body(Box(3.0, 3.0), [5.0, 1.0], kind="static")
    world.set_sensor(zone)
    began, ended = [], []
    for _ in range(240):  # 4 s: the crate falls asleep (0.5 s slow)
        world.step()
        began += world.sensor_events().begin.tolist()
        ended += world.sensor_events().end.tolist()
    assert not world.body(crate).awake
    assert began == [(zone, crate)]
    assert ended == []
    np.testing.assert_array_equal(world.sensor_overlaps(zone), [crate])
    world.remove_body(crate)
    world.step()
    assert world.sensor_events().end.tolist() == [(zone, crate)]
    assert world.sensor_overlaps(zone).size == 0


@pytest.mark.parametrize("dim", [2, 3])
def test_rays_do_not_see_sensors(dim: int) -> None:
    world = _ball_through_a_sensor(dim)
    origin = [5.0, 0.0] if dim == 2 else [5.0, 0.0, 5.0]
    up = [0.0, 1.0] if dim == 2 else [0.0, 1.0, 0.0]
    hit = world.ray_cast(origin, up)
    assert hit is not None
    assert hit.body == 1  # through the sensor to the ball
    assert math.isclose(hit.distance, Y0 - R, rel_tol=1e-12)


def test_sensors_are_kept_in_a_checkpoint_and_rerun_bit_for_bit(tmp_path: Path) -> None:
    world = _ball_through_a_sensor(2)
    for _ in range(20):
        world.step()
    path = tmp_path / "sensed.npz"
    world.save(path)
    again = carom.World.load(path)
    np.testing.assert_array_equal(again.sensors, world.sensors)
    runs = [_steps_of_events(w, 40) for w in (world, again)]
    assert runs[0] == runs[1] == ([11], [25])
    np.testing.assert_array_equal(again.positions, world.positions)


def test_bad_sensor_calls_are_refused_and_change_nothing() -> None:
    world = _ball_through_a_sensor(2)
    with pytest.raises(CaromError, match="body 7"):
        world.set_sensor([1, 7])
    np.testing.assert_array_equal(world.sensors, [True, False])
    gas = carom.World(2, [1.0, 1.0])
    gas.add_spheres([[0.5, 0.5]], [[1.0, 0.0]], radius=0.1)
    with pytest.raises(CaromError, match="rigid"):
        gas.set_sensor(0)
    with pytest.raises(CaromError, match="rigid"):
        gas.sensor_events()


SCENE = """
[[bodies]]
shape = "box"
size = [2.0, 1.0]
positions = [[5.0, 2.0]]
kind = "static"
sensor = true

[[bodies]]
shape = "circle"
radius = 0.25
positions = [[5.0, 4.0]]

[[bodies]]
shape = "circle"
radius = 0.25
positions = [[8.0, 4.0]]
category = 2

[[bodies]]
shape = "box"
size = [10.0, 1.0]
positions = [[5.0, -0.5]]
kind = "static"
{floor}
"""


def _scene(floor: str) -> carom.World:
    return scene_world(SCENE.format(floor=floor))


def test_sensors_and_filters_in_a_scene() -> None:
    # the floor touches all but category 2 (mask -3: every bit but 0b10): ball 2 (category
    # 2, its mask left whole) falls through it; the sensor box reports ball 1 on its way
    # down (and up again: it bounces off the floor, e = 1)
    world = _scene("mask = -3")
    np.testing.assert_array_equal(world.sensors, [True, False, False, False])
    assert world.collision_filters[3, 1] == -3
    began = []
    for _ in range(90):
        world.step()
        began += world.sensor_events().begin.tolist()
    assert set(began) == {(0, 1)}
    assert world.positions[2, 1] < -2.0  # through the floor
    assert world.positions[1, 1] > 0.0  # on it


def test_a_bad_filter_in_a_scene_is_named_by_file_line_and_table() -> None:
    from carom.scene.schema import SceneError

    with pytest.raises(SceneError, match="group") as caught:
        _scene("group = 2.5")
    assert "scene.toml:" in str(caught.value)
