"""Scene files: what a good one builds, and the message each kind of bad one gets."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import carom
from carom.errors import CaromError
from carom.scene import Scene, SceneError, load_scene

GOOD = """\
# two balls and a gas in a 2D box
[world]
dimension = 2
box = [4.0, 2.0]
boundary = "walls"
walls = 0.9

[[materials]]
name = "rubber"
restitution = 0.8

[[bodies]]
positions = [[0.5, 1.0], [3.5, 1.0]]
velocities = [[1.0, 0.0], [-1.0, 0.0]]
radius = 0.1
mass = [1.0, 2.0]
material = "rubber"

[[gas]]
count = 20
packing = 0.1
radius = 0.05
seed = 3

[run]
until = 2.0
frame_interval = 0.1
"""


def _write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "scene.toml"
    path.write_text(text)
    return path


def test_a_good_scene_builds_its_world(tmp_path: Path) -> None:
    scene = load_scene(_write(tmp_path, GOOD))
    world = scene.build()
    assert world.n_bodies == 22
    np.testing.assert_array_equal(world.box, [4.0, 2.0])
    assert scene.run == {"until": 2.0, "frame_interval": 0.1}
    # the gas: 20 radius-0.05 disks inside the walls, none overlapping, zero total momentum
    # (unit mass: the mean velocity was removed), the same for the same seed
    x = world.positions[2:]
    assert np.all(x >= 0.05)
    assert np.all(x <= np.array([4.0, 2.0]) - 0.05)
    d = np.linalg.norm(x[:, None] - x[None], axis=-1) + np.eye(20)
    assert d.min() >= 0.1
    # 20 velocities of order 1 m/s, their mean removed: the sum is zero to ~20 eps (4e-15)
    np.testing.assert_allclose(world.velocities[2:].sum(axis=0), 0.0, atol=1e-12)
    again = load_scene(_write(tmp_path, GOOD)).build()
    np.testing.assert_array_equal(again.positions, world.positions)
    # and it runs: the two balls meet head on (e = 0.8 from the material)
    world.run(until=scene.run["until"])
    assert world.stats.collisions > 0


def test_the_python_api_builds_the_same_scene(tmp_path: Path) -> None:
    import tomllib

    from_file = load_scene(_write(tmp_path, GOOD)).build()
    from_dict = Scene.from_dict(tomllib.loads(GOOD)).build()
    np.testing.assert_array_equal(from_file.positions, from_dict.positions)
    np.testing.assert_array_equal(from_file.velocities, from_dict.velocities)


TWICE = 'name = "rubber"\nrestitution = 0.8\n'
#: (change to GOOD, the message it must get): each bad input the scene format refuses
BAD_SCENES: list[tuple[tuple[str, str], str]] = [
    # unparsable TOML: tomllib's line and column
    (("box = [4.0, 2.0]", "box = [4.0, 2.0"), r"scene\.toml: not valid TOML: .*line \d+"),
    # unknown key, with its line: a misspelt one answered with the nearest, another with
    # the list of them
    (
        ('boundary = "walls"', 'boundry = "walls"'),
        r"scene\.toml:5: \[world\] boundry: is not a known key; did you mean boundary\?$",
    ),
    (
        ('boundary = "walls"', 'colour = "red"'),
        r"scene\.toml:5: \[world\] colour: is not a known key; use one of dimension, box",
    ),
    (
        ("[run]", "[rnu]"),
        r"unknown table \[rnu\]; did you mean \[run\]\?",
    ),
    # wrong type
    (
        ("dimension = 2", 'dimension = "two"'),
        r"scene\.toml:3: \[world\] dimension: must be an integer, got 'two' \(str\)",
    ),
    # missing required key
    (("until = 2.0\n", ""), r"\[run\] until: is required; add until = \.\.\."),
    # zero or negative radius and mass
    (
        ("radius = 0.1", "radius = -0.1"),
        r"scene\.toml:15: \[\[bodies\]\] #1 radius: must be > 0, got -0\.1",
    ),
    (
        ("mass = [1.0, 2.0]", "mass = [1.0, 0.0]"),
        r"\[\[bodies\]\] #1 mass: must be > 0, got 0\.0",
    ),
    # restitution outside [0, 1]
    (
        ("restitution = 0.8", "restitution = 1.2"),
        r"scene\.toml:10: \[\[materials\]\] #1 restitution: must lie in \[0, 1\]; got 1\.2",
    ),
    # bodies overlapping at the start
    (
        ("[[0.5, 1.0], [3.5, 1.0]]", "[[0.5, 1.0], [0.6, 1.0]]"),
        r"scene\.toml: spheres 0 and 1 overlap",
    ),
    # outside the box
    (
        ("[[0.5, 1.0], [3.5, 1.0]]", "[[0.5, 1.0], [4.5, 1.0]]"),
        r"scene\.toml: sphere 1 at \[4\.5, 1\.0\] with radius 0\.1 m reaches outside the box",
    ),
    # frame interval <= 0
    (
        ("frame_interval = 0.1", "frame_interval = 0.0"),
        r"scene\.toml:27: \[run\] frame_interval: must be > 0, got 0\.0",
    ),
    # a material nobody defined
    (
        ('material = "rubber"', 'material = "steel"'),
        r"names material 'steel', which no \[\[materials\]\] table defines",
    ),
    # rows of the wrong dimension
    (
        ("[[1.0, 0.0], [-1.0, 0.0]]", "[[1.0, 0.0, 0.0], [-1.0, 0.0]]"),
        r"velocities: rows must have 2 numbers in a 2D world",
    ),
    # wall restitutions: neither one number nor one per wall
    (
        ("walls = 0.9", "walls = [0.9, 0.9, 0.9]"),
        r"\[world\] walls: must be one restitution or material name, or one per wall face",
    ),
    # a key renamed since: the message names the new one
    (
        ("walls = 0.9", "wall_restitution = 0.9"),
        r"scene\.toml:6: \[world\] wall_restitution: was renamed to walls; write walls = \.\.\.",
    ),
    # two materials of one name (the second silently won)
    (
        (TWICE, TWICE + '\n[[materials]]\nname = "rubber"\nrestitution = 0.3\n'),
        r"\[\[materials\]\] #2 name: 'rubber' is defined twice \(also \[\[materials\]\] #1\)",
    ),
    # walls of a material no table defines
    (("walls = 0.9", 'walls = "steel"'), r"\[world\] walls: names material 'steel'"),
    # a rigid body's shape needs its own keys
    (
        ("radius = 0.1\n", 'radius = 0.1\nshape = "box"\n'),
        r"\[\[bodies\]\] #1: a box needs size = \[width, height\] \[m\]",
    ),
    (("walls = 0.9", 'walls = 0.9\nengine = "warp"'), r"\[world\] engine: must be one of"),
    # a gas that cannot fit
    (
        ("packing = 0.1", "packing = 0.001"),
        r"\[\[gas\]\] #1: 20 spheres of radius 0\.05 need a packing of",
    ),
]


@pytest.mark.parametrize(("change", "message"), BAD_SCENES)
def test_each_bad_scene_gets_one_clear_message(
    tmp_path: Path, change: tuple[str, str], message: str
) -> None:
    old, new = change
    assert old in GOOD
    path = _write(tmp_path, GOOD.replace(old, new, 1))
    with pytest.raises(SceneError, match=message):
        load_scene(path).build()


def test_a_scene_built_without_its_engine_checks_the_start_on_its_first_run(
    tmp_path: Path,
) -> None:
    # build(engine=False) places the bodies and builds nothing else (no kernel compiles:
    # the showcase sorts its scenes by engine that way); the overlap is refused at the run
    path = _write(tmp_path, GOOD.replace("[[0.5, 1.0], [3.5, 1.0]]", "[[0.5, 1.0], [0.6, 1.0]]"))
    world = load_scene(path).build(engine=False)
    assert world.engine is None
    assert world.n_bodies == 22
    with pytest.raises(CaromError, match=r"spheres 0 and 1 overlap"):
        world.run(0.1)


def test_walls_take_materials_by_name(tmp_path: Path) -> None:
    scene = GOOD.replace("walls = 0.9", 'walls = ["rubber", 0.5, 1.0, 1.0]')
    world = load_scene(_write(tmp_path, scene)).build()
    assert [m.restitution for m in world.walls] == [0.8, 0.5, 1.0, 1.0]


def test_a_missing_file_is_named(tmp_path: Path) -> None:
    with pytest.raises(SceneError, match=r"nope\.toml: no such scene file; check the path"):
        load_scene(tmp_path / "nope.toml")


def test_scene_errors_are_value_errors() -> None:
    # the API's promise: bad input raises ValueError (CaromError) subclasses
    assert issubclass(SceneError, carom.CaromError)
    assert issubclass(SceneError, ValueError)


def test_a_3d_periodic_gas_at_the_packing_asked_for() -> None:
    # 200 spheres of radius 0.5 at packing 0.2 in a periodic cube: the box holds exactly that
    # packing (count x 4/3 pi r^3 / L^3), no pair overlaps under the minimum image
    side = (200 * 4 / 3 * math.pi * 0.125 / 0.2) ** (1 / 3)
    scene = Scene.from_dict(
        {
            "world": {"dimension": 3, "box": [side] * 3, "boundary": "periodic"},
            "gas": [{"count": 200, "packing": 0.2, "radius": 0.5, "seed": 1}],
            "run": {"until": 1.0},
        }
    )
    world = scene.build()
    x = world.positions
    d = x[:, None] - x[None]
    d -= side * np.round(d / side)
    dist = np.linalg.norm(d, axis=-1) + np.eye(200) * side
    assert dist.min() >= 1.0


GENERATED = """\
[world]
dimension = 2
box = [4.0, 3.0]

