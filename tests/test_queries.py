"""Ray casts (issue 43, item 4): ``World.ray_cast`` and ``World.ray_casts``, exact for every
shape kind, turned and moved.

Each expected distance is the shape's closed form, worked out here in the body's own frame
(the ray turned back by the body's rotation): a circle's and sphere's quadratic, a box's slabs,
a polygon's or hull's face plane along its normal, a capsule's axis distance less its radius,
a segment's and a triangle's line or plane. Carom places the body and solves the same closed
form in the world's frame, so the two agree to round-off of the coordinates: 1e-12 relative.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.errors import CaromError
from tests.worlds import rotation

REL = 1e-12


def _world2(*bodies: tuple) -> carom.World:  # type: ignore[type-arg]
    world = carom.World(2, [20.0, 20.0], boundary="open")
    for shape, at, angle, kind in bodies:
        world.add_body(shape, at, angle=angle, kind=kind)
    return world


def _turn2(angle: float) -> np.ndarray:
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


def _slabs(o: np.ndarray, d: np.ndarray, half: np.ndarray) -> float:
    """Where the ray (local frame) enters the box |x_k| <= half_k: the slab test."""
    lo, hi = 0.0, math.inf
    for k in range(o.shape[0]):
        t1, t2 = (-half[k] - o[k]) / d[k], (half[k] - o[k]) / d[k]
        lo, hi = max(lo, min(t1, t2)), min(hi, max(t1, t2))
    assert lo <= hi
    return lo


def test_a_circle_anywhere_is_met_at_its_quadratic() -> None:
    from carom.shapes import Circle

    centre, r = np.array([7.3, 4.1]), 1.7
    world = _world2((Circle(r), centre, 0.9, "dynamic"))
    o, d = np.array([0.2, 0.5]), np.array([0.8, 0.35])
    d = d / np.linalg.norm(d)
    f = o - centre
    b, c = f @ d, f @ f - r * r
    t = -b - math.sqrt(b * b - c)  # |o + t d - centre| = r, entering root
    hit = world.ray_cast(o, d * 3.0)  # (a direction's length does not matter)
    assert hit is not None
    assert hit.body == 0
    assert hit.distance == pytest.approx(t, rel=REL)
    np.testing.assert_allclose(hit.normal, (o + t * d - centre) / r, atol=1e-12)
    np.testing.assert_allclose(hit.point, o + t * d, rtol=REL)


@pytest.mark.parametrize("angle", [0.0, 0.37, -2.1])
def test_a_turned_box_is_met_where_the_slabs_say(angle: float) -> None:
    from carom.shapes import Box

    centre, half = np.array([9.0, 6.0]), np.array([1.5, 0.4])
    world = _world2((Box(*(2 * half)), centre, angle, "static"))
    o, d = np.array([2.0, 1.0]), np.array([0.75, 0.5])
    d = d / np.linalg.norm(d)
    rot = _turn2(angle)
    t = _slabs(rot.T @ (o - centre), rot.T @ d, half)
    hit = world.ray_cast(o, d)
    assert hit is not None
    assert hit.distance == pytest.approx(t, rel=REL)
    assert abs(np.linalg.norm(hit.normal) - 1.0) < 1e-15


@pytest.mark.parametrize("radius", [0.0, 0.3])
def test_a_turned_hexagon_along_a_face_normal_and_a_corner(radius: float) -> None:
    from carom.shapes import Polygon

    big, angle, centre = 2.0, 0.61, np.array([10.0, 10.0])
    corners = [[big * math.cos(k * math.pi / 3), big * math.sin(k * math.pi / 3)] for k in range(6)]
    world = _world2((Polygon(corners, radius=radius), centre, angle, "dynamic"))
    apothem = big * math.cos(math.pi / 6)
    # along the normal of the face between corners 0 and 1 (at 30 degrees, turned): the face
    # pushed out by the radius is met at |o - c| - apothem - r
    face = angle + math.pi / 6
    n = np.array([math.cos(face), math.sin(face)])
    o = centre + 6.5 * n
    hit = world.ray_cast(o, -n)
    assert hit is not None
    assert hit.distance == pytest.approx(6.5 - apothem - radius, rel=REL)
    np.testing.assert_allclose(hit.normal, n, atol=1e-12)
    # toward a corner: the corner, or its arc, at |o - c| - R - r
    corner = np.array([math.cos(angle), math.sin(angle)])
    hit = world.ray_cast(centre + 5.0 * corner, -corner)
    assert hit is not None
    assert hit.distance == pytest.approx(5.0 - big - radius, rel=REL)


def test_a_capsule_side_and_cap() -> None:
    from carom.shapes import Capsule

    length, r, angle, centre = 3.0, 0.4, 0.8, np.array([6.0, 12.0])
    world = _world2((Capsule(length, r), centre, angle, "dynamic"))
    axis = np.array([math.cos(angle), math.sin(angle)])
    side = np.array([-axis[1], axis[0]])
    # square onto the side at a third of the way along: 4.5 - r from 4.5 off the axis
    o = centre + 0.5 * axis + 4.5 * side
    hit = world.ray_cast(o, -side)
    assert hit is not None
    assert hit.distance == pytest.approx(4.5 - r, rel=REL)
    np.testing.assert_allclose(hit.normal, side, atol=1e-12)
    # along the axis onto the end cap: from 5 beyond the centre, 5 - L/2 - r
    hit = world.ray_cast(centre + 5.0 * axis, -axis)
    assert hit is not None
    assert hit.distance == pytest.approx(5.0 - length / 2 - r, rel=REL)


def test_a_compound_is_met_at_its_nearer_part() -> None:
    from carom.shapes import Circle, Compound

    parts = [(Circle(0.5), [-1.0, 0.0]), (Circle(0.8), [1.5, 0.0])]
    world = _world2((Compound(parts), [10.0, 5.0], 0.0, "dynamic"))  # (the parts' origin)
    # straight down onto each circle's top: the big one's centre at (11.5, 5), the small's
    # at (9, 5)
    hit = world.ray_cast([11.5, 15.0], [0.0, -1.0])
    assert hit is not None
    assert hit.distance == pytest.approx(15.0 - 5.0 - 0.8, rel=REL)
    hit = world.ray_cast([9.0, 15.0], [0.0, -1.0])
    assert hit is not None
    assert hit.distance == pytest.approx(15.0 - 5.0 - 0.5, rel=REL)
    # along the line of centres from x = 0: the small circle's left side first, at x = 8.5
    hit = world.ray_cast([0.0, 5.0], [1.0, 0.0])
    assert hit is not None
    assert hit.distance == pytest.approx(8.5, rel=REL)


def test_segments_and_chains_are_met_from_either_side() -> None:
    from carom.shapes import Chain, Segment

    world = _world2(
        (Segment([2.0, 3.0], [8.0, 5.0]), [0.0, 0.0], 0.0, "static"),
        (Chain([[1.0, 14.0], [5.0, 16.0], [9.0, 15.0]]), [0.0, 0.0], 0.0, "static"),
    )
    # the line y = 3 + (x - 2) / 3 crossed by x = 5: at y = 4
    up = world.ray_cast([5.0, 0.0], [0.0, 1.0])
    down = world.ray_cast([5.0, 9.0], [0.0, -1.0])
    assert up is not None
    assert up.distance == pytest.approx(4.0, rel=REL)
    assert up.body == 0
    assert down is not None
    assert down.distance == pytest.approx(5.0, rel=REL)
    assert up.normal[1] < 0.0 < down.normal[1]  # each side faces its ray
    # the chain's second link, (5, 16) to (9, 15), crossed by x = 7: at y = 15.5
    hit = world.ray_cast([7.0, 10.0], [0.0, 1.0])
    assert hit is not None
    assert hit.body == 1
    assert hit.distance == pytest.approx(5.5, rel=REL)


def _world3(*bodies: tuple) -> carom.World:  # type: ignore[type-arg]
    world = carom.World(3, [20.0] * 3, boundary="open")
    for shape, at, turn, kind in bodies:
        world.add_body(shape, at, orientation=turn, kind=kind)
    return world


def _quat(axis: list[float], angle: float) -> np.ndarray:
    u = np.asarray(axis, float) / np.linalg.norm(axis)
    return np.r_[math.cos(angle / 2), math.sin(angle / 2) * u]


def test_a_sphere_and_a_turned_box_in_3d() -> None:
    from carom.shapes3d import Box, Sphere

    turn = _quat([1.0, 2.0, -0.5], 0.9)
    half = np.array([1.0, 0.6, 0.3])
    world = _world3(
        (Sphere(1.2), [4.0, 15.0, 4.0], [1.0, 0, 0, 0], "dynamic"),
        (Box(2 * half), [14.0, 12.0, 9.0], turn, "dynamic"),
    )
    o = np.array([0.5, 0.2, 1.0])
    for target, expected in (
        (np.array([4.0, 15.0, 4.0]), None),
        (np.array([14.0, 12.0, 9.0]), half),
    ):
        d = (target + 0.05) - o
        d /= np.linalg.norm(d)
        if expected is None:  # the sphere's quadratic
            f = o - target
            b, c = f @ d, f @ f - 1.2**2
            t = -b - math.sqrt(b * b - c)
        else:  # the box's slabs, in its own frame
            rot = rotation(world.orientations[1])
            t = _slabs(rot.T @ (o - target), rot.T @ d, expected)
        hit = world.ray_cast(o, d)
        assert hit is not None
        assert hit.distance == pytest.approx(t, rel=REL)


def test_a_3d_capsule_side_and_cap() -> None:
    from carom.shapes3d import Capsule

    turn = _quat([0.3, -1.0, 0.2], 1.1)
    world = _world3((Capsule(2.0, 0.35), [8.0, 8.0, 8.0], turn, "dynamic"))
    axis = rotation(world.orientations[0]) @ np.array([0.0, 0.0, 1.0])  # (along z when unturned)
    side = np.cross(axis, [1.0, 0.0, 0.0])
    side /= np.linalg.norm(side)
    centre = world.positions[0]
    hit = world.ray_cast(centre - 0.4 * axis + 3.0 * side, -side)
    assert hit is not None
    assert hit.distance == pytest.approx(3.0 - 0.35, rel=REL)
    hit = world.ray_cast(centre - 4.0 * axis, axis)
    assert hit is not None
    assert hit.distance == pytest.approx(4.0 - 1.0 - 0.35, rel=REL)


def test_a_turned_hull_along_a_face_normal() -> None:
    from carom.shapes3d import Hull

    a = 1.5  # the octahedron |x| + |y| + |z| <= a: its faces lie a / sqrt(3) from the centre
    points = a * np.array([[1, 0, 0], [-1, 0, 0], [0, 1, 0], [0, -1, 0], [0, 0, 1], [0, 0, -1]])
    turn = _quat([1.0, 1.0, 0.0], 0.7)
    world = _world3((Hull(points), [10.0, 9.0, 8.0], turn, "dynamic"))
    n = rotation(world.orientations[0]) @ (np.array([1.0, 1.0, 1.0]) / math.sqrt(3))
    centre = world.positions[0]
    hit = world.ray_cast(centre + 6.0 * n, -n)
    assert hit is not None
    assert hit.distance == pytest.approx(6.0 - a / math.sqrt(3), rel=REL)
    np.testing.assert_allclose(hit.normal, n, atol=1e-12)


def test_a_mesh_and_a_plane() -> None:
    from carom.meshes import Mesh

    # a tilted square of two triangles, and the ground z = 0.5 tilted about x
    corners = np.array([[2.0, 2.0, 3.0], [8.0, 2.0, 4.0], [8.0, 8.0, 5.0], [2.0, 8.0, 4.0]])
    mesh = Mesh(corners, [[0, 1, 2], [0, 2, 3]])
    normal = np.array([0.0, math.sin(0.2), math.cos(0.2)])
    world = _world3((mesh, [0.0, 0.0, 0.0], [1.0, 0, 0, 0], "static"))
    world.add_plane(0.5 * normal, normal)
    # straight down at (6, 3): the first triangle's plane z = 3 + (x - 2) / 6 + (y - 2) / 6
    hit = world.ray_cast([6.0, 3.0, 10.0], [0.0, 0.0, -1.0])
    z = 3.0 + 4.0 / 6.0 + 1.0 / 6.0
    assert hit is not None
    assert hit.body == 0
    assert hit.distance == pytest.approx(10.0 - z, rel=REL)
    # beside the mesh, down onto the plane n . x = 0.5: t = (o . n - 0.5) / n_z
    o = np.array([15.0, 15.0, 10.0])
    hit = world.ray_cast(o, [0.0, 0.0, -1.0])
    assert hit is not None
    assert hit.body == -1  # (a plane is the world's scenery, not a body)
    assert hit.distance == pytest.approx((o @ normal - 0.5) / normal[2], rel=REL)


def test_a_ray_meets_a_body_where_it_is_now_and_not_from_inside() -> None:
    from carom.shapes import Circle

    world = carom.World(2, [20.0, 20.0], gravity=[0.0, -9.81], boundary="open")
    world.add_body(Circle(1.0), [10.0, 15.0])
    for _ in range(30):
        world.step()
    y = world.positions[0, 1]  # fallen 9.81 / 2 x (1/2)^2 m, exactly
    assert y == pytest.approx(15.0 - 9.81 / 8, abs=1e-12)
    hit = world.ray_cast([10.0, 0.0], [0.0, 1.0])
    assert hit is not None
    assert hit.distance == pytest.approx(y - 1.0, rel=REL)
    assert world.ray_cast([10.0, y], [0.0, 1.0]) is None  # from inside: it looks outward
    assert world.ray_cast([10.0, 0.0], [0.0, 1.0], max_distance=y - 1.01) is None


def test_many_rays_are_the_bits_of_one_at_a_time() -> None:
    from carom.shapes import Box, Circle

    world = carom.World(2, [20.0, 20.0], boundary="open")
    rng = np.random.default_rng(7)
    for k in range(40):  # a grid 2 m apart, each body within 0.5 m of its node
        shape = Circle(0.3) if k % 2 else Box(0.5, 0.8)
        node = np.array([2.0 + 2.0 * (k % 8), 2.0 + 2.0 * (k // 8)])
        world.add_body(shape, node, angle=float(rng.uniform(0, 3)))
    origins = rng.uniform(0.0, 20.0, (64, 2))
    directions = rng.normal(size=(64, 2))
    many = world.ray_casts(origins, directions)  # through a tree over the bodies
    assert np.count_nonzero(many["body"] >= 0) > 10
    for k in range(64):
        one = world.ray_cast(origins[k], directions[k])  # one by one
        if one is None:
            assert many["body"][k] == -2
            assert math.isinf(many["distance"][k])
        else:
            assert (one.body, one.distance) == (many["body"][k], many["distance"][k])
            np.testing.assert_array_equal(one.normal, many["normal"][k])


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda w: w.ray_cast([0.0, 0.0], [0.0, 0.0]), "ray 0 has a zero direction"),
        (lambda w: w.ray_cast([math.nan, 0.0], [1.0, 0.0]), "origins must be finite"),
        (lambda w: w.ray_cast([0.0, 0.0, 0.0], [1.0, 0.0]), "origins must have shape"),
        (lambda w: w.ray_cast([0.0, 0.0], [1.0, 0.0], max_distance=0.0), "max_distance"),
        (lambda w: w.ray_casts([[0.0, 0.0]] * 3, [[1.0, 0.0]] * 2), "directions must have"),
    ],
)
def test_a_wrong_ray_is_refused(call: object, match: str) -> None:
    from carom.shapes import Circle

    world = _world2((Circle(1.0), [5.0, 5.0], 0.0, "dynamic"))
    with pytest.raises(CaromError, match=match):
        call(world)  # type: ignore[operator]


def test_the_event_driven_engine_says_it_does_not_cast_rays_yet() -> None:
    world = carom.World(3, [10.0] * 3)
    world.add_spheres(np.array([[5.0, 5.0, 5.0]]), np.zeros((1, 3)), radius=0.5)
    with pytest.raises(CaromError, match="ray casts are the rigid engines'"):
        world.ray_cast([0.0, 5.0, 5.0], [1.0, 0.0, 0.0])


# -- shape casts (issue 43, item 4) ----------------------------------------------------------


def _cast_world() -> carom.World:
    """A 2x2 m static box at (10, 10) (body 0) and a disc of radius 1 at (15, 10) (body 1)."""
    from carom.shapes import Box, Circle

    world = carom.World(2, [20.0, 20.0], boundary="open")
    world.add_body(Box(2.0, 2.0), [10.0, 10.0], kind="static")
    world.add_body(Circle(1.0), [15.0, 10.0])
    return world


def test_a_disc_cast_head_on_at_a_box_touches_its_face() -> None:
    from carom.shapes import Circle

    world = _cast_world()
    hit = world.shape_cast(Circle(0.5), [0.0, 10.0], [20.0, 0.0])
    assert hit is not None
    # the disc's centre stops 0.5 m before the face x = 9: fraction 8.5 / 20, in one step of
    # conservative advancement (the gap is measured along the move): round-off
    assert hit.body == 0
    assert abs(hit.fraction - 8.5 / 20.0) < REL
    np.testing.assert_allclose(hit.point, [9.0, 10.0], atol=1e-12)
    np.testing.assert_allclose(hit.normal, [-1.0, 0.0], atol=1e-12)


def test_a_disc_cast_obliquely_at_a_disc_meets_the_closed_form() -> None:
    from carom.shapes import Box, Circle

    world = _cast_world()
    start, move = np.array([11.0, 13.0]), np.array([8.0, -4.0])
    hit = world.shape_cast(Circle(0.5), start, move, mask=0b1)
    # |start + t move - c| = 1.5: the smaller root of a t^2 + b t + c0 = 0
    rel = start - np.array([15.0, 10.0])
    a, b, c0 = move @ move, 2.0 * rel @ move, rel @ rel - 1.5**2
    t = (-b - math.sqrt(b * b - 4.0 * a * c0)) / (2.0 * a)
    assert hit is not None
    assert hit.body == 1
    # conservative advancement stops within 1e-9 of the pieces' reach (2.5 m) of touching:
    # the fraction within that over the closing speed along the normal (cos ~ 0.9 here)
    assert abs(hit.fraction - t) * math.hypot(*move) < 5e-9
    centre = start + t * move
    normal = (centre - [15.0, 10.0]) / 1.5
    np.testing.assert_allclose(hit.normal, normal, atol=1e-8)
    np.testing.assert_allclose(hit.point, [15.0, 10.0] + 1.0 * normal, atol=1e-8)
    # a path above both bodies (their tops at y = 11) meets nothing
    assert world.shape_cast(Box(0.2, 0.2), [0.0, 15.0], [20.0, 0.0]) is None


def test_a_turned_box_cast_up_at_a_box_touches_at_its_reach() -> None:
    from carom.shapes import Box

    world = _cast_world()
    theta = 0.3
    hit = world.shape_cast(Box(1.0, 1.0), [10.0, 0.0], [0.0, 20.0], angle=theta)
    # a unit box turned by theta reaches 0.5 (cos + sin) above its centre; the face is y = 9
    reach = 0.5 * (math.cos(theta) + math.sin(theta))
    assert hit is not None
    assert hit.body == 0
    assert abs(hit.fraction - (9.0 - reach) / 20.0) < 1e-11
    np.testing.assert_allclose(hit.normal, [0.0, -1.0], atol=1e-12)


def test_a_cast_starting_inside_hits_at_once_and_masks_and_sensors_hide() -> None:
    from carom.shapes import Circle

    world = _cast_world()
    hit = world.shape_cast(Circle(0.5), [10.0, 10.5], [5.0, 0.0])
    assert hit is not None
    assert hit.body == 0
    assert hit.fraction == 0.0
    world.set_filter(0, category=0b10)
    hit = world.shape_cast(Circle(0.5), [0.0, 10.0], [20.0, 0.0], mask=0b1)
    assert hit is not None
    assert hit.body == 1  # past the box, now category 2, to the disc
    world.set_sensor(1)
    assert world.shape_cast(Circle(0.5), [0.0, 10.0], [20.0, 0.0], mask=0b1) is None


def test_bad_shape_casts_are_refused() -> None:
    from carom.shapes import Circle, Segment
    from carom.shapes3d import Sphere

    world = _cast_world()
    with pytest.raises(CaromError, match="translation is zero"):
        world.shape_cast(Circle(0.5), [0.0, 0.0], [0.0, 0.0])
    with pytest.raises(CaromError, match="2D body's shape"):
        world.shape_cast(Segment([0.0, 0.0], [1.0, 0.0]), [0.0, 0.0], [1.0, 0.0])
    with pytest.raises(CaromError, match="translation must be finite"):
        world.shape_cast(Circle(0.5), [0.0, 0.0], [np.nan, 0.0])
    with pytest.raises(CaromError, match="orientation is a 3D turn"):
        world.shape_cast(Circle(0.5), [0.0, 0.0], [1.0, 0.0], orientation=[1, 0, 0, 0])
    space = carom.World(3, [10.0] * 3, boundary="open")
    space.add_body(Sphere(1.0), [5.0, 5.0, 5.0])
    with pytest.raises(CaromError, match="3D body's shape"):
        space.shape_cast(Circle(0.5), [0.0, 5.0, 5.0], [10.0, 0.0, 0.0])
    with pytest.raises(CaromError, match="not zero"):
        space.shape_cast(Sphere(0.5), [0.0, 5.0, 5.0], [10.0, 0.0, 0.0], orientation=[0] * 4)
    with pytest.raises(CaromError, match="position must be 3 numbers"):
        space.shape_cast(Sphere(0.5), [0.0, 5.0], [10.0, 0.0, 0.0])


def test_shapes_cast_in_3d_meet_the_closed_forms() -> None:
    from carom.shapes3d import Box as Box3D
    from carom.shapes3d import Sphere

    # the 2D scene in the z = 10 plane: a 2 m static cube at (10, 10, 10), a unit ball at
    # (15, 10, 10)
    world = carom.World(3, [20.0] * 3, boundary="open")
    world.add_body(Box3D([2.0, 2.0, 2.0]), [10.0, 10.0, 10.0], kind="static")
    world.add_body(Sphere(1.0), [15.0, 10.0, 10.0])
    hit = world.shape_cast(Sphere(0.5), [0.0, 10.0, 10.0], [20.0, 0.0, 0.0])
    assert hit is not None
    assert hit.body == 0
    assert abs(hit.fraction - 8.5 / 20.0) < REL  # head-on at the face x = 9
    np.testing.assert_allclose(hit.point, [9.0, 10.0, 10.0], atol=1e-12)
    np.testing.assert_allclose(hit.normal, [-1.0, 0.0, 0.0], atol=1e-12)
    start, move = np.array([11.0, 13.0, 10.0]), np.array([8.0, -4.0, 0.0])
    hit = world.shape_cast(Sphere(0.5), start, move)
    rel = start - [15.0, 10.0, 10.0]
    a, b, c0 = move @ move, 2.0 * rel @ move, rel @ rel - 1.5**2
    t = (-b - math.sqrt(b * b - 4.0 * a * c0)) / (2.0 * a)
    assert hit is not None
    assert hit.body == 1
    assert abs(hit.fraction - t) * math.hypot(*move) < 5e-9  # as the 2D oblique cast
    normal = (start + t * move - [15.0, 10.0, 10.0]) / 1.5
    np.testing.assert_allclose(hit.normal, normal, atol=1e-8)
    # a cube turned by 0.3 rad about z, cast up (+y) at the cube's face y = 9: it reaches
    # 0.5 (cos + sin) above its centre
    turn = [math.cos(0.15), 0.0, 0.0, math.sin(0.15)]
    hit = world.shape_cast(Box3D([1.0, 1.0, 1.0]), [10.0, 0.0, 10.0], [0.0, 20.0, 0.0],
                           orientation=turn)  # fmt: skip
    assert hit is not None
    assert hit.body == 0
    reach = 0.5 * (math.cos(0.3) + math.sin(0.3))
    assert abs(hit.fraction - (9.0 - reach) / 20.0) < 1e-10
    np.testing.assert_allclose(hit.normal, [0.0, -1.0, 0.0], atol=1e-9)
    assert world.shape_cast(Sphere(0.5), [0.0, 2.0, 2.0], [20.0, 0.0, 0.0]) is None
