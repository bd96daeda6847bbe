"""The 2D exact impacts' search for a time of impact (:mod:`carom.engines.rigid.impacts`): its
steps never pass the first touch, and a body turning about a corner that nearly touches is
not held to crawling steps.

Each step the search takes is the longer of two safe ones: the gap over a bound on how fast
it can close (the centres' motion along the gap's direction exact, the turn bounded by spin
times reach), and the least time at which a corner pair's second-order bound could close it
(each corner's real velocity along the direction, its curving bounded by Taylor's remainder,
``(omega^2 r - g_n) h^2 / 2``). Both hold the separation along a fixed direction above zero,
and the separation along any direction is at most the distance.
"""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from carom.engines.rigid.impacts import _curved_step, _face_step, time_of_impact
from carom.engines.rigid.motion import place_piece
from carom.engines.stepped.impacts import NEW, closing_bound
from carom.geometry.manifold2d import core_witness
from carom.geometry.outline import outward_normals


class Pair:
    """Two single-piece bodies, A (piece 0) and B (piece 1), as the engine's arrays."""

    def __init__(self, corners_a: np.ndarray, corners_b: np.ndarray) -> None:
        self.local_vertices = np.concatenate((corners_a, corners_b)).astype(float)
        self.local_normals = np.concatenate(
            (outward_normals(corners_a), outward_normals(corners_b))
        )
        self.piece_start = np.array([0, corners_a.shape[0]], np.int64)
        self.piece_count = np.array([corners_a.shape[0], corners_b.shape[0]], np.int64)
        self.piece_radius = np.zeros(2)
        self.piece_reach = np.array(
            [np.linalg.norm(corners_a, axis=1).max(), np.linalg.norm(corners_b, axis=1).max()]
        )
        self.vertices = np.zeros_like(self.local_vertices)
        self.normals = np.zeros_like(self.local_normals)
        self.x = np.zeros((2, 2))
        self.angle = np.zeros(2)
        self.v = np.zeros((2, 2))
        self.omega = np.zeros(2)
        self.accel = np.zeros((2, 2))

    def place(self, tau: float) -> None:
        """Both pieces where their free flight puts them ``tau`` [s] from now."""
        for p in (0, 1):
            at = self.x[p] + (self.v[p] + 0.5 * self.accel[p] * tau) * tau
            place_piece(
                p, at[0], at[1], self.angle[p] + self.omega[p] * tau, self.piece_start,
                self.piece_count, self.local_vertices, self.local_normals, self.vertices,
                self.normals,
            )  # fmt: skip

    def time_of_impact(self, tol: float) -> float:
        """The search's first touch within 1 s [s] (``tol`` [m]), from a new meeting."""
        t: float = time_of_impact(
            0, 1, 0, 1, 1.0, tol, NEW, self.x, self.angle, self.v, self.omega, self.accel,
            self.piece_start, self.piece_count, self.piece_radius, self.piece_reach,
            self.local_vertices, self.local_normals, self.vertices, self.normals, np.zeros(8),
            np.zeros(2, np.int64),
        )  # fmt: skip
        return t

    def separation(self, n: np.ndarray) -> float:
        """A's lowest corner along ``n`` less B's highest [m]."""
        k = self.piece_count[0]
        return float((self.vertices[:k] @ n).min() - (self.vertices[k:] @ n).max())

    def witness(self) -> tuple[float, np.ndarray]:
        d, wx, wy = core_witness(
            self.vertices,
            self.normals,
            0,
            self.piece_count[0],
            self.piece_count[0],
            self.piece_count[1],
        )
        return d, np.array([wx, wy])


def _box(hx: float, hy: float) -> np.ndarray:
    return np.array([[-hx, -hy], [hx, -hy], [hx, hy], [-hx, hy]])


finite = st.floats(-3.0, 3.0)


