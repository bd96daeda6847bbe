"""Exact mass properties in 3D (carom.geometry.mass3d, carom.shapes3d) against closed forms:
box, tetrahedron, regular prisms (the cylinder limit), the sphere limit of inscribed hulls, the
capsule against an independent quadrature, and parallel-axis compounds.

Tolerances: the sums are exact up to float64 round-off of a few dozen terms of the solid's
size, so closed forms are held to a relative 1e-12 (about 5000 ulps, far above the round-off
of these sums, far below any formula error).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from carom.errors import CaromError
from carom.geometry.mass3d import (
    box_integrals,
    capsule_integrals,
    check_closed,
    polyhedron_integrals,
    sphere_integrals,
)
from carom.shapes3d import Box, Capsule, Compound, Hull, Sphere, rotation_matrix

pytest.importorskip("scipy")

REL = 1e-12


def _close(a: np.ndarray | float, b: np.ndarray | float, scale: float) -> None:
    assert np.max(np.abs(np.asarray(a) - np.asarray(b))) <= REL * scale


def test_a_box_from_its_corners_matches_the_closed_form() -> None:
    # I = m diag(b^2 + c^2, a^2 + c^2, a^2 + b^2)/12 for a box of edges a, b, c
    # (moved off the origin: the integrals about the origin then cancel to about
    # eps (|t| / size)^2 of the result when taken about the centroid, 1e-14 here)
    a, b, c, m = 0.3, 0.4, 0.5, 2.0
    expected = m / 12.0 * np.diag([b * b + c * c, a * a + c * c, a * a + b * b])
    for shape in (Box([a, b, c]), Hull(Box([a, b, c]).corners() + np.array([1.0, -2.0, 3.0]))):
        props = shape.mass_properties(mass=m)
        _close(props.inertia, expected, m * (a * a + b * b + c * c))
    _close(Box([a, b, c]).volume, a * b * c, a * b * c)


def test_a_right_tetrahedron() -> None:
    # corners 0, a e_x, b e_y, c e_z: V = abc/6, centroid (a, b, c)/4, and about the origin
    # int x^2 dV = a^3 bc/60, int xy dV = a^2 b^2 c/120 (the unit one's 1/60 and 1/120, scaled)
    a, b, c = 0.7, 1.3, 0.4
    points = np.array([[0, 0, 0], [a, 0, 0], [0, b, 0], [0, 0, c]], float)
    hull = Hull(points)
    integrals = polyhedron_integrals(hull.vertices, hull.triangles)
    v = a * b * c / 6.0
    _close(integrals.volume, v, v)
    _close(integrals.centroid, [a / 4, b / 4, c / 4], a + b + c)
    s = np.array([a, b, c])
    second = a * b * c / 120.0 * (np.outer(s, s) + np.diag(s * s))
    _close(integrals.second, second, v * float(s @ s))


@pytest.mark.parametrize("sides", [3, 4, 5, 6, 8, 12, 64])
def test_a_regular_prism_and_the_cylinder_limit(sides: int) -> None:
    # A regular n-gon of circumradius R is n triangles from the centre, each with polar moment
    # (A_t/6)(R^2 + R^2 + R^2 cos a), a = 2 pi/n; so J/A = R^2 (2 + cos a)/6, which tends to
    # the disk's R^2/2. A prism of height H: I_zz = m R^2 (2 + cos a)/6,
    # I_xx = I_yy = m (R^2 (2 + cos a)/12 + H^2/12).
    radius, height, m = 0.5, 1.5, 3.0
    turn = 2.0 * math.pi / sides
    ring = np.array(
        [[radius * math.cos(k * turn), radius * math.sin(k * turn)] for k in range(sides)]
    )
    points = np.vstack(
        [np.column_stack([ring, np.full(sides, z)]) for z in (-height / 2, height / 2)]
    )
    props = Hull(points).mass_properties(mass=m)
    polar = radius * radius * (2.0 + math.cos(turn)) / 6.0
    expected = m * np.diag([polar / 2 + height**2 / 12, polar / 2 + height**2 / 12, polar])
    _close(props.inertia, expected, m * (radius * radius + height * height))
    if sides == 64:  # the cylinder's m R^2/2, less m R^2 (1 - cos a)/6: 0.16% short here
        gap = radius**2 / 2 - props.inertia[2, 2] / m
        assert gap == pytest.approx((1 - math.cos(turn)) * radius**2 / 6, rel=1e-9)
        assert gap < 2e-3 * radius**2 / 2


@pytest.mark.parametrize("count", [50, 400, 3000])
def test_hulls_of_points_on_a_sphere_are_held_between_two_balls(count: int) -> None:
    # The hull of points on a sphere of radius R holds the ball of its inradius r (the nearest
    # face plane) and lies in the ball of radius R; the volume and int |x|^2 dV are monotone in
    # the set, so they lie between the two balls' 4/3 pi r^3 .. 4/3 pi R^3 and
    # 4/5 pi r^5 .. 4/5 pi R^5, and the gap closes as the points fill the sphere.
    radius = 0.8
    k = np.arange(count) + 0.5
    polar = np.arccos(1.0 - 2.0 * k / count)  # a Fibonacci lattice: nearly even spacing
    azimuth = math.pi * (1.0 + 5.0**0.5) * k
    points = radius * np.column_stack(
        [np.sin(polar) * np.cos(azimuth), np.sin(polar) * np.sin(azimuth), np.cos(polar)]
    )
    hull = Hull(points)
    integrals = polyhedron_integrals(hull.vertices, hull.triangles)
    corners = hull.vertices[hull.triangles]
    normals = np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0])
    normals /= np.linalg.norm(normals, axis=1)[:, None]
    inner = float(np.min(np.einsum("ij,ij->i", normals, corners[:, 0])))
    assert 0.0 < inner < radius
    assert 4 / 3 * math.pi * inner**3 <= integrals.volume <= 4 / 3 * math.pi * radius**3
    trace = float(np.trace(integrals.second))
    assert 4 / 5 * math.pi * inner**5 <= trace <= 4 / 5 * math.pi * radius**5


def test_the_capsule_against_a_quadrature_over_its_slices() -> None:
    # An independent route: slice along z. At height z the capsule's section is a disk of
    # radius rho(z) (r on the cylinder, sqrt(r^2 - (|z| - h)^2) on a cap), so
    # V = int pi rho^2 dz, int x^2 dV = int pi rho^4/4 dz, int z^2 dV = int pi rho^2 z^2 dz.
    # On each of the three pieces the integrands are polynomials in z of degree <= 4, which
    # Gauss-Legendre with 5 nodes integrates exactly.
    r, length = 0.3, 1.1
    h = length / 2
    nodes, weights = np.polynomial.legendre.leggauss(5)
    volume = xx = zz = 0.0
    for lo, hi in ((-h - r, -h), (-h, h), (h, h + r)):
        z = 0.5 * (hi - lo) * nodes + 0.5 * (hi + lo)
        w = 0.5 * (hi - lo) * weights
        rho2 = r * r - np.maximum(np.abs(z) - h, 0.0) ** 2
        volume += float(w @ (math.pi * rho2))
        xx += float(w @ (math.pi * rho2 * rho2 / 4))
        zz += float(w @ (math.pi * rho2 * z * z))
    integrals = capsule_integrals(r, length)
    _close(integrals.volume, volume, volume)
    _close(integrals.second, np.diag([xx, xx, zz]), zz)
    _close(Capsule(length, r).volume, volume, volume)
    # no length: a ball
    _close(capsule_integrals(r, 0.0).second, sphere_integrals(r).second, zz)


def test_a_sphere() -> None:
    # I = 2/5 m r^2 about every axis
    props = Sphere(0.25).mass_properties(mass=4.0)
    _close(props.inertia, np.eye(3) * 0.4 * 4.0 * 0.25**2, 1.0)


def test_compounds_add_by_the_parallel_axis_theorem() -> None:
    # Two boxes side by side are one box twice as long.
    a, b, c = 0.2, 0.3, 0.4
    pair = Compound([(Box([a, b, c]), [-a / 2, 0, 0]), (Box([a, b, c]), [a / 2, 0, 0])])
    whole = Box([2 * a, b, c])
    _close(
        pair.mass_properties(density=7.0).inertia, whole.mass_properties(density=7.0).inertia, 1.0
    )
    # A quarter turn about z swaps a box's x and y edges.
    quarter = [math.cos(math.pi / 4), 0.0, 0.0, math.sin(math.pi / 4)]
    turned = Compound([(Box([a, b, c]), [0, 0, 0], quarter)])
    _close(
        turned.mass_properties(mass=1.0).inertia,
        Box([b, a, c]).mass_properties(mass=1.0).inertia,
        1.0,
    )
    # A dumbbell: balls of mass m_b at +-d on x and a rod (a capsule along x) between them.
    # About y through the centre: sum of (I_own + m d^2), Steiner's theorem.
    rb, d, rr = 0.1, 0.5, 0.02
    along_x = rotation_matrix([math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0])
    dumbbell = Compound(
        [
            (Sphere(rb), [-d, 0, 0]),
            (Sphere(rb), [d, 0, 0]),
            (Capsule(2 * d, rr), [0, 0, 0], along_x),
        ]
    )
    rho = 1000.0
    m_ball = rho * 4 / 3 * math.pi * rb**3
    rod = capsule_integrals(rr, 2 * d)
    i_yy = 2 * (0.4 * m_ball * rb * rb + m_ball * d * d) + rho * (
        rod.second[2, 2] + rod.second[0, 0]
    )
    props = dumbbell.mass_properties(density=rho)
    _close(props.centroid, np.zeros(3), d)
    _close(props.inertia[1, 1], i_yy, i_yy)
    _close(props.mass, 2 * m_ball + rho * rod.volume, props.mass)


@settings(max_examples=40, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    angle=st.floats(-math.pi, math.pi),
    offset=st.lists(st.floats(-50, 50), min_size=3, max_size=3),
)
def test_moving_a_hull_moves_its_centroid_and_turns_its_inertia(
    seed: int, angle: float, offset: list[float]
) -> None:
    # The centroid follows x -> R x + t; the inertia about it becomes R I R^T; principal
    # moments are positive and obey the triangle inequality I1 + I2 >= I3.
    rng = np.random.default_rng(seed)
    points = rng.normal(size=(12, 3)) * rng.uniform(0.1, 2.0, size=3)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    q = [math.cos(angle / 2), *(math.sin(angle / 2) * axis)]
    r = rotation_matrix(q)
    before = Hull(points).mass_properties(density=1.0)
    after = Hull(points @ r.T + offset).mass_properties(density=1.0)
    size = float(np.max(np.abs(points)))
    assert abs(after.mass - before.mass) <= 1e-9 * before.mass
    assert np.max(np.abs(after.centroid - (r @ before.centroid + offset))) <= 1e-9 * (size + 50)
    turned = r @ before.inertia @ r.T
    assert np.max(np.abs(after.inertia - turned)) <= 1e-9 * np.max(np.abs(before.inertia))
    moments, axes = before.principal()
    assert moments[0] > 0.0
    assert moments[0] + moments[1] >= moments[2] * (1 - 1e-12)
    assert np.allclose(axes @ np.diag(moments) @ axes.T, before.inertia, atol=1e-12 * moments[2])
    assert np.linalg.det(axes) > 0.0


def test_integrals_of_a_closed_box_mesh_match_the_box() -> None:
    box = Box([1.0, 2.0, 3.0])
    piece = box.pieces()[0]
    mesh = polyhedron_integrals(piece.vertices, piece.triangles)
    closed = box_integrals(np.array([1.0, 2.0, 3.0]))
    _close(mesh.volume, closed.volume, 6.0)
    _close(mesh.second, closed.second, 6.0 * 14.0)


def test_open_or_inconsistent_meshes_are_refused() -> None:
    piece = Box([1.0, 1.0, 1.0]).pieces()[0]
    with pytest.raises(CaromError, match="not closed"):
        check_closed(piece.triangles[1:], 8)
    flipped = piece.triangles.copy()
    flipped[0] = flipped[0, [0, 2, 1]]
    with pytest.raises(CaromError, match="consistently oriented"):
        check_closed(flipped, 8)
    with pytest.raises(CaromError, match=r"outside 0\.\.7"):
        check_closed(piece.triangles + 1, 8)