[[row]]
count = 4
start = [0.5, 0.5]
radius = 0.1
velocity = [0.5, 0.0]

[[rack]]
rows = 5
apex = [2.0, 1.5]
radius = 0.1
gap = 0.01

[[lattice]]
shape = [3, 2]
origin = [0.5, 2.5]
spacing = 0.25
radius = 0.1
temperature = 1.0
seed = 4

[[pegs]]
rows = 3
top = [3.5, 2.8]
spacing = [0.3, 0.3]
radius = 0.05

[run]
until = 1.0
"""


def test_generators_place_rows_racks_lattices_and_pegs(tmp_path: Path) -> None:
    scene = load_scene(_write(tmp_path, GENERATED))
    world = scene.build()
    # 4 in the row, 5 * 6 / 2 = 15 in the rack, 3 * 2 in the lattice, 3 * 4 / 2 = 6 pegs
    assert world.n_bodies == 4 + 15 + 6 + 6
    x, v = world.positions, world.velocities
    row, rack, lattice = x[:4], x[4:19], x[19:25]
    # the row touches: centres one diameter apart along +x (spacing's default)
    np.testing.assert_allclose(np.diff(row[:, 0]), 0.2, rtol=0, atol=1e-15)
    np.testing.assert_array_equal(v[:4], [[0.5, 0.0]] * 4)
    # the rack: nearest neighbours at the pitch 2 r + gap = 0.21, apex first, opening to +x
    d = np.linalg.norm(rack[:, None] - rack[None], axis=-1) + np.eye(15)
    np.testing.assert_allclose(d.min(axis=1), 0.21, rtol=1e-14, atol=0)
    np.testing.assert_array_equal(rack[0], [2.0, 1.5])
    assert rack[:, 0].max() == pytest.approx(2.0 + 4 * 0.21 * math.sqrt(3) / 2, rel=1e-14, abs=0)
    # the lattice: a 3 x 2 grid, Maxwell velocities drawn with its seed
    np.testing.assert_allclose(np.unique(lattice[:, 0]), [0.5, 0.75, 1.0], rtol=0, atol=1e-15)
    np.testing.assert_allclose(np.unique(lattice[:, 1]), [2.5, 2.75], rtol=0, atol=1e-15)
    assert np.all(v[19:25] != 0)
    # pegs are static: infinite mass, never moving
    assert np.all(np.isinf(world.masses[25:]))
    world.run(until=1.0, log=False)
    np.testing.assert_array_equal(world.positions[25:], x[25:])
    # and the Python API takes the same tables
    import tomllib

    again = Scene.from_dict(tomllib.loads(GENERATED)).build()
    np.testing.assert_array_equal(again.velocities, v)


@pytest.mark.parametrize(
    ("change", "message"),
    [
        (
            ("spacing = [0.3, 0.3]", "spacing = [0.3]"),
            r"scene\.toml:\d+: \[\[pegs\]\] #1 spacing: must be \[dx, dy\] with both > 0",
        ),
        (
            ("rows = 3\n", 'rows = 3\nlayout = "staggered"\n'),
            r"\[\[pegs\]\] #1 columns: is required for layout = 'staggered'",
        ),
        (
            ("velocity = [0.5, 0.0]", "direction = [0.0, 0.0]"),
            r"scene\.toml:\d+: \[\[row\]\] #1 direction: is the zero vector",
        ),
        (
            ("shape = [3, 2]", "shape = [3, 2, 2]"),
            r"\[\[lattice\]\] #1 shape: has 3 components for a 2D world",
        ),
        (("shape = [3, 2]", "shape = [3, 0]"), r"shape: must be a list of whole numbers >= 1"),
        (("rows = 5", "rows = 0"), r"\[\[rack\]\] #1 rows: must be >= 1, got 0"),
        # a rack that runs into the lattice
        (("apex = [2.0, 1.5]", "apex = [0.6, 2.3]"), r"spheres \d+ and \d+ overlap"),
    ],
)
def test_each_bad_generator_gets_one_clear_message(
    tmp_path: Path, change: tuple[str, str], message: str
) -> None:
    old, new = change
    assert old in GENERATED
    path = _write(tmp_path, GENERATED.replace(old, new, 1))
    with pytest.raises(SceneError, match=message):
        load_scene(path).build()