@settings(max_examples=200, deadline=None)
@given(
    st.floats(0.1, 1.0), st.floats(0.1, 1.0), st.floats(-1.5, 1.5), st.floats(0.0, math.pi),
    st.tuples(finite, finite), st.tuples(finite, finite), finite, finite,
    st.tuples(finite, finite), st.floats(0.01, 1.0),
)  # fmt: skip
def test_a_step_never_loses_more_than_the_gap_along_its_direction(
    hx, hy, dx, turn, va, vb, wa, wb, pull, share
) -> None:
    # A box above a triangle, both moving, turning and pulled: over the curved step h, the
    # separation along the fixed witness direction n, sampled densely on the exact motion,
    # stays above its value now less the gap the step was asked to keep (a share of it).
    pair = Pair(_box(hx, hy), np.array([[-0.6, -0.3], [0.6, -0.3], [0.0, 0.4]]))
    pair.x[:] = [[dx, 2.0], [0.0, 0.0]]
    pair.angle[:] = [turn, 0.3]
    pair.v[:] = [va, vb]
    pair.omega[:] = [wa, wb]
    pair.accel[0] = pull
    pair.place(0.0)
    d, n = pair.witness()
    assert d > 0.0
    gap = share * d
    h = _curved_step(
        0, 1, 0, 1, 0.0, n[0], n[1], gap, pair.x, pair.v, pair.omega, pair.accel,
        pair.piece_start, pair.piece_count, pair.piece_reach, pair.vertices,
    )  # fmt: skip
    assert h > 0.0
    start = pair.separation(n)
    for tau in np.linspace(0.0, min(h, 5.0), 401):
        pair.place(tau)
        # the bound's own arithmetic: a few ulps of the O(1) heights and speeds
        assert pair.separation(n) >= start - gap - 1e-12


@settings(max_examples=200, deadline=None)
@given(st.floats(1e-6, 1.0), st.floats(-3.0, 3.0), st.floats(-10.0, 10.0), st.floats(0.0, 3.0))
def test_the_speed_bound_never_closes_the_gap_sooner_than_it_can(gap, opening, pull, spin) -> None:
    # closing_bound's step s = gap / closing: the lower bound of the separation along n,
    # gap + opening s + pull s^2 / 2 - spin s, is still >= 0 at s and at every time before it
    closing = closing_bound(gap, opening, pull, spin)
    # (0: it says the bound never closes; check far out)
    s_end = 100.0 if closing == 0.0 else gap / closing
    for s in np.linspace(0.0, s_end, 201):
        assert gap + opening * s + 0.5 * pull * s * s - spin * s >= -1e-12 * (1.0 + gap)


def _first_touch(height, end: float) -> float:
    """First root [s] of ``height(t)`` in ``[0, end]``: a scan of 2e5 samples brackets it,
    then bisection to adjacent floats."""
    ts = np.linspace(0.0, end, 200_001)
    hs = np.array([height(t) for t in ts])
    k = int(np.argmax(hs <= 0.0))
    assert k > 0
    lo, hi = float(ts[k - 1]), float(ts[k])
    while lo < (mid := 0.5 * (lo + hi)) < hi:
        lo, hi = (mid, hi) if height(mid) > 0.0 else (lo, mid)
    return lo


def test_a_box_turning_about_a_corner_that_nearly_touches_finds_its_next_impact() -> None:
    # A unit square tilted by 0.3 rad, its lowest corner 1e-7 m above a floor, turning at
    # -2 rad/s with its centre moving at omega x r about that corner (the corner at rest this
    # instant; in free flight the centre goes straight, so it lifts slowly), no gravity. The
    # first touch is the first root of the lowest corner's height, each corner's height the
    # explicit y0 + vy t + (R(theta0 + omega t) p)_y (the floor's top y = 0 spans them all).
    # The gap over the fastest corner's speed (sqrt(2) * 2 m/s) would advance 1e-7 / 2.8 s a
    # step and stop after its 200 steps at 7e-6 s, far short; the search must end within
    # tol of touching, on the safe side of the first touch.
    omega, theta0, lift = -2.0, 0.3, 1e-7
    pair = Pair(_box(0.5, 0.5), _box(5.0, 0.5))
    c, s = math.cos(theta0), math.sin(theta0)
    pivot = np.array([0.0, lift])
    centre = pivot + np.array([0.5 * (c - s), 0.5 * (s + c)])  # corner (-0.5, -0.5) at pivot
    r = centre - pivot
    pair.x[:] = [centre, [0.0, -0.5]]
    pair.angle[:] = [theta0, 0.0]
    pair.omega[:] = [omega, 0.0]
    pair.v[0] = omega * np.array([-r[1], r[0]])
    tol = 1e-9 * float(pair.piece_reach.sum())
    t = pair.time_of_impact(tol)
    corners = _box(0.5, 0.5)

    def lowest(tau: float) -> float:
        turn = theta0 + omega * tau
        y = centre[1] + pair.v[0, 1] * tau + math.sin(turn) * corners[:, 0]
        return float((y + math.cos(turn) * corners[:, 1]).min())

    first = _first_touch(lowest, 1.0)
    assert 0.1 < first < 0.2  # the next corner, near theta0 / |omega| = 0.15 s
    assert t <= first + 1e-12  # never past the first touch (the reference's own round-off)
    assert lowest(t) <= tol + 1e-15  # and within tol of it


