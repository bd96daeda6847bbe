"""Polyhedron against polyhedron (carom.geometry.manifold3d.contact_hull_hull): separating axes
and face clipping, against closed forms (a box resting on a box, a turned box overhanging,
crossed edges) and, over random hulls, against a linear program that decides overlap exactly.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from carom.geometry.manifold3d import (
    MAX_POINTS,
    OUT_SIZE,
    contact_hull_capsule,
    contact_hull_hull,
    contact_hull_sphere,
)
from carom.geometry.polyhedron import polyhedron_features, triangle_features
from carom.shapes3d import Box, Hull, rotation_matrix

scipy_optimize = pytest.importorskip("scipy.optimize")

TOL = 1e-12
SLOP = 0.005


def _placed(
    vertices: np.ndarray, triangles: np.ndarray, rotation: np.ndarray, offset: np.ndarray
) -> tuple[np.ndarray, ...]:
    features = polyhedron_features(vertices, triangles)
    return (
        vertices @ rotation.T + offset,
        features.normals @ rotation.T,
        features.face_start,
        features.face_count,
        features.corners,
        features.edges,
    )


def _box(
    size: list[float], offset: list[float], q: list[float] | None = None
) -> tuple[np.ndarray, ...]:
    piece = Box(size).pieces()[0]
    r = rotation_matrix(q) if q is not None else np.eye(3)
    return _placed(piece.vertices, piece.triangles, r, np.array(offset, float))


def _contact(
    a: tuple[np.ndarray, ...], b: tuple[np.ndarray, ...], margin: float = 0.0
) -> tuple[int, np.ndarray, np.ndarray]:
    out = np.zeros(OUT_SIZE)
    ids = np.full(MAX_POINTS, -1, np.int64)
    count = contact_hull_hull(*a, *b, margin, SLOP, out, ids)
    points = np.array([out[3 + 4 * j : 7 + 4 * j] for j in range(count)]).reshape(count, 4)
    return count, out[:3].copy(), points


def test_a_box_resting_on_a_box_touches_at_its_four_corners() -> None:
    # a unit cube 1 cm into the top of a 4 x 4 x 1 slab: its bottom face, 4 corners, each
    # -0.01, midway at z = 0.5 - 0.005, normal up from the slab (A) to the cube (B)
    slab = _box([4.0, 4.0, 1.0], [0.0, 0.0, 0.0])
    cube = _box([1.0, 1.0, 1.0], [0.3, -0.2, 0.99])
    count, normal, points = _contact(slab, cube)
    assert count == 4
    assert normal == pytest.approx([0.0, 0.0, 1.0], abs=TOL)
    assert points[:, 3] == pytest.approx([-0.01] * 4, abs=TOL)
    assert points[:, 2] == pytest.approx([0.495] * 4, abs=TOL)
    assert sorted(map(tuple, np.round(points[:, :2], 9))) == sorted(
        (0.3 + x, -0.2 + y) for x in (-0.5, 0.5) for y in (-0.5, 0.5)
    )
    # and the other way round: the normal turns, nothing else changes
    count, back, again = _contact(cube, slab)
    assert count == 4
    assert back == pytest.approx([0.0, 0.0, -1.0], abs=TOL)
    assert again[:, 3] == pytest.approx([-0.01] * 4, abs=TOL)


def test_a_turned_box_overhanging_a_box_keeps_four_points_on_the_shared_octagon() -> None:
    # a unit cube on another, turned 45 deg about z: the two squares overlap in a regular
    # octagon; four of its corners are kept, all 5 mm deep, all on both squares
    lower = _box([1.0, 1.0, 1.0], [0.0, 0.0, 0.0])
    q = [math.cos(math.pi / 8), 0.0, 0.0, math.sin(math.pi / 8)]
    upper = _box([1.0, 1.0, 1.0], [0.0, 0.0, 0.995], q)
    count, normal, points = _contact(lower, upper)
    assert count == 4
    assert normal == pytest.approx([0.0, 0.0, 1.0], abs=TOL)
    assert points[:, 3] == pytest.approx([-0.005] * 4, abs=TOL)
    xy = points[:, :2]
    assert np.all(np.abs(xy) <= 0.5 + TOL)  # on the lower square
    assert np.all(np.abs(xy[:, 0]) + np.abs(xy[:, 1]) <= math.sqrt(0.5) + TOL)  # the diamond
    # each is an octagon corner: at the octagon's circumradius 0.5/cos(22.5 deg)
    assert np.hypot(xy[:, 0], xy[:, 1]) == pytest.approx([0.5 / math.cos(math.pi / 8)] * 4)


def test_crossed_edges_touch_at_one_point() -> None:
    # A turned 45 deg about x has a top edge along x at z = sqrt(2)/2; B turned 45 deg about y,
    # centred at height h, a bottom edge along y at h - sqrt(2)/2: they cross at the origin's
    # vertical, separation h - sqrt(2), one point midway at (0, 0, h/2)
    h = 1.4
    a = _box([1.0, 1.0, 1.0], [0.0, 0.0, 0.0], [math.cos(math.pi / 8), math.sin(math.pi / 8), 0, 0])
    b = _box([1.0, 1.0, 1.0], [0.0, 0.0, h], [math.cos(math.pi / 8), 0, math.sin(math.pi / 8), 0])
    count, normal, points = _contact(a, b)
    assert count == 1
    assert normal == pytest.approx([0.0, 0.0, 1.0], abs=TOL)
    assert points[0] == pytest.approx([0.0, 0.0, h / 2, h - math.sqrt(2.0)], abs=TOL)


def test_boxes_apart_beyond_the_margin_have_no_contact() -> None:
    a = _box([1.0, 1.0, 1.0], [0.0, 0.0, 0.0])
    b = _box([1.0, 1.0, 1.0], [0.0, 0.0, 1.02])
    assert _contact(a, b, margin=0.01)[0] == 0
    count, normal, points = _contact(a, b, margin=0.03)  # speculative: 2 cm apart
    assert count == 4
    assert normal == pytest.approx([0.0, 0.0, 1.0], abs=TOL)
    assert points[:, 3] == pytest.approx([0.02] * 4, abs=TOL)


def _overlap(a: np.ndarray, b: np.ndarray) -> bool:
    """Whether two hulls share a point: some convex combination of A's corners equals one of
    B's (a feasibility linear program)."""
    ka, kb = a.shape[0], b.shape[0]
    equality = np.zeros((5, ka + kb))
    equality[:3, :ka] = a.T
    equality[:3, ka:] = -b.T
    equality[3, :ka] = 1.0
    equality[4, ka:] = 1.0
    rhs = np.array([0.0, 0.0, 0.0, 1.0, 1.0])
    result = scipy_optimize.linprog(np.zeros(ka + kb), A_eq=equality, b_eq=rhs, bounds=(0, None))
    return bool(result.status == 0)


