"""Contact manifolds of round shapes and planes in 3D (carom.geometry.manifold3d) against their
closed forms: distances between centres and segments, the midpoint convention, two points for
parallel capsules, four for a box on a plane.

Tolerances: each quantity is a handful of float64 operations on numbers of order 1, so 1e-14.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from carom.geometry.manifold3d import (
    MAX_POINTS,
    OUT_SIZE,
    closest_segment_segment,
    contact_capsule_capsule,
    contact_capsule_sphere,
    contact_hull_plane,
    contact_segments_plane,
    contact_sphere_sphere,
)
from carom.shapes3d import Box, rotation_matrix

TOL = 1e-14


def _buffers() -> tuple[np.ndarray, np.ndarray]:
    return np.zeros(OUT_SIZE), np.full(MAX_POINTS, -1, np.int64)


def _points(out: np.ndarray, count: int) -> np.ndarray:
    return np.array([out[3 + 4 * j : 7 + 4 * j] for j in range(count)])


coordinate = st.floats(-3.0, 3.0)
vector = st.tuples(coordinate, coordinate, coordinate).map(np.array)


@settings(max_examples=100, deadline=None)
@given(a=vector, b=vector, ra=st.floats(0.01, 1.0), rb=st.floats(0.01, 1.0))
def test_two_spheres_touch_on_the_line_of_centres(
    a: np.ndarray, b: np.ndarray, ra: float, rb: float
) -> None:
    # separation |b - a| - ra - rb along n = (b - a)/|b - a|; the point midway between the
    # surface points a + ra n and b - rb n; swapping A and B turns n round
    distance = float(np.linalg.norm(b - a))
    if distance < 1e-6:
        return
    out, ids = _buffers()
    count = contact_sphere_sphere(a, ra, b, rb, 10.0, out, ids)
    assert count == 1
    n = (b - a) / distance
    assert np.allclose(out[:3], n, atol=TOL * 10)
    point = _points(out, 1)[0]
    assert point[3] == pytest.approx(distance - ra - rb, abs=TOL * 10)
    assert np.allclose(point[:3], 0.5 * ((a + ra * n) + (b - rb * n)), atol=TOL * 10)
    back, _ = _buffers()
    contact_sphere_sphere(b, rb, a, ra, 10.0, back, ids)
    assert np.allclose(back[:3], -out[:3], atol=TOL * 10)
    assert contact_sphere_sphere(a, ra, b, rb, distance - ra - rb - 1e-9, out, ids) == 0


def test_a_sphere_beside_a_capsule_meets_the_nearest_point_of_its_segment() -> None:
    out, ids = _buffers()
    a0, a1 = np.array([-1.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0])
    # beside the middle: the segment's point (0.3, 0, 0), distance 0.5
    count = contact_capsule_sphere(a0, a1, 0.1, np.array([0.3, 0.5, 0.0]), 0.2, 0.5, out, ids)
    assert count == 1
    assert ids[0] == 2
    assert np.allclose(out[:3], [0.0, 1.0, 0.0])
    assert _points(out, 1)[0] == pytest.approx([0.3, 0.5 * (0.1 + 0.3), 0.0, 0.2], abs=TOL)
    # beyond an end: the end, along the line to the centre (3-4-5)
    count = contact_capsule_sphere(a0, a1, 0.1, np.array([1.3, 0.4, 0.0]), 0.2, 0.5, out, ids)
    assert ids[0] == 1
    assert np.allclose(out[:3], [0.6, 0.8, 0.0])
    assert _points(out, 1)[0][3] == pytest.approx(0.5 - 0.3, abs=TOL)


def _brute_segments(
    p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray, steps: int = 401
) -> float:
    s = np.linspace(0.0, 1.0, steps)
    p = p0 + s[:, None] * (p1 - p0)
    q = q0 + s[:, None] * (q1 - q0)
    return float(np.min(np.linalg.norm(p[:, None, :] - q[None, :, :], axis=2)))


@settings(max_examples=60, deadline=None)
@given(p0=vector, p1=vector, q0=vector, q1=vector)
def test_closest_points_of_two_segments_beat_a_dense_grid(
    p0: np.ndarray, p1: np.ndarray, q0: np.ndarray, q1: np.ndarray
) -> None:
    # the exact minimum is at or below any sampled pair's distance, and a 401 x 401 grid on
    # segments of length <= 6 sqrt(3) has a pair within half a step of each closest point,
    # so within a step (2.6e-2 m) of the minimum
    s, t = closest_segment_segment(p0, p1, q0, q1)
    assert 0.0 <= s <= 1.0
    assert 0.0 <= t <= 1.0
    found = float(np.linalg.norm((p0 + s * (p1 - p0)) - (q0 + t * (q1 - q0))))
    grid = _brute_segments(p0, p1, q0, q1)
    assert found <= grid + 1e-12
    assert found >= grid - 6 * math.sqrt(3) / 400


def test_crossing_capsules_touch_at_one_point() -> None:
    out, ids = _buffers()
    # along x at z = 0 and along y at z = 0.5: closest points (0, 0, 0) and (0, 0, 0.5)
    count = contact_capsule_capsule(
        np.array([-1.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), 0.2,
        np.array([0.0, -1.0, 0.5]), np.array([0.0, 1.0, 0.5]), 0.2, 0.2, out, ids,
    )  # fmt: skip
    assert count == 1
    assert np.allclose(out[:3], [0.0, 0.0, 1.0])
    assert _points(out, 1)[0] == pytest.approx([0.0, 0.0, 0.25, 0.1], abs=TOL)
    assert ids[0] == 2


def test_a_capsule_lying_on_a_parallel_capsule_rests_on_two_points() -> None:
    # A from x = -1 to 1; B from x = 0.5 to 3, 0.39 above: the overlap x in [0.5, 1], two
    # points at its ends, each overlapping by 0.4 - 0.39 = 0.01
    out, ids = _buffers()
    count = contact_capsule_capsule(
        np.array([-1.0, 0.0, 0.0]), np.array([1.0, 0.0, 0.0]), 0.2,
        np.array([3.0, 0.0, 0.39]), np.array([0.5, 0.0, 0.39]), 0.2, 0.0, out, ids,
    )  # fmt: skip
    assert count == 2
    assert np.allclose(out[:3], [0.0, 0.0, 1.0], atol=TOL)
    points = _points(out, 2)
    assert points[:, 0] == pytest.approx([0.5, 1.0], abs=TOL)
    assert points[:, 2] == pytest.approx([0.195, 0.195], abs=TOL)
    assert points[:, 3] == pytest.approx([-0.01, -0.01], abs=TOL)
    assert list(ids[:2]) == [0, 1]


def test_a_capsule_on_a_plane_rests_on_both_ends() -> None:
    out, ids = _buffers()
    ends = np.array([[-1.0, 0.0, 0.19], [1.0, 0.0, 0.25]])
    count = contact_segments_plane(ends, 0.2, np.array([0.0, 0.0, 1.0]), 0.0, 0.01, out, ids)
    # the end 0.19 up overlaps by 0.01; the one 0.25 up is 0.05 away, beyond the 0.01 margin
    assert count == 1
    assert np.allclose(out[:3], [0.0, 0.0, -1.0])
    assert _points(out, 1)[0] == pytest.approx([-1.0, 0.0, -0.005, -0.01], abs=TOL)
    assert contact_segments_plane(ends, 0.2, np.array([0.0, 0.0, 1.0]), 0.0, 0.06, out, ids) == 2


def test_a_box_on_a_plane_rests_on_its_four_corners() -> None:
    # a 1 x 2 x 0.5 box sunk 1 mm into the floor: the 4 bottom corners, each -1 mm
    corners = Box([1.0, 2.0, 0.5]).corners() + np.array([0.0, 0.0, 0.249])
    out, ids = _buffers()
    count = contact_hull_plane(corners, np.array([0.0, 0.0, 1.0]), 0.0, 0.005, out, ids)
    assert count == 4
    points = _points(out, 4)
    assert points[:, 3] == pytest.approx([-0.001] * 4, abs=TOL)
    assert sorted(map(tuple, np.round(points[:, :2], 12))) == sorted(
        (x, y) for x in (-0.5, 0.5) for y in (-1.0, 1.0)
    )


def test_of_many_corners_near_a_plane_the_deepest_and_the_widest_four_are_kept() -> None:
    # an octagonal prism lying flat, tilted a little about x: 8 corners near the floor; the
    # deepest is kept, and the four span at least the area of the inscribed square's share
    turn = 2 * math.pi / 8
    ring = [[math.cos(k * turn), math.sin(k * turn), 0.0] for k in range(8)]
    prism = np.array(ring + [[x, y, 0.3] for x, y, _ in ring])
    tilt = rotation_matrix([math.cos(0.001), math.sin(0.001), 0.0, 0.0])
    placed = prism @ tilt.T
    out, ids = _buffers()
    count = contact_hull_plane(placed, np.array([0.0, 0.0, 1.0]), 0.0, 0.01, out, ids)
    assert count == 4
    heights = placed[:8, 2]
    assert int(np.argmin(heights)) in ids[:4]
    chosen = placed[ids[:4], :2]
    # area of the kept quadrilateral (shoelace on its hull) >= the inscribed square's 2 r^2
    centre = chosen.mean(axis=0)
    order = np.argsort(np.arctan2(chosen[:, 1] - centre[1], chosen[:, 0] - centre[0]))
    x, y = chosen[order, 0], chosen[order, 1]
    area = 0.5 * abs(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1)))
    assert area >= 2.0 * math.cos(0.002) - 1e-12  # the square, seen at the tilt
