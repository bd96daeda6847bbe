"""The hostile corpus: scenes and API calls a careless or malicious user might write, each
with the words its refusal must contain (issue 12). Every entry was once a crash, a
traceback, a hang, a run that filled the disk, or a result broken by overflow."""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np

import carom
import carom.meshes

#: a minimal good scene; each hostile scene is this with one thing changed
BASE = """\
[world]
dimension = 2
box = [4.0, 2.0]

[[bodies]]
positions = [[1.0, 1.0]]
velocities = [[1.0, 0.0]]
radius = 0.1

[run]
until = 0.5
"""

GAS = "\n[[gas]]\ncount = 5\npacking = 0.1\nradius = 0.05\n"


def _with(old: str, new: str, extra: str = "") -> str:
    assert old in BASE
    return BASE.replace(old, new) + extra


#: (id, scene text, a regular expression the one-line message must match)
SCENES: list[tuple[str, str, str]] = [
    # 1. numbers that overflowed the cell grid (segfault) or asked for 114 TiB
    ("box-1e300", _with("box = [4.0, 2.0]", "box = [1e300, 1e300]"), r"at most 1e\+100"),
    ("radius-1e-310", _with("radius = 0.1", "radius = 1e-310"), r"radius: must be at least 1e-100"),
    (
        "radius-below-resolution",
        _with("radius = 0.1", "radius = 1e-13"),
        r"below 1e-12 of the box",
    ),
    # 2. tracebacks instead of messages
    ("nested-too-deeply", "a = " + "[" * 100_000 + "]" * 100_000 + "\n" + BASE, r"nested too"),
    ("negative-seed", BASE + GAS + "seed = -1\n", r"seed: must be a whole number from 0"),
    ("seed-too-large", BASE + GAS + "seed = 18446744073709551616\n", r"seed: must be a whole"),
    (
        "lattice-of-1e9",
        _with("box = [4.0, 2.0]", "box = [1e6, 1e6]")
        + "\n[[lattice]]\nshape = [31623, 31623]\norigin = [1.0, 1.0]\nspacing = 1.0\n"
        + "radius = 0.1\n",
        r"places 1,000,014,129 bodies, more than the 100,000,000",
    ),
    (
        "rack-of-1e12",
        _with("box = [4.0, 2.0]", "box = [1e7, 1e7]")
        + "\n[[rack]]\nrows = 2000000\napex = [1.0, 1.0]\nradius = 0.1\n",
        r"places 2,000,001,000,001 bodies, more than the 100,000,000",
    ),
    # 3. work that never ends or fills the disk
    (
        "jammed-gas",
        _with("box = [4.0, 2.0]", "box = [10.0, 10.0]")
        + "\n[[gas]]\ncount = 5000\npacking = 0.95\nradius = 0.07\n",
        r"packing of 0\.7697, beyond 0\.547, where placing them at random jams",
    ),
    (
        "frames-1e18",
        _with("until = 0.5", "until = 1e9\nframe_interval = 1e-9"),
        r"1,000,000,000,000,000,002 frames, more than the 10,000,000",
    ),
    ("temperature-1e308", BASE + GAS + "temperature = 1e308\n", r"temperature: must be at most"),
    ("mass-1e-320", _with("radius = 0.1", "radius = 0.1\nmass = 1e-320"), r"mass: must be at"),
    # 4. physics broken by overflow: a sphere that flew through the wall
    ("speed-1e200", _with("[[1.0, 0.0]]", "[[1e200, 0.0]]"), r"velocities: .*at most 1e\+100"),
    (
        "gravity-1e200",
        _with("box = [4.0, 2.0]", "box = [4.0, 2.0]\ngravity = [0.0, -1e200]"),
        r"gravity: .*at most 1e\+100",
    ),
    ("until-1e300", _with("until = 0.5", "until = 1e300"), r"until: must be at most 1e\+100"),
    # 8. keys that would drive the terminal: echoed escaped
    (
        "escape-in-key",
        _with("[world]\n", '[world]\n"\\u001b[2J\\u0007evil\\u202e" = 1\n'),
        r"\\x1b\[2J\\x07evil\\u202e: is not a known key",
    ),
    ("escape-in-table", BASE + '\n["\\u001b[31mred"]\nx = 1\n', r"unknown table \[\\x1b\[31mred\]"),
    # 9. quietly surprising
    (
        "material-twice",
        "[[materials]]\nname = 'a'\nrestitution = 0.5\n[[materials]]\nname = 'a'\n"
        "restitution = 0.9\n" + BASE,
        r"name: 'a' is defined twice",
    ),
]