@settings(max_examples=80, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), gap=st.floats(-0.6, 0.6))
@example(seed=45, gap=0.5)  # apart and beside each other: clipping alone found no point
@example(seed=602666, gap=0.0)  # deep overlap, the clipped face off the reference face: none
def test_the_separating_axes_decide_overlap_as_a_linear_program_does(seed: int, gap: float) -> None:
    # two random hulls, B moved along a random direction by a distance around touching: the
    # test's separation is positive exactly when no point is shared (every axis that can
    # separate two convex polyhedra is a face normal or an edge cross product); near-touching
    # cases within 1e-7 m are left out, as round-off decides them
    rng = np.random.default_rng(seed)
    shapes = []
    for _ in range(2):
        hull = Hull(rng.normal(size=(10, 3)) * rng.uniform(0.2, 1.0, size=3))
        r = rotation_matrix(rng.normal(size=4))
        shapes.append((hull, r))
    direction = rng.normal(size=3)
    direction /= np.linalg.norm(direction)
    a = _placed(
        shapes[0][0].vertices - shapes[0][0].centroid,
        shapes[0][0].triangles,
        shapes[0][1],
        np.zeros(3),
    )
    reach = np.max(np.linalg.norm(a[0], axis=1))
    b_hull, b_rot = shapes[1]
    b0 = b_hull.vertices - b_hull.centroid
    b_reach = np.max(np.linalg.norm(b0, axis=1))
    b = _placed(b0, b_hull.triangles, b_rot, direction * (reach + b_reach) * (0.5 + gap))
    count, normal, points = _contact(a, b, margin=10.0)
    assert count >= 1
    sep = float(points[:, 3].min())
    if abs(sep) < 1e-7:
        return
    assert (sep <= 0.0) == _overlap(a[0], b[0])
    assert abs(np.linalg.norm(normal) - 1.0) < 1e-12


