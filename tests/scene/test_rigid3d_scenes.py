"""3D rigid bodies in scenes: the shapes' keys, the square pyramid, and the built-in 3D scenes."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import carom
from carom.errors import CaromError
from carom.geometry.polyhedron import polyhedron_features
from carom.scene import find_scene, load_scene
from carom.shapes3d import Hull, rotation_matrix

HEADER = """
[world]
dimension = 3
box = [10.0, 10.0, 10.0]
gravity = [0.0, 0.0, -9.81]
[run]
until = 1.0
"""


def scene(text: str, tmp: Path) -> carom.World:
    path = tmp / "scene.toml"
    path.write_text(HEADER + text)
    return load_scene(path).build()


def test_a_3d_pyramid_stands_on_its_base_touching_and_not_overlapping(tmp_path: Path) -> None:
    world = scene(
        "[[pyramid]]\nrows = 4\nbase = [5.0, 5.0, 0.0]\nsize = [1.0, 0.5, 0.25]\n", tmp_path
    )
    # 16 + 9 + 4 + 1 boxes, layer k at height (k + 1/2) c, centred over the base
    assert world.n_bodies == 30
    x = world.positions
    layers = np.round((x[:, 2] / 0.25) - 0.5).astype(int)
    assert np.bincount(layers).tolist() == [16, 9, 4, 1]
    assert x[:, 0].mean() == pytest.approx(5.0)
    assert x[:, 1].mean() == pytest.approx(5.0)
    # neighbours in a layer touch face to face: 1 m apart along x, 0.5 m along y
    bottom = x[layers == 0]
    d = np.abs(bottom[:, None, :2] - bottom[None, :, :2])
    assert np.isclose(d[..., 0], 1.0).sum() > 0
    assert np.isclose(d[..., 1], 0.5).sum() > 0
    assert d[..., 0].max() == pytest.approx(3.0)
    world.run(until=0.1)  # the engine accepts the layout: nothing overlaps beyond the slop


def test_3d_shapes_orientations_and_spins_from_keys(tmp_path: Path) -> None:
    q = [math.cos(0.3), 0.0, math.sin(0.3), 0.0]
    capsule = (  # an inline table: one line of TOML
        '{shape = "capsule", size = 0.4, radius = 0.05, offset = [0.3, 0, 0], '
        "orientation = [1, 0, 1, 0]}"
    )
    world = scene(
        f"""
        [[materials]]
        name = "rubber"
        restitution = 0.8
        friction = 0.9
        rolling = 0.002

        [[bodies]]
        shape = "box"
        size = [0.2, 0.3, 0.4]
        positions = [[2, 2, 2], [3, 2, 2]]
        orientations = {q}
        angular_velocities = [[0, 0, 1], [0, 1, 0]]
        material = "rubber"

        [[bodies]]
        shape = "hull"
        vertices = [[0, 0, 0], [0.2, 0, 0], [0, 0.2, 0], [0, 0, 0.2]]
        positions = [[5, 5, 5]]

        [[bodies]]
        shape = "compound"
        pieces = [
          {{shape = "ball", radius = 0.1}},
          {capsule},
        ]
        positions = [[7, 7, 7]]
        mass = 2.0
        """,
        tmp_path,
    )
    assert world.n_bodies == 4
    assert world.orientations[0] == pytest.approx(np.array(q), abs=1e-15)
    assert world.angular_velocities[1] == pytest.approx([0, 1, 0])
    assert rotation_matrix(world.orientations[0]) @ [0, 0, 1] == pytest.approx(
        [math.sin(0.6), 0, math.cos(0.6)], abs=1e-15
    )
    assert world.materials[0].rolling == 0.002
    assert world.masses[3] == pytest.approx(2.0)


@pytest.mark.parametrize(
    ("body", "pattern"),
    [
        ('shape = "box"\nsize = [1, 1]\npositions = [[1, 1, 1]]', r"size in 3D is \[x, y, z\]"),
        ('shape = "ball"\npositions = [[1, 1, 1]]', r"a ball needs radius"),
        ('shape = "box"\nsize = [1, 1, 1]\norientations = [1, 0, 0]\npositions = [[1, 1, 1]]',
         r"orientations: must be a quaternion"),
        ('shape = "box"\nsize = [1, 1, 1]\nangles = 0.5\npositions = [[1, 1, 1]]',
         r"angles are for 2D bodies"),
    ],
)  # fmt: skip
def test_bad_3d_bodies_are_named_by_file_and_table(tmp_path: Path, body: str, pattern: str) -> None:
    with pytest.raises(CaromError, match=pattern) as caught:
        scene("[[bodies]]\n" + body, tmp_path)
    assert "scene.toml" in str(caught.value)


def test_spheres_spin_as_their_entry_says(tmp_path: Path) -> None:
    # a [[bodies]] entry of spheres (the default shape) keeps its angular_velocities, one for
    # all or one each (they were dropped without a word before: a follow shot set up in a
    # scene file rolled in without its topspin)
    world = scene(
        """
        [[bodies]]
        positions = [[2, 2, 2], [3, 2, 2]]
        radius = 0.1
        angular_velocities = [[0, 5, 0], [1, 0, 0]]

        [[bodies]]
        positions = [[5, 5, 5], [6, 5, 5]]
        radius = 0.1
        angular_velocities = [0, 0, 3]

        [[bodies]]
        positions = [[8, 8, 8]]
        radius = 0.1
        """,
        tmp_path,
    )
    expected = [[0, 5, 0], [1, 0, 0], [0, 0, 3], [0, 0, 3], [0, 0, 0]]
    assert world.angular_velocities.tolist() == expected


@pytest.mark.parametrize(
    "name",
    [
        "billiards-3d",
        "bowl",
        "box-corner-3d",
        "box-edge-3d",
        "bullet-3d",
        "cut-shot",
        "dominoes-3d",
        "draw-shot",
        "follow-shot",
        "pyramid-3d",
        "ring-toss",
        "rod-drop-3d",
        "spin-ball-3d",
        "stun-shot",
        "three-cushion",
        "tumbler-3d",
        "wall-and-ball",
    ],
)
def test_each_built_in_3d_scene_runs_a_little(name: str) -> None:
    scene_ = load_scene(find_scene(name))
    assert scene_.scene["title"]
    assert scene_.scene["description"]
    world = scene_.build()
    assert world.engine_name == "rigid"
    assert world.dim == 3
    world.run(until=0.2)
    assert np.all(np.isfinite(world.positions))
    moving = np.isfinite(world.masses)  # the impact scenes' ground is a static slab below 0
    assert world.positions[moving, 2].min() > 0.0  # nothing fell through the floor


@pytest.mark.needs_jit  # 600 steps of 385 boxes
def test_the_3d_pyramid_stands_for_ten_seconds() -> None:
    # issue 14's standard: the top box moves less than 1% of its size in 10 s (measured:
    # 2.7 mm, and no box turns more than 0.02 degree)
    world = load_scene(find_scene("pyramid-3d")).build()
    x0 = world.positions.copy()
    top = int(np.argmax(x0[:, 2]))
    world.run(until=10.0)
    assert np.linalg.norm(world.positions[top] - x0[top]) < 0.01
    turned = 2.0 * np.degrees(np.arccos(np.clip(np.abs(world.orientations[:, 0]), 0, 1)))
    assert turned.max() < 0.1


def test_the_3d_dominoes_all_fall() -> None:
    world = load_scene(find_scene("dominoes-3d")).build()
    world.run(until=6.0)
    q = world.orientations[:30]
    tilt = 2.0 * np.degrees(np.arccos(np.clip(np.abs(q[:, 0]), 0, 1)))
    assert np.all(tilt > 45.0)  # every domino lies toppled


@pytest.mark.needs_jit  # 240 steps of 217 bodies
def test_the_3d_tumbler_keeps_its_rocks_inside_the_turning_drum() -> None:
    # the drum's inner faces are 2 m from its centre; every rock's centre stays within 2 m
    # less the rock's least depth (its centre of mass to its nearest face), in the drum's own
    # (turning) frame, to the soft contact's overlap (a few millimetres at most)
    scene_ = load_scene(find_scene("tumbler-3d"))
    rock = Hull(scene_.lattice[0]["body"]["vertices"])
    faces = polyhedron_features(rock.vertices, rock.triangles)
    depth = float(np.min(faces.offsets - faces.normals @ rock.centroid))
    world = scene_.build()
    world.run(until=4.0)
    drum = rotation_matrix(world.orientations[0])
    inside = (world.positions[1:] - world.positions[0]) @ drum  # rows: drum-frame coordinates
    assert np.abs(inside).max() < 2.0 - depth + 0.005
    # the drum turned 25 degrees a second for 4 s, about y
    angle = 2.0 * math.degrees(math.acos(min(1.0, abs(float(world.orientations[0, 0])))))
    assert angle == pytest.approx(100.0, rel=1e-12)


def test_billiard_balls_slide_roll_and_stop_on_the_cloth() -> None:
    # after the break the balls slide, friction (0.2) turns sliding into rolling (the contact
    # point at rest: v + w x (-R z) = 0), and the cloth's rolling resistance stops them
    world = load_scene(find_scene("billiards-3d")).build()
    radius = 0.028575
    world.run(until=3.0)
    v, w = world.velocities, world.angular_velocities
    moving = np.linalg.norm(v, axis=1) > 0.05
    assert moving.any()
    slip = v + np.cross(w, [0.0, 0.0, -radius])
    assert np.abs(slip[moving][:, :2]).max() < 0.01 * np.linalg.norm(v[moving], axis=1).max()
    world.run(until=10.0)
    assert np.linalg.norm(world.velocities, axis=1).max() < 1e-3
    # they stayed on the cloth: centres a radius above it, less the soft contact's sink (the
    # bodies after the 16 balls are the cushions' rails)
    assert world.positions[:16, 2] == pytest.approx(radius, abs=1e-4)


@pytest.mark.needs_jit  # 90 and 360 steps of 2 balls
@pytest.mark.parametrize("name", ["follow-shot", "stun-shot", "draw-shot", "cut-shot"])
def test_the_shots_are_the_same_at_any_rate(tmp_path: Path, name: str) -> None:
    # each ball slides and rolls in closed form and the impact is carom.collide's at its time
    # (tests/engines/rigid3d/test_cloth.py holds the shots to their closed forms): the scene
    # at 240 Hz ends where it does at 60 Hz, to round-off of the composed phases (measured
    # 7e-11 at worst; 1e-9 the bound), with one impact and both balls on the cloth
    ends = []
    text = find_scene(name).read_text()
    for rate in (60.0, 240.0):
        path = tmp_path / f"{name}-{rate:g}.toml"
        path.write_text(text + f"\n[rigid]\nrate = {rate}\n")
        scene_ = load_scene(path)
        world = scene_.build()
        assert world.rigid_settings.rate == rate
        log: list[np.ndarray] = []
        world.run(until=scene_.run["until"], on_collisions=log.append)
        records = np.concatenate(log)
        assert records["body"].tolist() == [0]  # the cue ball, once
        assert records["partner"].tolist() == [1]
        assert world.positions[:, 2] == pytest.approx(0.028575, abs=1e-15)
        # (spins as the speed they give the ball's surface, R w [m/s], as velocities)
        ends.append((world.positions, world.velocities, 0.028575 * world.angular_velocities))
    for a, b in zip(*ends, strict=True):
        assert a == pytest.approx(b, abs=1e-9)


@pytest.mark.needs_jit  # 200 and 800 steps of 3 balls and 4 rails
def test_the_three_cushion_shot_makes_its_point_at_any_rate(tmp_path: Path) -> None:
    # three-cushion: the cue ball (0) meets the yellow (1), then three cushions (the rails,
    # bodies 3 to 6: bottom, right, top), then the red (2); every impact is solved at its
    # time (balls by carom.collide's law, cushions at their nose, the cloth in closed form
    # between), so 50 and 200 Hz give the same impacts at the same times, and the same
    # balls after 4 s, to the time of impact's tolerance (measured 3.7e-8 m, 1.5e-8 m/s)
    text = find_scene("three-cushion").read_text()
    runs = []
    for rate in (50.0, 200.0):  # (frames every 0.01 s: whole numbers of steps)
        path = tmp_path / f"three-cushion-{rate:g}.toml"
        path.write_text(text.replace("rate = 100.0", f"rate = {rate}"))
        world = load_scene(path).build()
        log: list[np.ndarray] = []
        world.run(until=4.0, on_collisions=log.append)
        records = np.concatenate(log)
        cue = records[records["body"] == 0]
        assert cue["partner"][:5].tolist() == [1, 6, 3, 4, 2]
        assert (cue["kind"][:5] == 0).all()  # bodies all: balls and rails
        runs.append((records, world.positions[:3], world.velocities[:3]))
    (a, xa, va), (b, xb, vb) = runs
    assert a[["body", "partner"]].tolist() == b[["body", "partner"]].tolist()
    assert a["time"] == pytest.approx(b["time"], abs=1e-7)
    assert xa == pytest.approx(xb, abs=1e-6)
    assert va == pytest.approx(vb, abs=1e-6)


@pytest.mark.needs_jit  # 240 steps of 64 balls on 264 triangles
def test_balls_poured_into_the_bowl_settle_inside_it() -> None:
    # every ball ends at rest inside the bowl (a sphere of 0.5 m about its centre, rim at
    # z = 0.6): its centre within 0.5 m less its radius of the bowl's centre, below the rim
    world = load_scene(find_scene("bowl")).build()
    world.run(until=4.0)
    balls = world.positions[1:]
    assert np.linalg.norm(balls - [1.0, 1.0, 0.6], axis=1).max() <= 0.5 - 0.04 + 1e-3
    assert balls[:, 2].max() < 0.6
    assert np.linalg.norm(world.velocities, axis=1).max() < 1e-3


@pytest.mark.needs_jit  # concave rings: 12 pieces each
def test_rings_tossed_over_the_pole_fall_around_it() -> None:
    # the rings (hole 0.11 m in radius) fall around the pole (0.02 m): they end stacked on the
    # floor with the pole through their holes (centres within the hole's clearance)
    world = load_scene(find_scene("ring-toss")).build()
    world.run(until=3.0)
    rings = world.positions[1:]
    assert np.hypot(rings[:, 0] - 1.0, rings[:, 1] - 1.0).max() < 0.11 - 0.02
    assert np.sort(rings[:, 2])[0] == pytest.approx(0.04, abs=1e-3)  # the lowest on the floor
    assert rings[:, 2].max() < 0.3  # all slid down the pole
