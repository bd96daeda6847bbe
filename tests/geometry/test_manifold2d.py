"""Contact manifolds of rounded convex polygons against configurations with known answers.

Each case places two shapes so that the gap, the normal and the contact points follow from
the placement by hand (the comment says how); the tolerance is float64 round-off of a
rotation and a few subtractions on O(1) lengths.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from carom.geometry.manifold2d import collide, core_distance
from carom.shapes import Box, Capsule, Circle, ConvexPiece, Polygon, Segment

TOL = 1e-12
SLOP = 0.005


def placed(*poses: tuple[ConvexPiece, tuple[float, float], float]):
    """World corners, normals and (start, count, radius) of pieces at (position, angle)."""
    vertices, normals, pieces = [], [], []
    start = 0
    for piece, position, angle in poses:
        moved = piece.moved(np.asarray(position, float), angle)
        vertices.append(moved.vertices)
        normals.append(moved.normals if moved.vertices.shape[0] > 1 else np.zeros((1, 2)))
        pieces.append((start, moved.vertices.shape[0], moved.radius))
        start += moved.vertices.shape[0]
    return np.concatenate(vertices), np.concatenate(normals), pieces


def manifold(a, pose_a, b, pose_b, margin=1.0):
    vertices, normals, ((sa, ka, ra), (sb, kb, rb)) = placed(
        (a.pieces()[0], *pose_a), (b.pieces()[0], *pose_b)
    )
    out = np.full(8, np.nan)
    ids = np.full(2, -1, np.int64)
    count = collide(vertices, normals, sa, ka, ra, sb, kb, rb, margin, SLOP, out, ids)
    points = [(out[2 + 3 * j : 4 + 3 * j].copy(), out[4 + 3 * j]) for j in range(count)]
    return out[:2].copy(), points, ids[:count].copy()


def gap(a, pose_a, b, pose_b) -> float:
    vertices, normals, ((sa, ka, ra), (sb, kb, rb)) = placed(
        (a.pieces()[0], *pose_a), (b.pieces()[0], *pose_b)
    )
    return core_distance(vertices, normals, sa, ka, sb, kb) - ra - rb


def test_box_resting_on_box_gives_two_points_at_the_corners() -> None:
    # A 1 x 1 box centred at (0.2, 1.0 + g) above a 2 x 1 box at the origin: faces y = 0.5 + g
    # and y = 0.5; the top box's bottom corners x = -0.3 and 0.7 both lie over the bottom box.
    g = 0.01
    n, points, ids = manifold(Box(1, 1), ((0.2, 1.0 + g), 0.0), Box(2, 1), ((0, 0), 0.0))
    assert np.allclose(n, [0, 1], atol=TOL)
    assert len(points) == 2
    xs = sorted(p[0][0] for p in points)
    assert np.allclose(xs, [-0.3, 0.7], atol=TOL)
    for p, s in points:
        assert abs(s - g) < TOL
        assert abs(p[1] - (0.5 + g / 2)) < TOL  # halfway between the faces
    assert len(set(ids.tolist())) == 2


def test_box_overhanging_is_clipped_to_the_support() -> None:
    # the top box spans x in [0.5, 1.5]; the bottom box ends at x = 1: points at 0.5 and 1
    n, points, _ = manifold(Box(1, 1), ((1.0, 0.995), 0.0), Box(2, 1), ((0, 0), 0.0))
    assert np.allclose(n, [0, 1], atol=TOL)
    assert np.allclose(sorted(p[0][0] for p in points), [0.5, 1.0], atol=TOL)
    assert all(abs(s + 0.005) < TOL for _, s in points)


def test_tilted_box_corner_first() -> None:
    # A unit box turned by 30 degrees, its lowest corner a height h above a floor at y = 0:
    # the corner is at distance sqrt(2)/2 * cos(15 deg) below the centre (the half diagonal at
    # 45 - 30 = 15 degrees from vertical). One point at the separation h, or two with the
    # second corner higher by sin(30 deg) (the bottom edge's rise).
    h = 0.02
    drop = math.sqrt(2) / 2 * math.cos(math.radians(15))
    n, points, _ = manifold(
        Box(1, 1), ((0.0, drop + h), math.radians(30)), Box(10, 1), ((0, -0.5), 0.0)
    )
    assert np.allclose(n, [0, 1], atol=TOL)
    seps = sorted(s for _, s in points)
    assert abs(seps[0] - h) < TOL
    if len(seps) == 2:
        assert abs(seps[1] - (h + math.sin(math.radians(30)))) < TOL


def test_circles() -> None:
    # centres 1.0 apart along (3, 4)/5, radii 0.3 and 0.5: gap 0.2, normal from B to A
    u = np.array([3.0, 4.0]) / 5.0
    n, points, _ = manifold(Circle(0.3), (tuple(u), 0.0), Circle(0.5), ((0, 0), 0.0))
    assert np.allclose(n, u, atol=TOL)
    ((p, s),) = points
    assert abs(s - 0.2) < TOL
    assert np.allclose(p, u * 0.6, atol=TOL)  # halfway between 0.5 u and 0.7 u


def test_circle_on_box_face_and_corner() -> None:
    # face: a circle of radius 0.25 centred 0.3 above the top face y = 0.5
    n, points, _ = manifold(Circle(0.25), ((0.1, 0.8), 0.0), Box(1, 1), ((0, 0), 0.0))
    assert np.allclose(n, [0, 1], atol=TOL)
    assert abs(points[0][1] - 0.05) < TOL
    # corner: centre beyond the corner (0.5, 0.5) along (1, 1)/sqrt 2 at distance 0.4
    c = 0.5 + 0.4 / math.sqrt(2)
    n, points, _ = manifold(Circle(0.25), ((c, c), 0.0), Box(1, 1), ((0, 0), 0.0))
    assert np.allclose(n, [1 / math.sqrt(2)] * 2, atol=TOL)
    assert abs(points[0][1] - 0.15) < TOL
    # the same with the circle as B: the normal turns round, the gap stays
    n, points, _ = manifold(Box(1, 1), ((0, 0), 0.0), Circle(0.25), ((c, c), 0.0))
    assert np.allclose(n, [-1 / math.sqrt(2)] * 2, atol=TOL)
    assert abs(points[0][1] - 0.15) < TOL


def test_capsules_parallel_give_two_points_crossed_one() -> None:
    # parallel capsules (length 1, radius 0.1), one 0.25 above the other, offset 0.5 along x:
    # the overlap of their segments is x in [0, 0.5]; gap 0.25 - 0.2 = 0.05
    n, points, _ = manifold(Capsule(1, 0.1), ((0.5, 0.25), 0.0), Capsule(1, 0.1), ((0, 0), 0.0))
    assert np.allclose(n, [0, 1], atol=TOL)
    assert np.allclose(sorted(p[0][0] for p in points), [0.0, 0.5], atol=TOL)
    assert all(abs(s - 0.05) < TOL for _, s in points)
    # crossed at right angles, A's centre 0.3 above B's: one point, gap 0.1
    n, points, _ = manifold(
        Capsule(1, 0.1), ((0, 0.3), math.pi / 2 + 0.0), Capsule(1, 0.1), ((0, -0.5 + 0.0), 0.0)
    )
    assert len(points) == 1


def test_capsules_end_to_end_on_one_line() -> None:
    # collinear capsules whose caps are 0.04 apart: the separating axis is along the line,
    # which no edge normal of either segment gives; the closest-point branch must find it
    n, points, _ = manifold(Capsule(1, 0.1), ((1.24, 0), 0.0), Capsule(1, 0.1), ((0, 0), 0.0))
    assert np.allclose(n, [1, 0], atol=TOL)
    assert abs(points[0][1] - 0.04) < TOL


def test_box_on_static_segment() -> None:
    n, points, _ = manifold(Box(1, 1), ((0, 0.51), 0.0), Segment((-5, 0), (5, 0)), ((0, 0), 0.0))
    assert np.allclose(n, [0, 1], atol=TOL)
    assert len(points) == 2
    assert all(abs(s - 0.01) < TOL for _, s in points)


def test_far_apart_reports_nothing() -> None:
    _, points, _ = manifold(Box(1, 1), ((0, 3), 0.0), Box(1, 1), ((0, 0), 0.0), margin=0.5)
    assert points == []
    _, points, _ = manifold(Circle(1), ((0, 3), 0.0), Circle(1), ((0, 0), 0.0), margin=0.5)
    assert points == []


def test_rounded_corners_meet_along_the_diagonal() -> None:
    # two rounded unit boxes (radius 0.1) placed corner to corner along the diagonal: the gap
    # is the corners' distance minus 0.2 and the normal is the diagonal
    d = 0.3
    off = 1.0 + d / math.sqrt(2)
    a, b = Box(1, 1, radius=0.1), Box(1, 1, radius=0.1)
    n, points, _ = manifold(a, ((off, off), 0.0), b, ((0, 0), 0.0))
    assert len(points) == 1
    assert np.allclose(n, [1 / math.sqrt(2)] * 2, atol=TOL)
    assert abs(points[0][1] - (d - 0.2)) < TOL


SHAPES = [
    Box(1.0, 0.5),
    Box(0.3, 0.3, radius=0.05),
    Circle(0.4),
    Capsule(0.8, 0.15),
    Polygon.regular(5, 0.5),
    Polygon([[0, 0], [1, 0], [0.2, 0.6]], radius=0.02),
]


@settings(max_examples=400, deadline=None)
@given(
    st.sampled_from(range(len(SHAPES))),
    st.sampled_from(range(len(SHAPES))),
    st.floats(-1.2, 1.2),
    st.floats(-1.2, 1.2),
    st.floats(-math.pi, math.pi),
    st.floats(-math.pi, math.pi),
)
def test_manifold_agrees_with_exact_distance(ia, ib, x, y, angle_a, angle_b) -> None:
    # Within speculative range (a gap under 0.1 m) the deepest manifold point must match the
    # exact gap (core_distance minus the radii) up to the tie allowance 0.1 slop, by which a
    # face contact is kept over a nearly-as-close corner (no flip-flop between steps).
    # Overlapping shapes (exact gap <= 0 with sharp cores) must report an overlap.
    a, b = SHAPES[ia], SHAPES[ib]
    exact = gap(a, ((x, y), angle_a), b, ((0, 0), angle_b))
    _, points, _ = manifold(a, ((x, y), angle_a), b, ((0, 0), angle_b), margin=10.0)
    assert points, "a manifold within 10 m must report a point"
    deepest = min(s for _, s in points)
    if 0.0 < exact < 0.1:
        assert abs(deepest - exact) <= 0.1 * SLOP + 1e-12
    elif exact == 0.0 and min(sh.pieces()[0].radius for sh in (a, b)) == 0.0:
        assert deepest <= 1e-9


def test_core_distance_of_long_segment_past_a_box() -> None:
    # A long segment from (-2, 1.5) to (2, 0.5) passes above a unit box, beyond both ends of
    # every box face: only the segment's own normal (1, 4)/sqrt(17) separates them, and the
    # gap is the nearest corner's distance to the line, |(c - p) . n| with p = (-2, 1.5): for
    # c = (0.5, 0.5), (2.5, -1) . (1, 4)/sqrt(17) = -1.5/sqrt(17); (-0.5, 0.5) gives -2.5/sqrt(17).
    seg = Segment((-2, 1.5), (2, 0.5))
    vertices, normals, ((sa, ka, _), (sb, kb, _)) = placed(
        (Box(1, 1).pieces()[0], (0, 0), 0.0), (seg.pieces()[0], (0, 0), 0.0)
    )
    assert abs(core_distance(vertices, normals, sa, ka, sb, kb) - 1.5 / math.sqrt(17)) < TOL


@pytest.mark.parametrize("ka", [1, 2, 4])
def test_core_distance_zero_when_overlapping(ka: int) -> None:
    shape = {1: Circle(0.1), 2: Capsule(0.5, 0.1), 4: Box(0.5, 0.5)}[ka]
    vertices, normals, ((sa, k1, _), (sb, k2, _)) = placed(
        (shape.pieces()[0], (0.1, 0.05), 0.3), (Box(1, 1).pieces()[0], (0, 0), 0.0)
    )
    assert core_distance(vertices, normals, sa, k1, sb, k2) == 0.0