@settings(max_examples=150, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), gap=st.floats(-0.6, -0.02))
def test_the_gauss_map_keeps_the_deepest_axis_of_overlapping_hulls(seed: int, gap: float) -> None:
    # Overlapping hulls: the deepest overlap lies along a face of the Minkowski difference
    # (Gregorius, GDC 2013), so trying only the edge pairs whose arcs cross on the Gauss map
    # (edges given with their two faces, (E, 4)) finds the same manifold as crossing every
    # edge direction (edges given as corners only, (E, 2)). The pruned search measures an
    # edge pair's gap between the edges' lines, the full one by the bodies' extents: the two
    # agree to round-off of coordinates of order 1 (1e-12)
    rng = np.random.default_rng(seed)
    placed = []
    for k in range(2):
        hull = Hull(rng.normal(size=(12, 3)) * rng.uniform(0.2, 1.0, size=3))
        offset = np.zeros(3) if k == 0 else rng.normal(size=3) * (1.0 + gap)
        placed.append(
            _placed(
                hull.vertices - hull.centroid,
                hull.triangles,
                rotation_matrix(rng.normal(size=4)),
                offset,
            )
        )
    a, b = placed
    corners_only = [(*p[:5], np.ascontiguousarray(p[5][:, :2])) for p in placed]
    count, normal, points = _contact(a, b, margin=10.0)
    if count == 0 or points[:, 3].min() >= -1e-9:
        return  # apart after all: the speculative search may differ
    count2, normal2, points2 = _contact(*corners_only, margin=10.0)
    assert count == count2
    assert normal == pytest.approx(normal2, abs=1e-12)
    assert points == pytest.approx(points2, abs=1e-12)


@settings(max_examples=200, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    point=st.tuples(*[st.floats(-2.0, 2.0)] * 3),
    radius=st.floats(0.01, 0.5),
)
def test_a_sphere_against_a_box_meets_its_exact_closest_point(
    seed: int, point: tuple[float, float, float], radius: float
) -> None:
    # In the box's frame (half sizes h) the closest point of a box to p is p clamped to
    # [-h, h], at distance |max(|p| - h, 0)| outside; inside, the way out is through the
    # nearest face, min(h - |p|) away. The contact's separation is that distance less the
    # radius, its normal from the box to the centre, its point midway.
    rng = np.random.default_rng(seed)
    half = rng.uniform(0.1, 1.0, size=3)
    r = rotation_matrix(rng.normal(size=4))
    offset = rng.normal(size=3)
    box = _box(list(2 * half), list(offset), None)
    box = (box[0] - offset) @ r.T + offset, box[1] @ r.T, *box[2:]
    centre = offset + r @ np.array(point)
    local = np.array(point)
    outside = np.maximum(np.abs(local) - half, 0.0)
    if np.all(outside == 0.0):
        distance = -float(np.min(half - np.abs(local)))
        if np.sort(half - np.abs(local))[1] - np.sort(half - np.abs(local))[0] < 1e-9:
            return  # two faces equally near: either is right
    else:
        distance = float(np.linalg.norm(outside))
    out = np.zeros(OUT_SIZE)
    ids = np.full(MAX_POINTS, -1, np.int64)
    count = contact_hull_sphere(*box, centre, radius, 10.0, out, ids)
    assert count == 1
    assert out[6] == pytest.approx(distance - radius, abs=1e-12)
    if distance > 1e-9:
        surface = offset + r @ np.clip(local, -half, half)
        assert out[:3] == pytest.approx((centre - surface) / distance, abs=1e-9)
        assert out[3:6] == pytest.approx(surface + 0.5 * (distance - radius) * out[:3], abs=1e-12)


