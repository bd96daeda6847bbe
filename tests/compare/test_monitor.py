"""The yardstick: overlaps, pass-throughs and checks, against brute force."""

from __future__ import annotations

import itertools

import numpy as np
import pytest

from carom.compare.closed_form import Check, Expectation
from carom.compare.driver import peer_scene
from carom.compare.monitor import Monitor, pair_check


def _brute(before, after, radius):
    """O(N^2) overlap and pass-throughs, written the obvious way."""
    overlap, crossings = -np.inf, 0
    for i, j in itertools.combinations(range(len(radius)), 2):
        s = radius[i] + radius[j]
        d0, d1 = before[j] - before[i], after[j] - after[i]
        overlap = max(overlap, s - np.linalg.norm(d1))
        if d0 @ d1 < 0:
            f = np.linspace(0.0, 1.0, 20001)[:, None]
            if np.min(np.linalg.norm(d0 + f * (d1 - d0), axis=1)) < s:
                crossings += 1
    return overlap, crossings


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("seed", range(4))
def test_pair_check_agrees_with_brute_force(dim, seed):
    rng = np.random.default_rng(seed)
    n, box = 60, np.full(dim, 4.0)
    radius = rng.uniform(0.05, 0.2, n)
    before = rng.uniform(0.0, 4.0, (n, dim))
    after = before + rng.normal(scale=0.15, size=(n, dim))
    size = 2 * radius.max() + 2 * np.abs(after - before).max()
    overlap, crossings = pair_check(before, after, radius, box, size)
    want_overlap, want_crossings = _brute(before, after, radius)
    # the same distance (under 8 m) rounded by two routines differs by about an ulp of it,
    # 8.9e-16 m; then r_i + r_j - |d| cancels, so the bound is absolute: 1e-15 m
    assert overlap == pytest.approx(want_overlap, rel=1e-14, abs=1e-15)
    assert crossings == want_crossings


def test_two_disks_that_swap_sides_in_one_step_passed_through():
    radius = np.array([0.1, 0.1])
    before = np.array([[1.0, 1.0], [1.3, 1.0]])
    after = np.array([[1.3, 1.0], [1.0, 1.0]])  # exchanged places: no contact was resolved
    overlap, crossings = pair_check(before, after, radius, np.array([2.0, 2.0]), 1.0)
    assert crossings == 1
    assert overlap == pytest.approx(0.2 - 0.3, rel=1e-14, abs=0)


def test_a_bounce_is_not_a_pass_through():
    radius = np.array([0.1, 0.1])
    before = np.array([[1.0, 1.0], [1.25, 1.0]])
    after = np.array([[0.98, 1.0], [1.27, 1.0]])  # touched and went back
    _, crossings = pair_check(before, after, radius, np.array([2.0, 2.0]), 1.0)
    assert crossings == 0


def test_monitor_measures_wall_penetration_and_escape():
    spec = peer_scene("bouncing-ball")
    check = Check(1.0, np.zeros((1, 2)), 10.0)
    monitor = Monitor(spec, Expectation("test", [check], 1.0), 0.01)
    x = spec.positions.copy()
    v = np.zeros((1, 2))
    monitor.observe(0.0, x, v)
    x[0, 1] = 0.05 - 0.004  # 4 mm into the floor
    monitor.observe(0.5, x, v)
    result = monitor.result()
    assert result["max_overlap_walls"] == pytest.approx(0.004, rel=1e-12, abs=0)
    assert result["max_penetration_per_radius"] == pytest.approx(0.08, rel=1e-12, abs=0)
    # the ball moved from y = 1.55 m to 0.046 m in one step, 1.504 m = 30.08 radii
    assert result["max_step_per_radius"] == pytest.approx(1.504 / 0.05, rel=1e-12, abs=0)
    assert not result["tunnelled"]
    x[0, 1] = -0.01  # the centre below the floor: it went through
    monitor.observe(1.0, x, v)
    result = monitor.result()
    assert result["tunnelled"]
    assert result["bodies_through_walls"] == 1


def test_monitor_propagates_the_nearest_sample_to_the_check_time():
    # a sample 0.004 s before the check, under gravity: v(t) = v + g (t - t_s) is exact in
    # free flight, so a state exact at the sample is exact at the check
    spec = peer_scene("bouncing-ball")
    g = spec.gravity
    check = Check(1.0, np.zeros((1, 2)), 0.0)
    monitor = Monitor(spec, Expectation("test", [check], 1.0), 0.01)
    monitor.observe(0.996, spec.positions, -g * 0.004 * np.ones((1, 1)))
    monitor.observe(1.05, spec.positions, np.array([[0.0, 5.0]]))  # further away: ignored
    assert monitor.result()["velocity_error"] == pytest.approx(0.0, rel=0, abs=1e-15)