@settings(max_examples=200, deadline=None)
@given(
    st.floats(-0.4, 0.4), st.floats(0.0, math.pi / 2), st.tuples(finite, finite),
    st.tuples(finite, finite), finite, finite, st.tuples(finite, finite), st.floats(0.01, 1.0),
)  # fmt: skip
def test_a_face_step_never_loses_more_than_asked_along_the_turning_face(
    dx, turn, va, vb, wa, wb, pull, share
) -> None:
    # A square above a wide box B, both moving, turning and pulled: over the face step h, the
    # separation of A's corners from B's top face along the face's own normal (turning with
    # B), sampled densely on the exact motion, stays above the target it was given.
    pair = Pair(_box(0.3, 0.3), _box(2.0, 0.5))
    pair.x[:] = [[dx, 1.5], [0.0, 0.0]]
    pair.angle[:] = [turn, 0.0]
    pair.v[:] = [va, vb]
    pair.omega[:] = [wa, wb]
    pair.accel[0] = pull
    pair.place(0.0)
    top_row = 2  # B's face (2.0, 0.5) -> (-2.0, 0.5): normal +y
    n = pair.normals[4 + top_row]
    assert np.allclose(n, [0.0, 1.0])
    start = pair.separation(n)
    target = start - share * start
    horizon = 1.0
    h = _face_step(
        1, 1, 0, 0, 0.0, n[0], n[1], target, horizon, pair.x, pair.v, pair.omega, pair.accel,
        pair.piece_start, pair.piece_count, pair.piece_reach, pair.vertices,
    )  # fmt: skip
    assert h > 0.0
    for tau in np.linspace(0.0, min(h, horizon), 401):
        pair.place(tau)
        # the face's normal at tau is B's row, turned with it; the bound's arithmetic is a
        # few ulps of O(1) heights and speeds
        assert pair.separation(pair.normals[4 + top_row].copy()) >= target - 1e-12


def test_a_corner_over_a_face_that_turns_under_it_finds_the_touch_at_once() -> None:
    # A wide box (half 2 x 0.5) turns at 0.5 rad/s about its centre under a still square's
    # corner hanging 1e-7 m above its top face's middle; no gravity. The corner's height
    # above the face is (0.5 + 1e-7) cos(omega t) - 0.5: it touches at
    # t* = acos(0.5 / (0.5 + 1e-7)) / omega = 1.26e-3 s. The face's ends rise at 1 m/s, so a
    # fixed direction's bound would step 1e-7 s at a time (12600 steps for a search capped at
    # 200); the face followed as it turns sees the corner sink at the rate it does.
    omega, lift = 0.5, 1e-7
    pair = Pair(_box(0.5, 0.5), _box(2.0, 0.5))
    pair.x[:] = [[0.0, 0.5 + lift + math.sqrt(0.5)], [0.0, 0.0]]
    pair.angle[:] = [math.pi / 4, 0.0]
    pair.omega[:] = [0.0, omega]
    tol = 1e-9 * float(pair.piece_reach.sum())
    t = pair.time_of_impact(tol)

    def height(tau: float) -> float:
        return (0.5 + lift) * math.cos(omega * tau) - 0.5

    first = _first_touch(height, 0.01)
    assert abs(first - math.acos(0.5 / (0.5 + lift)) / omega) < 1e-9  # the closed form
    assert t <= first + 1e-12  # never past the first touch
    assert height(t) <= tol + 1e-15  # and within tol of it