def _capsule(
    box: tuple[np.ndarray, ...],
    p0: list[float],
    p1: list[float],
    radius: float,
    margin: float = 0.0,
) -> tuple[int, np.ndarray, np.ndarray]:
    out = np.zeros(OUT_SIZE)
    ids = np.full(MAX_POINTS, -1, np.int64)
    count = contact_hull_capsule(
        *box, np.array(p0, float), np.array(p1, float), radius, margin, SLOP, out, ids
    )
    points = np.array([out[3 + 4 * j : 7 + 4 * j] for j in range(count)]).reshape(count, 4)
    return count, out[:3].copy(), points


def test_a_capsule_lying_on_a_box_rests_on_the_part_over_the_face() -> None:
    # core from x = -0.3 to 0.8 at z = 0.69, radius 0.2, over a unit cube's top (z = 0.5):
    # 1 cm deep; the part over the face runs x in [-0.3, 0.5]: two points at its ends
    cube = _box([1.0, 1.0, 1.0], [0.0, 0.0, 0.0])
    count, normal, points = _capsule(cube, [-0.3, 0.0, 0.69], [0.8, 0.0, 0.69], 0.2)
    assert count == 2
    assert normal == pytest.approx([0.0, 0.0, 1.0], abs=TOL)
    assert sorted(points[:, 0]) == pytest.approx([-0.3, 0.5], abs=TOL)
    assert points[:, 2] == pytest.approx([0.495, 0.495], abs=TOL)
    assert points[:, 3] == pytest.approx([-0.01, -0.01], abs=TOL)
    # standing up: only the lower end touches
    count, normal, points = _capsule(cube, [0.1, 0.1, 0.69], [0.1, 0.1, 1.5], 0.2)
    assert count == 1
    assert points[0] == pytest.approx([0.1, 0.1, 0.495, -0.01], abs=TOL)


def test_a_capsule_across_a_box_edge_touches_at_one_point() -> None:
    # a cube turned 45 deg about x: top edge along x at z = sqrt(2)/2; a capsule along y at
    # height h crosses it: one point, separation h - sqrt(2)/2 - r
    h, r = 0.85, 0.15
    cube = _box(
        [1.0, 1.0, 1.0], [0.0, 0.0, 0.0], [math.cos(math.pi / 8), math.sin(math.pi / 8), 0, 0]
    )
    count, normal, points = _capsule(cube, [0.2, -1.0, h], [0.2, 1.0, h], r, margin=0.1)
    assert count == 1
    assert normal == pytest.approx([0.0, 0.0, 1.0], abs=TOL)
    assert points[0, 3] == pytest.approx(h - math.sqrt(0.5) - r, abs=TOL)
    assert points[0, :2] == pytest.approx([0.2, 0.0], abs=TOL)


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2**32 - 1))
def test_a_capsule_apart_from_a_box_reports_the_exact_gap(seed: int) -> None:
    # the distance from a segment to a box is the least over the segment of the distance of
    # its point to the box, a convex function of the segment's parameter: a bounded scalar
    # minimisation finds it to 1e-10; the contact's separation must equal it less the radius
    rng = np.random.default_rng(seed)
    half = rng.uniform(0.2, 1.0, size=3)
    box = _box(list(2 * half), [0.0, 0.0, 0.0])
    p0, p1 = rng.uniform(-2.5, 2.5, size=(2, 3))

    def gap(t: float) -> float:
        local = p0 + t * (p1 - p0)
        return float(np.linalg.norm(np.maximum(np.abs(local) - half, 0.0)))

    found = scipy_optimize.minimize_scalar(
        gap, bounds=(0.0, 1.0), method="bounded", options={"xatol": 1e-12}
    )
    distance = min(found.fun, gap(0.0), gap(1.0))
    if distance < 1e-6:
        return  # touching or through: the overlap branch, tested above
    count, normal, points = _capsule(box, list(p0), list(p1), 0.05, margin=10.0)
    assert count >= 1
    assert abs(float(np.linalg.norm(normal)) - 1.0) < 1e-12
    assert float(points[:, 3].min()) == pytest.approx(distance - 0.05, abs=1e-8)