#: a minimal good scene of the 3D rigid engine (issue 45); its hostile scenes change one thing
RIGID_3D = """\
[world]
dimension = 3
box = [2.0, 2.0, 2.0]
gravity = [0.0, 0.0, -9.81]

[[bodies]]
shape = "box"
size = [0.2, 0.2, 0.2]
positions = [[1.0, 1.0, 0.5]]

[run]
until = 0.1
"""


def _rigid_3d(old: str, new: str) -> str:
    assert old in RIGID_3D
    return RIGID_3D.replace(old, new)


SCENES += [
    # issue 45: a box within the limits whose inertia overflows float64 (once a warning, a run
    # that never fell and null energies)
    (
        "box-1e99-in-limits",
        _rigid_3d("size = [0.2, 0.2, 0.2]", "size = [1e99, 1e99, 1e99]").replace(
            "box = [2.0, 2.0, 2.0]", "box = [1e100, 1e100, 1e100]"
        ),
        r"the box's mass and inertia overflow float64 at this size",
    ),
    # issue 45: a 3D piece in a 2D compound, a 3D body in a 2D lattice (once AssertionErrors)
    (
        "ball-in-2d-compound",
        _with(
            "radius = 0.1",
            'shape = "compound"\npieces = [{shape = "ball", radius = 0.1, offset = [0.0, 0.0]}]',
        ),
        r"piece 1: a ball is a 3D shape; in 2D use circle",
    ),
    (
        "hull-in-2d-lattice",
        BASE
        + "\n[[lattice]]\nshape = [2, 2]\norigin = [2.0, 1.0]\nspacing = 0.5\n"
        + 'body = {shape = "hull", vertices = [[0,0,0],[0.1,0,0],[0,0.1,0],[0,0,0.1]]}\n',
        r"\[\[lattice\]\] #1: a hull is a 3D shape",
    ),
    # issue 45: a piece's orientation in 2D (or angle in 3D) was ignored
    (
        "orientation-of-a-2d-piece",
        _with(
            "radius = 0.1",
            'shape = "compound"\npieces = [{shape = "circle", radius = 0.1, '
            "orientation = [1.0, 0.0, 0.0, 0.0]}]",
        ),
        r"piece 1: orientation turns a piece in 3D; in 2D a piece is turned by angle = 0\.0",
    ),
    (
        "angle-of-a-3d-piece",
        _rigid_3d(
            'shape = "box"\nsize = [0.2, 0.2, 0.2]',
            'shape = "compound"\npieces = [{shape = "ball", radius = 0.1, angle = 0.5}]',
        ),
        r"piece 1: angle turns a piece in 2D; in 3D a piece is turned by orientation = ",
    ),
    # issue 45: a static body's velocities were dropped without a word
    (
        "static-sphere-moving",
        _with("radius = 0.1", 'radius = 0.1\nkind = "static"'),
        r"a static body never moves, but velocities is given; remove velocities",
    ),
    (
        "static-box-moving-3d",
        _rigid_3d(
            "positions = [[1.0, 1.0, 0.5]]",
            'positions = [[1.0, 1.0, 0.5]]\nvelocities = [[1.0, 0.0, 0.0]]\nkind = "static"',
        ),
        r"a static body never moves, but velocities is given",
    ),
    # issue 45: a scalar angular velocity on a 3D body was read as [3, 3, 3] rad/s
    (
        "spin-number-3d",
        _rigid_3d(
            "positions = [[1.0, 1.0, 0.5]]",
            "positions = [[1.0, 1.0, 0.5]]\nangular_velocities = 3.0",
        ),
        r"angular_velocities is a vector \[wx, wy, wz\] \[rad/s\] in 3D.*\[0, 0, 3\.0\]",
    ),
]


def _add_2d(shape: Any, **kw: Any) -> int:
    return carom.World(2, [10.0, 10.0]).add_body(shape, [5.0, 5.0], **kw)


def _add_3d(shape: Any, **kw: Any) -> int:
    return carom.World(3, [10.0, 10.0, 10.0]).add_body(shape, [5.0, 5.0, 5.0], **kw)


