"""Closed-form consequences of the smooth-sphere law (PHYSICS.md section 1).

Each test derives its expected value in a comment. Tolerances: a handful of float64 operations
each rounded to half an ulp, so errors of a few eps times the velocity scale; ``64 * eps``
leaves an order of magnitude of room and still catches any real mistake (which shows at the
percent level or worse).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import carom
from carom.reference.exact import smooth_exact
from tests.strategies import EPS, Pair, masses, pairs, restitutions, unit_vectors, vectors

TOL = 64 * EPS


def test_equal_masses_head_on_elastic_exchange_velocities() -> None:
    # 1D elastic collision of equal masses: v1' = v2, v2' = v1 (momentum and energy
    # conservation have this as their only non-trivial solution). The normal (-1, 0, 0) is
    # exact in binary, so the exchange is exact to the bit.
    r = carom.collide([0, 0, 0], [3.0, 0, 0], 2.0, [0.5, 0, 0], [-1.25, 0, 0], 2.0, e=1.0)
    assert r.v1.tolist() == [-1.25, 0.0, 0.0]
    assert r.v2.tolist() == [3.0, 0.0, 0.0]
    assert r.applied is True
    assert r.ke_lost == 0.0


@pytest.mark.parametrize("e", [0.0, 0.3, 0.5, 1.0])
@pytest.mark.parametrize(("m1", "m2"), [(1.0, 3.0), (5.0, 0.2), (2.0, 2.0)])
def test_head_on_matches_textbook_1d_formula(m1: float, m2: float, e: float) -> None:
    # Textbook 1D impact: v1' = ((m1 - e m2) v1 + (1 + e) m2 v2) / (m1 + m2) and
    # v2' = ((m2 - e m1) v2 + (1 + e) m1 v1) / (m1 + m2).
    v1, v2 = 2.0, -0.75
    r = carom.collide([-1.0, 0.0], [v1, 0.0], m1, [0.0, 0.0], [v2, 0.0], m2, e=e)
    expect1 = ((m1 - e * m2) * v1 + (1 + e) * m2 * v2) / (m1 + m2)
    expect2 = ((m2 - e * m1) * v2 + (1 + e) * m1 * v1) / (m1 + m2)
    assert r.v1[0] == pytest.approx(expect1, abs=TOL * abs(v1 - v2))
    assert r.v2[0] == pytest.approx(expect2, abs=TOL * abs(v1 - v2))
    assert r.v1[1] == 0.0
    assert r.v2[1] == 0.0


@given(n=unit_vectors(3), speed=st.floats(0.1, 10.0), m=masses)
def test_equal_masses_one_at_rest_leave_at_right_angles(
    n: np.ndarray, speed: float, m: float
) -> None:
    # Equal masses, e = 1, target at rest: momentum gives v1 = v1' + v2' and energy gives
    # |v1|^2 = |v1'|^2 + |v2'|^2, so v1' . v2' = 0: the spheres leave at 90 degrees.
    v1 = -speed * n + np.array([0.3, -0.2, 0.1])  # any velocity that approaches along n
    if v1 @ n >= 0:
        v1 = -v1
    r = carom.collide(n, v1, m, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], m, e=1.0)
    scale = float(v1 @ v1)
    assert abs(float(r.v1 @ r.v2)) <= TOL * scale
    # and the struck sphere leaves along the line of centres (it only ever receives -J)
    assert np.allclose(np.cross(r.v2, n), 0.0, atol=TOL * speed * 10)


@given(pair=pairs(2), e_unused=restitutions)
def test_plastic_impact_leaves_equal_normal_velocities(pair: Pair, e_unused: float) -> None:
    # e = 0: u' = -e u = 0, so both spheres have the same velocity component along n.
    r = carom.collide(*pair.args, e=0.0)
    scale = float(np.abs(pair.v1).sum() + np.abs(pair.v2).sum())
    if r.applied:
        assert abs(float(r.v1 @ pair.n) - float(r.v2 @ pair.n)) <= TOL * scale


@given(n=unit_vectors(3), v1=vectors(3), e=restitutions, m1=masses)
def test_static_wall_mirrors_normal_component_scaled_by_e(
    n: np.ndarray, v1: np.ndarray, e: float, m1: float
) -> None:
    # m2 = inf: mu = m1, J = -(1 + e) m1 u n, so v1' = v1 - (1 + e) u n: the normal
    # component is reversed and scaled by e, the tangential component is kept.
    u = float(v1 @ n)
    r = carom.collide(n, v1, m1, [0.0, 0.0, 0.0], [0.0, 0.0, 0.0], math.inf, e=e)
    expect = v1 - (1 + e) * u * n if u < 0 else v1
    assert np.allclose(r.v1, expect, rtol=0, atol=TOL * (float(np.abs(v1).sum()) + 1e-300))
    assert r.v2.tolist() == [0.0, 0.0, 0.0]
    assert r.applied == (u < 0)


def test_separating_pair_gets_no_impulse() -> None:
    # (v1 - v2) . n > 0: the gap is opening; nothing happens.
    r = carom.collide([0.0, 0.0], [-1.0, 0.3], 1.0, [0.2, 0.0], [1.0, 0.0], 2.0, e=0.5)
    assert r.applied is False
    assert r.v1.tolist() == [-1.0, 0.3]
    assert r.v2.tolist() == [1.0, 0.0]
    assert r.impulse.tolist() == [0.0, 0.0]
    assert r.ke_lost == 0.0


@given(pair=pairs(3), e=restitutions)
def test_agrees_with_exact_rational_arithmetic(pair: Pair, e: float) -> None:
    # The exact answer is rational in the float inputs (carom/reference/exact.py); carom's
    # float64 evaluation must match it to round-off of the velocity scale.
    r = carom.collide(*pair.args, e=e)
    v1x, v2x, ke_lost = smooth_exact(pair.x1, pair.v1, pair.m1, pair.x2, pair.v2, pair.m2, e)
    scale = float(np.abs(pair.v1).sum() + np.abs(pair.v2).sum())
    assert np.allclose(r.v1, v1x, rtol=0, atol=TOL * scale)
    assert np.allclose(r.v2, v2x, rtol=0, atol=TOL * scale)
    ke = float(r.ke_before)
    assert r.ke_lost == pytest.approx(ke_lost, abs=TOL * ke + 1e-300)


def test_separation_speed_is_e_times_approach_speed() -> None:
    # "How far they rebound": the gap opens at e |u| (PHYSICS.md section 1).
    r = carom.collide([-0.16, -0.12], [3.0, 0.0], 1.0, [0.0, 0.0], [1.0, 0.0], 1.0, e=0.5)
    # u = (2, 0) . (-0.8, -0.6) = -1.6, so approach 1.6 m/s and separation 0.8 m/s
    assert r.approach_speed == pytest.approx(1.6, abs=TOL)
    assert r.separation_speed == pytest.approx(0.8, abs=TOL)
    assert r.relative_speed_after == pytest.approx(float(np.hypot(*(r.v1 - r.v2))), abs=TOL)
