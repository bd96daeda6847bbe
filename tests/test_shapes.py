"""2D shapes: outlines refused or accepted, and exact mass properties against closed forms.

Every expected value below is a textbook closed form, derived in the comment beside it. The
library computes the same quantities by a different decomposition (core polygon by the
shoelace formula, a rectangle per edge, a sector per corner), so agreement is a real check;
the tolerance is float64 round-off of a few dozen operations on O(1) numbers.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from carom.errors import CaromError
from carom.shapes import Box, Capsule, Chain, Circle, Compound, Polygon, Segment

REL = 1e-13  # a few dozen float64 operations on O(1) numbers


def close(a: float, b: float, rel: float = REL) -> bool:
    return math.isclose(a, b, rel_tol=rel, abs_tol=1e-15)


@pytest.mark.parametrize(("w", "h", "m"), [(1.0, 1.0, 1.0), (0.3, 0.4, 2.0), (5.0, 0.01, 7.5)])
def test_rectangle_inertia_is_m_w2_plus_h2_over_12(w: float, h: float, m: float) -> None:
    props = Box(w, h).mass_properties(mass=m)
    assert close(props.mass, m)
    assert close(props.inertia, m * (w * w + h * h) / 12.0)
    assert np.allclose(props.centroid, 0.0, atol=1e-15)


def test_density_gives_mass_rho_times_area() -> None:
    # 2 x 3 box at 5 kg/m^2: m = 30 kg, I = 30 (4 + 9)/12
    props = Box(2.0, 3.0).mass_properties(5.0)
    assert close(props.mass, 30.0)
    assert close(props.inertia, 30.0 * 13.0 / 12.0)


@pytest.mark.parametrize("r", [0.01, 0.5, 3.0])
def test_disk_inertia_is_half_m_r2(r: float) -> None:
    props = Circle(r).mass_properties(density=2.0)
    assert close(props.mass, 2.0 * math.pi * r * r)
    assert close(props.inertia, props.mass * r * r / 2.0)


@pytest.mark.parametrize("n", [3, 4, 5, 6, 8, 17, 100])
def test_regular_polygon_inertia(n: int) -> None:
    # A regular n-gon of circumradius R is n isosceles triangles; summing their polar moments
    # gives I = (m R^2 / 6) (1 + 2 cos^2(pi/n)), area A = (n/2) R^2 sin(2 pi/n).
    R = 1.3
    props = Polygon.regular(n, R).mass_properties(mass=2.0)
    assert close(props.inertia, 2.0 * R * R / 6.0 * (1.0 + 2.0 * math.cos(math.pi / n) ** 2))
    assert close(Polygon.regular(n, R).area, n / 2.0 * R * R * math.sin(2.0 * math.pi / n))
    assert np.allclose(props.centroid, 0.0, atol=1e-14)


@pytest.mark.parametrize(("length", "r"), [(1.0, 0.2), (0.1, 1.0), (2.0, 0.5)])
def test_capsule_mass_properties(length: float, r: float) -> None:
    # A capsule is an L x 2r rectangle plus two half disks whose centres of mass sit
    # 4r/(3 pi) beyond the segment's ends. Per unit density:
    #   rectangle: A_r = 2 r L, I_r = A_r (L^2 + 4 r^2)/12
    #   half disk about its flat edge's midpoint: pi r^4/4; about its centre of mass: minus
    #   A_h d^2, d = 4r/(3 pi); moved to the body centre: plus A_h (L/2 + d)^2.
    rho = 3.0
    a_rect = 2.0 * r * length
    a_half = math.pi * r * r / 2.0
    d = 4.0 * r / (3.0 * math.pi)
    inertia = a_rect * (length**2 + 4.0 * r * r) / 12.0 + 2.0 * (
        math.pi * r**4 / 4.0 - a_half * d * d + a_half * (length / 2.0 + d) ** 2
    )
    props = Capsule(length, r).mass_properties(rho)
    assert close(props.mass, rho * (a_rect + 2.0 * a_half))
    assert close(props.inertia, rho * inertia)


def test_rounded_box_against_a_different_decomposition() -> None:
    # Rounded box (core w x h, radius r): one (w + 2r) x h rectangle, two w x r strips above
    # and below, four quarter disks with their apexes at the core's corners (+-w/2, +-h/2).
    w, h, r = 1.2, 0.7, 0.15
    a_mid = (w + 2 * r) * h
    i_mid = a_mid * ((w + 2 * r) ** 2 + h**2) / 12.0
    a_strip = w * r
    # strip centred at (0, +-(h/2 + r/2)): own w x r rectangle, then parallel axis
    i_strip = a_strip * (w**2 + r**2) / 12.0 + a_strip * (h / 2 + r / 2) ** 2
    # quarter disk at apex v = (w/2, h/2) pointing outwards: about the apex pi r^4/8; its
    # first moment about the apex is r^3/3 (1, 1); J = J0 + 2 v.S0 + A |v|^2
    a_quarter = math.pi * r * r / 4.0
    v = np.array([w / 2, h / 2])
    first = np.array([r**3 / 3, r**3 / 3])
    i_quarter = math.pi * r**4 / 8.0 + 2.0 * float(v @ first) + a_quarter * float(v @ v)
    area = a_mid + 2 * a_strip + 4 * a_quarter
    inertia = i_mid + 2 * i_strip + 4 * i_quarter
    box = Box(w, h, radius=r)
    props = box.mass_properties(mass=1.0)
    assert close(box.area, area)
    assert close(props.inertia, inertia / area)


def test_compound_uses_the_parallel_axis_theorem() -> None:
    # An L from two sharp boxes: a 2 x 0.5 foot centred at (0, 0) and a 0.5 x 1.5 upright
    # centred at (-0.75, 1.0). Centroid = area-weighted centres; inertia about it = sum of
    # each box's m (w^2 + h^2)/12 + m d^2 (Steiner).
    parts = [((2.0, 0.5), (0.0, 0.0)), ((0.5, 1.5), (-0.75, 1.0))]
    rho = 2.0
    masses = [rho * w * h for (w, h), _ in parts]
    centres = np.array([c for _, c in parts])
    m = sum(masses)
    c = (masses[0] * centres[0] + masses[1] * centres[1]) / m
    inertia = sum(
        mi * (w * w + h * h) / 12.0 + mi * float((ci - c) @ (ci - c))
        for mi, ((w, h), ci) in zip(masses, parts, strict=True)
    )
    shape = Compound([(Box(*size), centre) for size, centre in parts])
    props = shape.mass_properties(rho)
    assert close(props.mass, m)
    assert np.allclose(props.centroid, c, rtol=0, atol=1e-15)
    assert close(props.inertia, inertia)


def test_compound_part_turned_by_its_angle() -> None:
    # A 1 x 0.2 box turned by 90 degrees is a 0.2 x 1 box: same inertia, same area.
    turned = Compound([(Box(1.0, 0.2), (0.0, 0.0), math.pi / 2)])
    xs = turned.pieces()[0].vertices[:, 0]
    assert np.allclose(np.sort(np.abs(xs)), 0.1)
    assert close(turned.mass_properties(mass=1.0).inertia, (1.0 + 0.04) / 12.0)


def test_polygon_centroid_is_reported_in_its_own_frame() -> None:
    # a right triangle (0,0), (3,0), (0,3): centroid (1, 1); I about it = m (a^2 + b^2)/18
    # for legs a = b = 3 (the triangle's polar moment about its centroid).
    tri = Polygon([[0.0, 0.0], [3.0, 0.0], [0.0, 3.0]])
    props = tri.mass_properties(mass=1.0)
    assert np.allclose(props.centroid, [1.0, 1.0], rtol=0, atol=1e-15)
    assert close(props.inertia, (9.0 + 9.0) / 18.0)


@settings(max_examples=200, deadline=None)
@given(
    st.lists(
        st.tuples(st.floats(-10, 10), st.floats(-10, 10)), min_size=3, max_size=30, unique=True
    ),
    st.floats(0.0, 2.0),
)
def test_polygon_integrals_match_triangle_fan(points: list[tuple[float, float]], r: float) -> None:
    # The hull of random points: sharp area = sum of triangles (c0, ci, ci+1); rounding adds
    # perimeter x r + pi r^2 (Steiner's formula for the parallel body of a convex set).
    cloud = np.array(points)
    try:
        poly = Polygon.hull_of(cloud, radius=r)
    except CaromError:
        return  # all points on one line: refused, tested elsewhere
    c = poly.corners
    fan = sum(
        0.5 * ((c[i] - c[0])[0] * (c[i + 1] - c[0])[1] - (c[i] - c[0])[1] * (c[i + 1] - c[0])[0])
        for i in range(1, len(c) - 1)
    )
    perimeter = float(np.sum(np.linalg.norm(np.roll(c, -1, axis=0) - c, axis=1)))
    expected = fan + perimeter * r + math.pi * r * r
    assert math.isclose(poly.area, expected, rel_tol=1e-11, abs_tol=1e-9)


def test_outline_either_way_round_with_repeats_and_edge_points() -> None:
    cw = Polygon([[0, 0], [0, 1], [0, 1], [1, 1], [1, 0.5], [1, 0]])
    assert cw.corners.shape == (4, 2)
    assert close(cw.area, 1.0)


@pytest.mark.parametrize(
    ("vertices", "words"),
    [
        ([[0, 0], [1, 0], [0.2, 0.2], [0, 1]], "concave"),
        ([[0, 0], [1, 1], [1, 0], [0, 1]], "crosses itself"),
        ([[0, 0], [1, 0], [2, 0]], "one line"),
        ([[0, 0], [0, 0], [0, 0]], "one line"),
        ([[0, 0], [1, 0]], "at least 3"),
        ([[0, 0], [1, math.nan], [0, 1]], "not finite"),
        ([[0, 0, 0], [1, 0, 0], [0, 1, 0]], "shape"),
        ("square", "points"),
    ],
)
def test_bad_outline_refused_with_a_message(vertices: object, words: str) -> None:
    with pytest.raises(CaromError, match=words):
        Polygon(vertices)


def test_concave_message_points_to_compound() -> None:
    with pytest.raises(CaromError, match="Compound"):
        Polygon([[0, 0], [2, 0], [2, 2], [1, 0.5], [0, 2]])


@pytest.mark.parametrize(
    ("make", "words"),
    [
        (lambda: Circle(0.0), "radius"),
        (lambda: Circle(-1.0), "radius"),
        (lambda: Box(1.0, math.inf), "height"),
        (lambda: Capsule(1.0, 0.0), "radius"),
        (lambda: Box(1.0, 1.0).mass_properties(), "density"),
        (lambda: Box(1.0, 1.0).mass_properties(1.0, mass=2.0), "one of them"),
        (lambda: Box(1.0, 1.0).mass_properties(mass=0.0), "mass"),
        (lambda: Box(1.0, 1.0).mass_properties(math.nan), "density"),
        (lambda: Segment((0, 0), (1, 0)).mass_properties(1.0), "static"),
        (lambda: Segment((0, 0), (0, 0)), "same point"),
        (lambda: Chain([[0, 0], [1, 0], [1, 0]]), "same point"),
        (lambda: Chain([[0, 0]]), "at least 2"),
        (lambda: Compound([]), "non-empty"),
        (lambda: Compound([(Box(1, 1), (0, 0, 0))]), "offset"),
        (lambda: Compound([Segment((0, 0), (1, 0))]), "static"),
        (lambda: Compound(["box"]), "part 0"),
    ],
)
def test_bad_shape_refused(make: object, words: str) -> None:
    with pytest.raises(CaromError, match=words):
        make()  # type: ignore[operator]


def test_chain_pieces_are_its_segments() -> None:
    open_chain = Chain([[0, 0], [1, 0], [2, 1]])
    closed = Chain([[0, 0], [1, 0], [1, 1]], loop=True)
    assert len(open_chain.pieces()) == 2
    assert len(closed.pieces()) == 3
    assert np.array_equal(closed.pieces()[2].vertices, [[1, 1], [0, 0]])