def test_a_box_on_a_mesh_triangle_rests_on_its_four_corners() -> None:
    # a triangle of the floor (z = 0) much larger than the box; the cube 2 mm into it
    floor = triangle_features(np.array([[-5.0, -5.0, 0.0], [5.0, -5.0, 0.0], [0.0, 5.0, 0.0]]))
    cube = _box([0.4, 0.4, 0.4], [0.0, 0.0, 0.198])
    count, normal, points = _contact(cube, floor)
    assert count == 4
    assert normal == pytest.approx([0.0, 0.0, -1.0], abs=TOL)  # from the box down to the floor
    assert points[:, 3] == pytest.approx([-0.002] * 4, abs=TOL)


def test_a_sphere_on_a_mesh_triangle_meets_its_face_or_its_edge() -> None:
    triangle = triangle_features(np.array([[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]))
    out = np.zeros(OUT_SIZE)
    ids = np.full(MAX_POINTS, -1, np.int64)
    # above the inside: straight down to the face, gap 0.3 - 0.1
    assert contact_hull_sphere(*triangle, np.array([0.2, 0.2, 0.3]), 0.1, 1.0, out, ids) == 1
    assert out[:7] == pytest.approx([0.0, 0.0, 1.0, 0.2, 0.2, 0.1, 0.2], abs=TOL)
    # beyond the long edge x + y = 1, level with the plane: to that edge's nearest point
    centre = np.array([0.8, 0.8, 0.0])
    assert contact_hull_sphere(*triangle, centre, 0.1, 1.0, out, ids) == 1
    gap = (1.6 - 1.0) / math.sqrt(2.0)  # the distance from (0.8, 0.8) to the line x + y = 1
    assert out[:3] == pytest.approx([math.sqrt(0.5), math.sqrt(0.5), 0.0], abs=TOL)
    assert out[6] == pytest.approx(gap - 0.1, abs=TOL)


def test_boxes_apart_beside_each_other_meet_at_their_closest_edges() -> None:
    # regression: two cubes apart by 0.2 along x and along z: the best face axis separates
    # them by 0.2, but the facing faces do not overlap, so clipping kept nothing and the
    # speculative contact was lost. The closest points are the parallel edges at
    # (0.5, y, 0.5) and (0.7, y, 0.7): 0.2 sqrt(2) apart along (1, 0, 1)/sqrt(2).
    a = _box([1.0, 1.0, 1.0], [0.0, 0.0, 0.0])
    b = _box([1.0, 1.0, 1.0], [1.2, 0.0, 1.2])
    count, normal, points = _contact(a, b, margin=0.5)
    assert count == 1
    assert normal == pytest.approx([math.sqrt(0.5), 0.0, math.sqrt(0.5)], abs=TOL)
    assert points[0, 3] == pytest.approx(0.2 * math.sqrt(2.0), abs=TOL)
    assert points[0, [0, 2]] == pytest.approx([0.6, 0.6], abs=TOL)
