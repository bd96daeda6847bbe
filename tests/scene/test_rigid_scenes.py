"""Rigid bodies in scene files (issue 13, item 6): the shape keys, [[pyramid]], a lattice of
bodies, [rigid], the built-in rigid scenes, and bad input named by file and line."""

from __future__ import annotations

import math
import textwrap
import tomllib
from pathlib import Path

import numpy as np
import pytest

import carom
from carom.errors import CaromError
from carom.run.runner import run_scene
from carom.scene import Scene, find_scene, load_scene
from carom.scene.schema import SceneError

HEAD = """
[world]
dimension = 2
box = [10.0, 10.0]
boundary = "open"
{world}

[run]
until = 0.5
"""


def scene(body: str, world: str = "", tmp: Path | None = None) -> carom.World:
    """The world of a 2D open scene with these tables (read from a file in ``tmp``)."""
    text = textwrap.dedent(HEAD.format(world=world)) + textwrap.dedent(body)
    if tmp is None:
        return Scene.from_dict(tomllib.loads(text), "scene.toml", text).build()
    path = tmp / "scene.toml"
    path.write_text(text)
    return load_scene(path).build()


def test_each_shape_key_makes_its_shape_with_exact_mass() -> None:
    world = scene(
        """
        [[bodies]]
        shape = "box"
        size = [2.0, 0.5]
        density = 3.0
        positions = [[1, 1], [4, 1]]
        angles = [0.0, 0.5]

        [[bodies]]
        shape = "capsule"
        size = 1.0
        radius = 0.25
        mass = 2.0
        positions = [[1, 5]]

        [[bodies]]
        shape = "polygon"
        vertices = [[0, 0], [1, 0], [0, 1]]
        positions = [[6, 6]]

        [[bodies]]
        shape = "compound"
        pieces = [{shape = "box", size = [2, 1], offset = [1, 0.5]},
                  {shape = "box", size = [1, 1], offset = [0.5, 1.5]}]
        positions = [[3, 7]]

        [[bodies]]
        shape = "chain"
        vertices = [[0, 0], [2, -1], [4, 0]]
        positions = [[5, 3]]
        kind = "static"
        """
    )
    assert world.engine_name == "rigid"
    m = world.masses
    assert m[0] == m[1] == pytest.approx(3.0, rel=1e-15)  # 2 x 0.5 m at 3 kg/m^2
    assert world.orientations[1] == 0.5
    assert m[2] == 2.0
    # the capsule (L = 1, r = 0.25): the rectangle L x 2r, m (L^2 + 4 r^2)/12, and two half
    # disks: each r^2/2 per mass about its circle's centre, moved to the caps by the parallel
    # axis through its own centroid (4 r / 3 pi from the flat side, d):
    # m_disk (r^2/2 + (L/2 + d)^2 - d^2) = m_disk (r^2/2 + L^2/4 + L d)
    rho = 2.0 / (1.0 * 0.5 + math.pi * 0.25**2)
    disk = math.pi * 0.25**2
    d = 4 * 0.25 / (3 * math.pi)
    inertia = rho * (0.5 * (1.0 + 0.25) / 12 + disk * (0.25**2 / 2 + 0.25 + d))
    assert world.bodies.inertia[2] == pytest.approx(inertia, rel=1e-13)
    assert m[3] == pytest.approx(0.5, rel=1e-15)  # the triangle, density 1 by default
    np.testing.assert_allclose(world.positions[3], [6 + 1 / 3, 6 + 1 / 3], atol=1e-15)
    assert m[4] == pytest.approx(3.0, rel=1e-15)  # the L: 2 + 1 m^2
    assert not np.isfinite(m[5])


@pytest.mark.parametrize(
    ("body", "pattern"),
    [
        ('shape = "box"\npositions = [[1, 1]]', r"#1: a box needs size = \[width, height\]"),
        (
            'shape = "capsule"\nsize = [1, 2]\nradius = 0.1\npositions = [[1, 1]]',
            r"a capsule's size is one length",
        ),
        (
            'shape = "polygon"\nvertices = [[0, 0], [2, 0], [1, 0.2], [1, 2]]\n'
            "positions = [[1, 1]]",
            r"Compound",
        ),
        (
            'shape = "compound"\npieces = [{shape = "star"}]\npositions = [[1, 1]]',
            r"pieces: piece 1: shape must be one of",
        ),
        ('shape = "segment"\nvertices = [[0, 0], [1, 0]]\npositions = [[1, 1]]', r"no area"),
        (
            'shape = "box"\nsize = [1, 1]\npositions = [[1, 1], [1.5, 1]]',
            r"body 0 and body 1 overlap by 0.5 m",
        ),
        (
            'shape = "box"\nsize = [1, 1]\nangles = [0.1, 0.2]\npositions = [[1, 1]]',
            r"angles has 2 values for 1 positions",
        ),
    ],
)
def test_bad_rigid_bodies_are_named_by_file_and_table(
    tmp_path: Path, body: str, pattern: str
) -> None:
    with pytest.raises(CaromError, match=pattern) as caught:
        scene("[[bodies]]\n" + body, tmp=tmp_path)
    assert "scene.toml" in str(caught.value)


