"""Overlap queries (issue 43, item 4): which bodies hold a point or meet a box, exactly.

Each shape is probed just inside and just outside its boundary, at a point whose distance
from the shape is written out in closed form: inside by 1e-9 m counts, outside by 1e-9 m does
not (the tests tell a boundary apart to a part in 10^9 of the shapes' metre sizes; the
kernels' distances are exact to round-off, 1e-15 m here)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.errors import CaromError
from carom.shapes import Box, Capsule, Circle, Polygon
from carom.shapes3d import Box as Box3D
from carom.shapes3d import Capsule as Capsule3D
from carom.shapes3d import Sphere

EPS = 1e-9


def rotate(angle: float, v: list[float]) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([c * v[0] - s * v[1], s * v[0] + c * v[1]])


def world_2d() -> carom.World:
    w = carom.World(2, [20.0, 20.0], boundary="open")
    w.add_body(Box(2.0, 1.0), [3.0, 3.0], angle=0.3)  # 0
    w.add_body(Circle(0.5), [8.0, 3.0])  # 1
    w.add_body(Capsule(1.0, 0.2), [13.0, 3.0], angle=-0.7)  # 2
    w.add_body(Polygon([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]], radius=0.1), [3.0, 10.0])  # 3
    return w


def test_a_point_is_in_each_2d_shape_up_to_its_boundary() -> None:
    w = world_2d()
    centre = w.positions
    # the box: along its turned x axis, its half-width 1 m from its centre
    edge = centre[0] + rotate(0.3, [1.0, 0.0])
    out = rotate(0.3, [1.0, 0.0])
    assert w.overlap_point(edge - EPS * out).tolist() == [0]
    assert w.overlap_point(edge + EPS * out).tolist() == []
    # the disc: 0.5 m from its centre, any direction
    u = np.array([0.6, 0.8])
    assert w.overlap_point(centre[1] + (0.5 - EPS) * u).tolist() == [1]
    assert w.overlap_point(centre[1] + (0.5 + EPS) * u).tolist() == []
    # the capsule: beyond its core's end by its radius, along its turned axis
    tip = centre[2] + rotate(-0.7, [0.5 + 0.2, 0.0])
    axis = rotate(-0.7, [1.0, 0.0])
    assert w.overlap_point(tip - EPS * axis).tolist() == [2]
    assert w.overlap_point(tip + EPS * axis).tolist() == []


def test_a_rounded_corner_is_an_arc() -> None:
    w = world_2d()
    # the rounded triangle's right-angle corner: the core corner at the polygon's own origin,
    # placed at (3, 10), rounded by 0.1 m: a point 0.1 m from it along the corner's bisector
    # outward is on the arc (its bounding box reaches 0.041 m further)
    corner = np.array([3.0, 10.0])
    out = -np.array([1.0, 1.0]) / math.sqrt(2.0)
    assert w.overlap_point(corner + (0.1 - EPS) * out).tolist() == [3]
    assert w.overlap_point(corner + (0.1 + EPS) * out).tolist() == []


def test_a_box_meets_a_disc_only_within_its_radius_of_the_corner() -> None:
    w = world_2d()
    c = w.positions[1]
    # the box's high corner on the disc's diagonal: in at 0.5 - eps from its centre, out at
    # 0.5 + eps (a test of bounding boxes would say "in" for both)
    k = (0.5 - EPS) / math.sqrt(2.0)
    assert w.overlap_box(c - 2.0, c - k).tolist() == [1]
    k = (0.5 + EPS) / math.sqrt(2.0)
    assert w.overlap_box(c - 2.0, c - k).tolist() == []
    assert w.overlap_box([0.0, 0.0], [20.0, 20.0]).tolist() == [0, 1, 2, 3]


def world_3d() -> carom.World:
    w = carom.World(3, [20.0, 20.0, 20.0], boundary="open")
    w.add_plane([0.0, 0.0, 0.0], [0.0, 0.0, 1.0])
    w.add_body(
        Box3D([2.0, 1.0, 1.0]),
        [3.0, 3.0, 3.0],
        orientation=[math.cos(0.2), 0.0, 0.0, math.sin(0.2)],
    )
    w.add_body(Sphere(0.5), [8.0, 3.0, 3.0])
    w.add_body(Capsule3D(1.0, 0.2), [13.0, 3.0, 3.0])
    return w


def test_a_point_is_in_each_3d_shape_up_to_its_boundary() -> None:
    w = world_3d()
    x = w.positions
    # the box, turned 0.4 rad about z: its face 1 m along its own x axis
    u = np.array([math.cos(0.4), math.sin(0.4), 0.0])
    assert w.overlap_point(x[0] + (1.0 - EPS) * u).tolist() == [0]
    assert w.overlap_point(x[0] + (1.0 + EPS) * u).tolist() == []
    u = np.array([2.0, -1.0, 2.0]) / 3.0
    assert w.overlap_point(x[1] + (0.5 - EPS) * u).tolist() == [1]
    assert w.overlap_point(x[1] + (0.5 + EPS) * u).tolist() == []
    # the capsule's core lies along z: beside its middle by its radius
    assert w.overlap_point(x[2] + [0.0, 0.2 - EPS, 0.3]).tolist() == [2]
    assert w.overlap_point(x[2] + [0.0, 0.2 + EPS, 0.3]).tolist() == []
    # under the plane is in its solid
    assert w.overlap_point([5.0, 5.0, -EPS]).tolist() == [-1]
    assert w.overlap_point([5.0, 5.0, EPS]).tolist() == []


def test_a_box_meets_3d_shapes_exactly() -> None:
    w = world_3d()
    c = w.positions[1]
    k = (0.5 - EPS) / math.sqrt(3.0)
    assert w.overlap_box(c - 2.0, c - k).tolist() == [1]
    k = (0.5 + EPS) / math.sqrt(3.0)
    assert w.overlap_box(c - 2.0, c - k).tolist() == []
    # the capsule's end cap: a box beyond its core's end along z by the radius
    end = w.positions[2] + [0.0, 0.0, 0.5]
    assert w.overlap_box(
        end + np.array([-1.0, -1.0, 0.2 - EPS]), end + np.array([1.0, 1.0, 2.0])
    ).tolist() == [2]
    assert (
        w.overlap_box(
            end + np.array([-1.0, -1.0, 0.2 + EPS]), end + np.array([1.0, 1.0, 2.0])
        ).tolist()
        == []
    )
    # and beside its side, the least distance along its core (golden-section search)
    side = w.positions[2] + [0.2, 0.0, 0.1]
    assert w.overlap_box(
        side - np.array([EPS, 1.0, 0.0]), side + np.array([1.0, 1.0, 0.05])
    ).tolist() == [2]
    assert (
        w.overlap_box(side + np.array([EPS, -1.0, 0.0]), side + np.array([1.0, 1.0, 0.05])).tolist()
        == []
    )
    # the turned box: a box beyond the corner of its bounding box that its turn left empty
    # (the separating axis is its face normal, not a world axis)
    corner = w.positions[0] + np.array([math.cos(0.4), math.sin(0.4), 0.0]) * 1.0
    probe = corner + np.array([math.cos(0.4), math.sin(0.4), 0.0]) * 0.01
    assert w.overlap_box(probe, probe + 0.5).tolist() == []
    assert w.overlap_box([0.0, 0.0, -1.0], [20.0, 20.0, 20.0]).tolist() == [-1, 0, 1, 2]


def test_overlaps_see_moved_bodies_and_respect_masks() -> None:
    w = world_2d()
    w.set_filter(1, category=0b10)
    c = w.positions[1]
    assert w.overlap_point(c, mask=0b01).tolist() == []
    assert w.overlap_point(c, mask=0b10).tolist() == [1]
    w.set_positions([1], [[15.0, 15.0]])
    assert w.overlap_point(c).tolist() == []
    assert w.overlap_point([15.0, 15.0]).tolist() == [1]
    w.remove_body(0)
    assert w.overlap_point(w.positions[0]).tolist() == []


@pytest.mark.parametrize(
    ("call", "message"),
    [
        (lambda w: w.overlap_point([1.0, math.nan]), "point must be finite"),
        (lambda w: w.overlap_point([1.0, 2.0, 3.0]), "point must be 2 numbers"),
        (lambda w: w.overlap_box([2.0, 2.0], [1.0, 3.0]), "must lie below high"),
        (lambda w: w.overlap_box([2.0], [1.0, 3.0]), "low must be 2 numbers"),
    ],
)
def test_bad_overlap_queries_are_refused(call: object, message: str) -> None:
    w = world_2d()
    with pytest.raises(CaromError, match=message):
        call(w)  # type: ignore[operator]
