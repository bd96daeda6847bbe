"""One table of shape names (:data:`carom.shape_base.SHAPES`), read by the scene schema,
the body table and H5MD; and what every shape shares (:class:`carom.shape_base.ShapeBase`)."""

from __future__ import annotations

import math

import pytest

from carom import shapes, shapes3d
from carom.errors import CaromError
from carom.scene import schema
from carom.shape_base import SHAPE_CODES, SHAPE_NAMES, SHAPES


def test_every_name_has_one_code_and_the_schema_reads_the_table() -> None:
    assert len(set(SHAPE_CODES.values())) == len(SHAPES)  # no two names share a code
    assert all(SHAPE_NAMES[code] == name for name, code in SHAPE_CODES.items())
    assert tuple(SHAPES) == schema.SHAPES
    assert set(schema.PIECE_SHAPES) == {name for name, s in SHAPES.items() if s.piece}
    # the names a stored body carries today (H5MD files written before keep their meaning)
    assert SHAPE_CODES["sphere"] == 0
    assert SHAPE_CODES["ball"] == 10


@pytest.mark.parametrize(
    ("shape", "dim"),
    [
        (shapes.Circle(1.0), 2),
        (shapes.Capsule(1.0, 0.2), 2),
        (shapes.Box(1.0, 2.0), 2),
        (shapes.Polygon([[0, 0], [1, 0], [0, 1]]), 2),
        (shapes3d.Sphere(1.0), 3),
        (shapes3d.Capsule(1.0, 0.2), 3),
        (shapes3d.Box([1.0, 2.0, 3.0]), 3),
    ],
)
def test_each_shape_class_is_named_in_the_table_for_its_dimension(shape, dim) -> None:
    name = "ball" if isinstance(shape, shapes3d.Sphere) else shape.kind
    assert dim in SHAPES[name].dims


def test_mass_from_a_density_or_a_mass_alike_in_2d_and_3d() -> None:
    # a disk: m = rho pi r^2, I = m r^2 / 2; a ball: m = rho 4/3 pi r^3, I = 2/5 m r^2
    disk = shapes.Circle(2.0).mass_properties(density=3.0)
    assert disk.mass == pytest.approx(3.0 * math.pi * 4.0, rel=1e-15)
    assert disk.inertia == pytest.approx(disk.mass * 4.0 / 2.0, rel=1e-14)
    ball = shapes3d.Sphere(2.0).mass_properties(mass=5.0)
    assert ball.mass == 5.0
    assert ball.inertia[0, 0] == pytest.approx(0.4 * 5.0 * 4.0, rel=1e-14)
    for shape, unit in ((shapes.Circle(1.0), "kg/m\\^2"), (shapes3d.Sphere(1.0), "kg/m\\^3")):
        with pytest.raises(CaromError, match=f"give density \\[{unit}\\] or mass"):
            shape.mass_properties(density=1.0, mass=1.0)


def test_a_shape_without_area_has_no_mass_and_sizes_are_checked_by_name() -> None:
    with pytest.raises(CaromError, match="a segment with no area has no mass"):
        shapes.Segment([0, 0], [1, 0]).mass_properties(density=1.0)
    with pytest.raises(CaromError, match="Circle radius"):
        shapes.Circle(-1.0)
    with pytest.raises(CaromError, match="Sphere radius"):
        shapes3d.Sphere(0.0)
    with pytest.raises(CaromError, match="Capsule length"):
        shapes3d.Capsule(0.0, 1.0)