def test_shapes_match_the_dimension_and_a_lattice_takes_radius_or_body(tmp_path: Path) -> None:
    text = "[[bodies]]\nshape = 'polygon'\nvertices = [[0, 0], [1, 0], [0, 1]]\n"
    path = tmp_path / "three.toml"
    path.write_text(
        "[world]\ndimension = 3\nbox = [5, 5, 5]\n[run]\nuntil = 1.0\n"
        + text
        + "positions = [[1, 1, 1]]\n"
    )
    with pytest.raises(
        SceneError,
        match=r"'polygon' is a 2D shape; in 3D use sphere, capsule, box, compound, ball, hull "
        r"or mesh",
    ):
        load_scene(path)
    with pytest.raises(SceneError, match=r"'hull' is a 3D shape"):
        scene("[[bodies]]\nshape = 'hull'\nvertices = [[0, 0]]\npositions = [[1, 1]]", tmp=tmp_path)
    box2d = "[[bodies]]\nshape = 'box'\nsize = [1, 1]\npositions = [[1, 1, 1]]\n"
    path.write_text("[world]\ndimension = 3\nbox = [5, 5, 5]\n[run]\nuntil = 1.0\n" + box2d)
    with pytest.raises(SceneError, match=r"a box's size in 3D is \[x, y, z\]"):
        load_scene(path).build()
    both = "[[lattice]]\nshape = [2, 2]\norigin = [1, 1]\nspacing = 1.0\nradius = 0.1\n"
    with pytest.raises(SceneError, match=r"needs radius = \.\.\. \(spheres\) or body"):
        scene(both + "body = {shape = 'box', size = [0.5, 0.5]}\n", tmp=tmp_path)


def test_a_pyramid_stands_on_its_base_line_touching_and_not_overlapping() -> None:
    world = scene(
        """
        [[pyramid]]
        rows = 4
        base = [5.0, 1.0]
        size = [1.0, 0.5]
        gap = 0.1
        repeat = [2, 1]
        pitch = [6.0, 0.0]
        """
    )
    x = world.positions
    assert len(x) == 2 * (4 * 5 // 2)
    # the first pyramid: bottom row of 4 centred on x = 5 at y = 1 + 0.25, 1.1 m apart
    np.testing.assert_allclose(np.sort(x[:4, 0]), 5.0 + 1.1 * np.array([-1.5, -0.5, 0.5, 1.5]))
    np.testing.assert_allclose(x[:4, 1], 1.25)
    np.testing.assert_allclose(x[9], [5.0, 1.0 + 3.5 * 0.5])  # the top box
    np.testing.assert_allclose(x[10:] - x[:10], np.tile([6.0, 0.0], (10, 1)))


def test_a_lattice_of_bodies_and_the_rigid_settings(tmp_path: Path) -> None:
    world = scene(
        """
        [[lattice]]
        shape = [3, 2]
        origin = [1.0, 1.0]
        spacing = 1.0
        body = {shape = "box", size = [0.5, 0.25]}
        mass = 0.5
        """,
        world="[rigid]\nrate = 120.0\nsubsteps = 8\nsleep = false\n",
    )
    assert world.n_bodies == 6
    np.testing.assert_allclose(world.masses, 0.5)
    assert world.rigid_settings.rate == 120.0
    assert world.rigid_settings.substeps == 8
    assert world.rigid_settings.sleep is False


def test_the_tumbler_turns_at_its_own_rate() -> None:
    world = load_scene(find_scene("tumbler")).build()
    assert world.n_bodies == 1 + 45 * 45
    drum = 0
    omega = math.radians(25.0)  # Box2D's tumbler: 25 degrees a second
    assert world.angular_velocities[drum, 2] == pytest.approx(omega, rel=1e-15)
    world.run(0.5)  # 30 steps of 1/60 s
    assert world.orientations[drum] == pytest.approx(omega * 0.5, rel=1e-12)
    np.testing.assert_allclose(world.positions[drum], [12.0, 12.0], atol=1e-12)
    assert np.all(np.isfinite(world.positions))


@pytest.mark.parametrize(
    ("name", "count"),
    [
        ("large-pyramid", 1 + 5050),
        ("many-pyramids", 20 + 400 * 55),
        ("dominoes", 41),
        ("pyramid", 1 + 210 + 1),  # ground, 20 rows, the cannonball
        ("card-house", 1 + 40),
    ],
)
def test_the_rigid_built_in_scenes_build(name: str, count: int) -> None:
    world = load_scene(find_scene(name)).build()  # no overlap deeper than the slop
    assert world.n_bodies == count
    assert world.engine_name == "rigid"


def test_a_rigid_run_takes_whole_steps(tmp_path: Path) -> None:
    path = tmp_path / "steps.toml"
    path.write_text(
        textwrap.dedent(HEAD.format(world="gravity = [0, -9.81]")).replace(
            "until = 0.5", "until = 0.5\nframe_interval = 0.04"
        )
        + "[[bodies]]\nshape = 'box'\nsize = [1, 1]\npositions = [[5, 5]]\n"
    )
    with pytest.raises(CaromError, match=r"frame_interval = 0.04 s is not a whole number of "):
        run_scene(path, tmp_path / "out", progress=False)
    assert not (tmp_path / "out").exists()