#: (id, call, a regular expression the CaromError's message must match)
API: list[tuple[str, Callable[[], Any], str]] = [
    # issue 45: shapes outside carom.limits (once a ZeroDivisionError, an OverflowError, a
    # RuntimeWarning, or accepted with masses down to 1e-300 kg)
    ("box-1e-99", lambda: _add_2d(carom.shapes.Box(1e-99, 1e-99)), r"the box weighs 1e-198 kg"),
    (
        "polygon-1e-150",
        lambda: _add_2d(carom.shapes.Polygon([[0, 0], [1e-150, 0], [0, 1e-150]])),
        r"the polygon reaches 1e-150 m from its origin; carom takes shapes from 1e-100",
    ),
    (
        "polygon-1e300",
        lambda: _add_2d(carom.shapes.Polygon([[0, 0], [1e300, 0], [0, 1e300]])),
        r"Polygon vertices\[1, 0\] = 1e\+300 exceeds 1e\+100 m",
    ),
    ("box-3d-1e300", lambda: _add_3d(carom.shapes3d.Box([1e300] * 3)), r"reaches 5e\+299 m"),
    (
        # within the limits, but its second moment of area (size^4) overflows: once a
        # RuntimeWarning, and a run that wrote null energies
        "polygon-1e99-in-limits",
        lambda: _add_2d(carom.shapes.Polygon([[0, 0], [1e99, 0], [1e99, 1e99], [0, 1e99]])),
        r"the polygon's mass and inertia overflow float64 at this size",
    ),
    (
        "static-polygon-1e99-in-limits",
        lambda: _add_2d(
            carom.shapes.Polygon([[0, 0], [1e99, 0], [1e99, 1e99], [0, 1e99]]), kind="static"
        ),
        r"the polygon's mass and inertia overflow float64 at this size",
    ),
    (
        "box-3d-1e99-in-limits",
        lambda: _add_3d(carom.shapes3d.Box([1e99] * 3), mass=1.0),
        r"the box's mass and inertia overflow float64 at this size",
    ),
    ("box-3d-1e-99", lambda: _add_3d(carom.shapes3d.Box([1e-99] * 3)), r"weighs 1e-297 kg"),
    (
        "mass-1e-300",
        lambda: _add_2d(carom.shapes.Box(1.0, 1.0), mass=1e-300),
        r"the box weighs 1e-300 kg; carom takes masses from 1e-100 to 1e\+100 kg",
    ),
    (
        "static-box-1e-200",
        lambda: _add_2d(carom.shapes.Box(1e-200, 1e-200), kind="static"),
        r"the box reaches 5e-201 m from its origin",
    ),
    (
        "hull-1e300",
        lambda: carom.shapes3d.Hull(np.eye(4, 3) * 1e300),
        r"Hull points\[0, 0\] = 1e\+300 exceeds 1e\+100 m",
    ),
    # issue 45: runs beyond reason started without a word (6e101 steps; 1e12 frames grew to
    # 3.8 GB); the API took until = 1e300, which the CLI refuses
    ("until-1e300-api", lambda: _one_ball().run(1e300), r"until = 1e\+300 s exceeds 1e\+100 s"),
    (
        "rigid-1e12-steps",
        lambda: _one_box(rate=1e12).run(1.0),
        r"takes 1e\+12 steps of 1e-12 s, more than the 1e\+09 carom takes in one run",
    ),
    (
        "rigid-until-1e100",
        lambda: _one_box().run(1e100),
        r"reaching until = 1e\+100 s from 0 s takes 6e\+101 steps",
    ),
    (
        "frames-1e12",
        lambda: _one_box().run(1.0, frame_interval=1e-12),
        r"frames every 1e-12 s up to until = 1 s are 1e\+12 frames, more than the 10,000,000",
    ),
    (
        "decompose-seed-negative",
        lambda: carom.meshes.decompose(carom.meshes.torus_mesh(0.3, 0.1), seed=-1, cache=False),
        r"seed must be a whole number from 0 to 2147483647 \(CoACD's seed\); got -1",
    ),
    (
        "mesh-1e300",
        lambda: carom.meshes.Mesh([[0, 0, 0], [1e300, 0, 0], [0, 1, 0]], [[0, 1, 2]]),
        r"Mesh vertices\[1, 0\] = 1e\+300 exceeds 1e\+100 m",
    ),
    (
        "spin-number-3d",
        lambda: carom.World(3, [1, 1, 1]).add_body(
            carom.shapes3d.Box([0.1, 0.1, 0.1]), [0.5, 0.5, 0.5], angular_velocity=3.0
        ),
        r"angular_velocities is a vector \[wx, wy, wz\]",
    ),
    ("dim-float", lambda: carom.World(3.0, [1, 1, 1]), r"dim must be the whole number 2 or 3"),  # type: ignore[arg-type]
    ("box-text", lambda: carom.World(3, "abc"), r"box must be 3 numbers"),
    ("box-1e300", lambda: carom.World(3, [1e300] * 3), r"box\[0\] = 1e\+300 exceeds 1e\+100"),
    ("t_c-text", lambda: carom.World(3, [1, 1, 1], t_c="x"), r"t_c must be a number"),  # type: ignore[arg-type]
    (
        "gravity-1e200",
        lambda: carom.World(3, [1, 1, 1], gravity=[0, 0, -1e200]),
        r"gravity\[2\] = -1e\+200 exceeds",
    ),
    (
        "positions-3d-array",
        lambda: carom.World(3, [1, 1, 1]).add_spheres(np.zeros((2, 2, 3)), radius=0.1),
        r"positions must have shape \(n, 3\) or \(3,\) \[m\]; got shape \(2, 2, 3\)",
    ),
    (
        "positions-text",
        lambda: carom.World(3, [1, 1, 1]).add_spheres([["a", "b", "c"]], radius=0.1),
        r"positions must be numeric",
    ),
    (
        "radius-text",
        lambda: carom.World(3, [1, 1, 1]).add_spheres([0.5, 0.5, 0.5], radius="big"),
        r"radius must be numeric",
    ),
    (
        "radius-1e-310",
        lambda: carom.World(3, [1, 1, 1]).add_spheres([0.5, 0.5, 0.5], radius=1e-310),
        r"radius\[0\] = 1e-310 is below 1e-100 m",
    ),
    (
        "mass-1e-320",
        lambda: carom.World(3, [1, 1, 1]).add_spheres([0.5, 0.5, 0.5], radius=0.1, mass=1e-320),
        r"mass\[0\] = 1e-320 is below 1e-100 kg",
    ),
    (
        "speed-1e200",
        lambda: carom.World(3, [1, 1, 1]).add_spheres([0.5, 0.5, 0.5], [1e200, 0, 0], radius=0.1),
        r"velocities\[0, 0\] = 1e\+200 exceeds 1e\+100 m/s",
    ),
    (
        "spins-wrong-shape",
        lambda: carom.World(3, [1, 1, 1]).add_spheres(
            [0.5, 0.5, 0.5], radius=0.1, angular_velocities=[[1, 2]]
        ),
        r"angular_velocities must have shape",
    ),
    (
        "spins-nan",
        lambda: carom.World(3, [1, 1, 1]).add_spheres(
            [0.5, 0.5, 0.5], radius=0.1, angular_velocities=[np.nan, 0, 0]
        ),
        r"angular_velocities\[0\] = \[nan, 0.0, 0.0\] is not finite",
    ),
    (
        "inertia-factor-negative",
        lambda: carom.World(3, [1, 1, 1]).add_spheres(
            [0.5, 0.5, 0.5], radius=0.1, inertia_factor=-1
        ),
        r"inertia_factor",
    ),
    (
        "collide-centre-1e308",
        lambda: carom.collide([1e308, 0, 0], [0, 0, 0], 1.0, [0, 0, 0], [1, 0, 0], 1.0),
        r"x1\[0\] = 1e\+308 exceeds 1e\+100 m",
    ),
    (
        "collide-speed-1e308",
        lambda: carom.collide([1, 0, 0], [-1e308, 0, 0], 1.0, [0, 0, 0], [1, 0, 0], 1.0),
        r"v1\[0\] = -1e\+308 exceeds 1e\+100 m/s",
    ),
    (
        "collide-mass-1e-320",
        lambda: carom.collide([1, 0, 0], [-1, 0, 0], 1e-320, [0, 0, 0], [1, 0, 0], 1.0),
        r"m1 = 1e-320 is below 1e-100 kg",
    ),
    (
        "run-until-text",
        lambda: _one_ball().run(until="soon"),  # type: ignore[arg-type]
        r"until must be a finite time",
    ),
]


def _one_ball() -> carom.World:
    world = carom.World(2, [1.0, 1.0])
    world.add_spheres([0.5, 0.5], [1.0, 0.0], radius=0.1)
    return world


def _one_box(**settings: float) -> carom.World:
    """A box resting in a 2D world run by the rigid engine (``settings`` for its RigidSettings)."""
    from carom.engines.stepped.settings import RigidSettings

    world = carom.World(2, [1.0, 1.0], gravity=[0.0, -9.81], rigid=RigidSettings(**settings))
    world.add_body(carom.shapes.Box(0.2, 0.2), [0.5, 0.1])
    return world
