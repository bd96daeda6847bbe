"""Hecker's impulse formula (PHYSICS.md section 2) on rigid bodies and on spheres.

The formula is derived so that the contact points' normal relative velocity obeys Newton's
law, v_AB' . n = -e v_AB . n; an equal and opposite impulse conserves linear momentum; an
impulse through the contact point conserves each body's angular momentum about that point;
e = 1 conserves kinetic energy. Tolerance as in test_law_properties: 1024 eps of the scale.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

import carom
from carom.studies import hecker
from tests.strategies import EPS, Pair, masses, pairs, restitutions, unit_vectors, vectors

TOL = 1024 * EPS


def _spd(rng: np.random.Generator) -> np.ndarray:
    """A random symmetric positive-definite inertia tensor [kg m^2]."""
    a = rng.normal(size=(3, 3))
    return a @ a.T + 0.1 * np.eye(3)


def _cross2(a: np.ndarray, b: np.ndarray) -> float:
    return float(a[0] * b[1] - a[1] * b[0])


@given(seed=st.integers(0, 2**32 - 1), e=restitutions, n=unit_vectors(2), m_a=masses, m_b=masses)
def test_2d_rigid_bodies(seed: int, e: float, n: np.ndarray, m_a: float, m_b: float) -> None:
    rng = np.random.default_rng(seed)
    r_a, r_b = rng.normal(size=2), rng.normal(size=2)
    i_a, i_b = m_a * rng.uniform(0.05, 1), m_b * rng.uniform(0.05, 1)
    v_a, v_b, w_a, w_b = rng.normal(size=2), rng.normal(size=2), rng.normal(), rng.normal()

    def perp(r):
        return np.array([-r[1], r[0]])

    v_ab = v_a + w_a * perp(r_a) - v_b - w_b * perp(r_b)
    j = float(
        hecker.impulse(v_ab, n, m_a, m_b, e=e, r_a=r_a, r_b=r_b, inertia_a=i_a, inertia_b=i_b)
    )
    J = j * n
    v_a2, v_b2 = v_a + J / m_a, v_b - J / m_b
    w_a2, w_b2 = w_a + _cross2(r_a, J) / i_a, w_b - _cross2(r_b, J) / i_b
    v_ab2 = v_a2 + w_a2 * perp(r_a) - v_b2 - w_b2 * perp(r_b)
    scale = float(np.abs(v_ab).sum() + np.abs(v_a).sum() + np.abs(v_b).sum()) * 10
    assert float(v_ab2 @ n) == pytest.approx(-e * float(v_ab @ n), abs=TOL * scale)
    p_scale = m_a * np.abs(v_a).sum() + m_b * np.abs(v_b).sum() + abs(j)
    assert np.abs(m_a * v_a2 + m_b * v_b2 - m_a * v_a - m_b * v_b).max() <= TOL * p_scale

    # angular momentum of A about the contact point: m (-r_a) x v + I w
    def L(m, r, v, i, w):
        return m * _cross2(-r, v) + i * w

    l_scale = (m_a + i_a) * scale * (1 + np.abs(r_a).sum())
    assert L(m_a, r_a, v_a2, i_a, w_a2) == pytest.approx(
        L(m_a, r_a, v_a, i_a, w_a), abs=TOL * l_scale
    )
    if e == 1.0:

        def ke(v1, w1, v2, w2):
            return 0.5 * (m_a * v1 @ v1 + i_a * w1**2 + m_b * v2 @ v2 + i_b * w2**2)

        before = ke(v_a, w_a, v_b, w_b)
        assert ke(v_a2, w_a2, v_b2, w_b2) == pytest.approx(before, rel=TOL * 10, abs=0)


@given(seed=st.integers(0, 2**32 - 1), e=restitutions, n=unit_vectors(3))
def test_3d_rigid_bodies_with_inertia_tensors(seed: int, e: float, n: np.ndarray) -> None:
    rng = np.random.default_rng(seed)
    m_a, m_b = 10 ** rng.uniform(-1, 1), 10 ** rng.uniform(-1, 1)
    i_a, i_b = _spd(rng), _spd(rng)
    r_a, r_b = rng.normal(size=3), rng.normal(size=3)
    v_a, v_b, w_a, w_b = (rng.normal(size=3) for _ in range(4))
    v_ab = v_a + np.cross(w_a, r_a) - v_b - np.cross(w_b, r_b)
    j = float(
        hecker.impulse(v_ab, n, m_a, m_b, e=e, r_a=r_a, r_b=r_b, inertia_a=i_a, inertia_b=i_b)
    )
    J = j * n
    v_a2, v_b2 = v_a + J / m_a, v_b - J / m_b
    w_a2 = w_a + np.linalg.solve(i_a, np.cross(r_a, J))
    w_b2 = w_b - np.linalg.solve(i_b, np.cross(r_b, J))
    v_ab2 = v_a2 + np.cross(w_a2, r_a) - v_b2 - np.cross(w_b2, r_b)
    # the tensors' condition numbers reach ~1e3 here: allow for it in the scale
    scale = float(np.abs(v_ab).sum() + 1) * 1e3
    assert float(v_ab2 @ n) == pytest.approx(-e * float(v_ab @ n), abs=TOL * scale)
    if e == 1.0:

        def ke(v1: np.ndarray, w1: np.ndarray, v2: np.ndarray, w2: np.ndarray) -> float:
            return 0.5 * float(m_a * v1 @ v1 + w1 @ i_a @ w1 + m_b * v2 @ v2 + w2 @ i_b @ w2)

        assert ke(v_a2, w_a2, v_b2, w_b2) == pytest.approx(
            ke(v_a, w_a, v_b, w_b), rel=TOL * 10, abs=0
        )


def test_rod_struck_at_its_end() -> None:
    # Uniform rod, length 1 m, mass 1 kg, I = m L^2 / 12 = 1/12, struck at one end by a
    # fixed wall, moving into it at 1 m/s, e = 1: j = 2 / (1 + (1/2)^2 * 12) = 1/2 N s.
    j = hecker.impulse(
        [0.0, -1.0], [0.0, 1.0], 1.0, math.inf, e=1.0, r_a=[0.5, 0.0], inertia_a=1.0 / 12.0
    )
    assert float(j) == pytest.approx(0.5, rel=4 * EPS, abs=0)


@pytest.mark.parametrize("dim", [2, 3])
@given(data=st.data(), e=restitutions)
def test_contact_reading_is_the_smooth_sphere_law(dim: int, data: st.DataObject, e: float) -> None:
    # For spheres r x n = 0: the rotational terms vanish and j = -(1 + e) mu u, section 1.
    pair: Pair = data.draw(pairs(dim))
    r = carom.collide(*pair.args, e=e)
    h = hecker.collide(*pair.args, e=e, reading="contact")
    scale = float(np.abs(pair.v1).sum() + np.abs(pair.v2).sum()) + 1e-300
    assert np.allclose(h.v1, r.v1, rtol=0, atol=TOL * scale)
    assert np.allclose(h.v2, r.v2, rtol=0, atol=TOL * scale)
    assert h.applied == r.applied


@given(pair=pairs(3), e=restitutions, w1=vectors(3), w2=vectors(3))
def test_contact_reading_leaves_sphere_spins_alone(
    pair: Pair, e: float, w1: np.ndarray, w2: np.ndarray
) -> None:
    # The impulse passes through both centres (r x n = 0): no torque, spins unchanged.
    h = hecker.collide(*pair.args, e=e, w1=w1, w2=w2, radius1=pair.a1, radius2=pair.a2)
    assert h.w1 is not None
    assert h.w2 is not None
    assert np.allclose(h.w1, w1, rtol=0, atol=TOL * (np.abs(w1).sum() + 1))
    assert np.allclose(h.w2, w2, rtol=0, atol=TOL * (np.abs(w2).sum() + 1))


@given(
    n=unit_vectors(3),
    s1=st.floats(-10, 10),
    s2=st.floats(-10, 10),
    m1=masses,
    m2=masses,
    e=restitutions,
)
def test_head_on_reading_is_right_for_head_on_impacts(
    n: np.ndarray, s1: float, s2: float, m1: float, m2: float, e: float
) -> None:
    # Both velocities along the line of centres n: the relative velocity is along n, so the
    # head-on reading picks n (or -n, the same line) and agrees with the law.
    assume(s1 - s2 < -1e-3)  # (v1 - v2) . n < 0: approaching
    args = (n * 0.3, s1 * n, m1, np.zeros(3), s2 * n, m2)
    r = carom.collide(*args, e=e)
    h = hecker.collide(*args, e=e, reading="head-on")
    scale = abs(s1) + abs(s2)
    assert h.applied
    assert r.applied
    assert np.allclose(h.v1, r.v1, rtol=0, atol=TOL * scale)
    assert np.allclose(h.v2, r.v2, rtol=0, atol=TOL * scale)


def test_head_on_reading_is_wrong_for_a_cut_shot() -> None:
    # Billiard cut shot, equal masses, e = 1, impact parameter a: the true law sends ball 2
    # along the line of centres (30 degrees off the cue line) and ball 1 off at 90 degrees to
    # it; the head-on reading stops ball 1 and sends ball 2 straight along the cue line.
    x1, x2 = [-math.sqrt(3) * 0.1, -0.1], [0.0, 0.0]
    h = hecker.collide(x1, [1.0, 0.0], 1.0, x2, [0.0, 0.0], 1.0, e=1.0, reading="head-on")
    r = carom.collide(x1, [1.0, 0.0], 1.0, x2, [0.0, 0.0], 1.0, e=1.0)
    assert np.allclose(h.v1, [0.0, 0.0], atol=4 * EPS)
    assert np.allclose(h.v2, [1.0, 0.0], atol=4 * EPS)
    # true answer: v2' = (v1 . n) n with n at 30 degrees: |v2'| = cos 30, v1' . v2' = 0
    assert float(np.hypot(*r.v2)) == pytest.approx(math.sqrt(3) / 2, rel=4 * EPS, abs=0)
    assert abs(float(r.v1 @ r.v2)) < 4 * EPS
