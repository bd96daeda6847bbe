"""The 3D point impulse with inertia tensors and Coulomb friction (carom.laws.rigid_impact)
against closed forms: Hecker's frictionless impulse, a spinning ball landing (the 5/7 rolling
rule when it sticks, the Coulomb slide when it does not), and over random bodies the laws of
impact: momentum and angular momentum about the contact point kept, energy never gained.

Tolerances: a few dozen float64 operations on numbers of order 1: 1e-12 relative.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from carom.laws.point_impulse import impulse as hecker
from carom.laws.rigid_impact import collision_matrix, point_impulse

REL = 1e-12


def _random_body(rng: np.random.Generator) -> tuple[float, np.ndarray, np.ndarray]:
    """A mass [kg], a world-frame inverse inertia tensor [1/(kg m^2)] and an offset r [m]."""
    mass = rng.uniform(0.2, 5.0)
    axes, _ = np.linalg.qr(rng.normal(size=(3, 3)))
    moments = mass * rng.uniform(0.01, 1.0, size=3)
    inertia = axes @ np.diag(moments) @ axes.T
    return mass, np.linalg.inv(inertia), rng.normal(size=3) * 0.5


def _point_velocity(v: np.ndarray, w: np.ndarray, r: np.ndarray) -> np.ndarray:
    return v + np.cross(w, r)


@settings(max_examples=100, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), e=st.floats(0.0, 1.0))
def test_frictionless_it_is_heckers_impulse(seed: int, e: float) -> None:
    # with mu = 0 the impulse is j n, j = -(1 + e) u.n / (n . K n): Hecker's formula
    rng = np.random.default_rng(seed)
    ma, ia, ra = _random_body(rng)
    mb, ib, rb = _random_body(rng)
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    u = rng.normal(size=3) - 2.0 * n  # approaching
    if u @ n >= 0.0:
        return
    p = point_impulse(u, n, collision_matrix(1 / ma, ia, ra, 1 / mb, ib, rb), e, 0.0)
    j = hecker(
        u, n, ma, mb, e=e, r_a=ra, r_b=rb, inertia_a=np.linalg.inv(ia), inertia_b=np.linalg.inv(ib)
    )
    assert p == pytest.approx(float(j) * n, rel=REL, abs=REL * abs(float(j)))


def _ball_on_floor(
    vx: float, vz: float, wy: float, e: float, mu: float
) -> tuple[np.ndarray, np.ndarray]:
    """A ball (R = 0.1 m, m = 2 kg, I = 2/5 m R^2) landing on a static floor: its velocity and
    spin after."""
    radius, mass = 0.1, 2.0
    inertia = 0.4 * mass * radius**2
    r = np.array([0.0, 0.0, -radius])  # centre to contact
    n = np.array([0.0, 0.0, 1.0])  # from the floor (B) to the ball (A)
    v = np.array([vx, 0.0, -vz])
    w = np.array([0.0, wy, 0.0])
    k = collision_matrix(1 / mass, np.eye(3) / inertia, r, 0.0, np.zeros((3, 3)), np.zeros(3))
    p = point_impulse(_point_velocity(v, w, r), n, k, e, mu)
    return v + p / mass, w + np.cross(r, p) / inertia


@pytest.mark.parametrize(("vx", "wy"), [(2.0, 0.0), (2.0, 30.0), (-1.0, -5.0), (0.0, 40.0)])
def test_a_ball_that_sticks_leaves_by_the_rolling_rule(vx: float, wy: float) -> None:
    # the contact point's slip u = v_x - R w_y stops: v_x' = (5 v_x + 2 R w_y)/7, and it rolls
    # (v_x' = R w_y'); the vertical speed becomes e v_z
    radius, e = 0.1, 0.6
    v, w = _ball_on_floor(vx, 3.0, wy, e, mu=10.0)
    expected = (5 * vx + 2 * radius * wy) / 7
    assert v[0] == pytest.approx(expected, rel=REL, abs=1e-13)
    assert v[0] == pytest.approx(radius * w[1], rel=REL, abs=1e-13)
    assert v[2] == pytest.approx(e * 3.0, rel=REL)
    assert v[1] == 0.0


def test_a_ball_that_slides_loses_mu_times_its_normal_impulse() -> None:
    # slip u = v_x - R w_y = 2 > 0 and little friction: the tangent impulse is -mu P_n with
    # P_n = m (1 + e) v_z, so v_x' = v_x - mu (1 + e) v_z and w_y' = w_y + R mu P_n / I
    radius, mass, e, mu, vz = 0.1, 2.0, 0.6, 0.1, 3.0
    v, w = _ball_on_floor(2.0, vz, 0.0, e, mu)
    assert v[0] == pytest.approx(2.0 - mu * (1 + e) * vz, rel=REL)
    normal = mass * (1 + e) * vz
    assert w[1] == pytest.approx(radius * mu * normal / (0.4 * mass * radius**2), rel=REL)
    assert v[2] == pytest.approx(e * vz, rel=REL)


@settings(max_examples=200, deadline=None)
@given(
    seed=st.integers(0, 2**32 - 1),
    e=st.floats(0.0, 1.0),
    mu=st.one_of(st.just(0.0), st.floats(1e-3, 2.0)),
)
def test_impacts_keep_momentum_and_never_gain_energy(seed: int, e: float, mu: float) -> None:
    # two free bodies meet at a point: P on A and -P on B keep the total momentum; both
    # impulses act at the same point, so angular momentum about it is kept too; the kinetic
    # energy never rises
    rng = np.random.default_rng(seed)
    ma, ia, ra = _random_body(rng)
    mb, ib, rb = _random_body(rng)
    va, wa, vb, wb = rng.normal(size=(4, 3))
    n = rng.normal(size=3)
    n /= np.linalg.norm(n)
    u = _point_velocity(va, wa, ra) - _point_velocity(vb, wb, rb)
    if u @ n >= -1e-3:
        return
    p = point_impulse(u, n, collision_matrix(1 / ma, ia, ra, 1 / mb, ib, rb), e, mu)
    va2, vb2 = va + p / ma, vb - p / mb
    wa2, wb2 = wa + ia @ np.cross(ra, p), wb - ib @ np.cross(rb, p)
    la, lb = np.linalg.inv(ia), np.linalg.inv(ib)
    assert ma * va2 + mb * vb2 == pytest.approx(
        ma * va + mb * vb, abs=1e-12 * (1 + np.abs(p).max())
    )

    # angular momentum about the contact point x_c: centres at x_c - r
    def spin(
        m: float, v: np.ndarray, w: np.ndarray, r: np.ndarray, inertia: np.ndarray
    ) -> np.ndarray:
        return m * np.cross(-r, v) + inertia @ w

    before = spin(ma, va, wa, ra, la) + spin(mb, vb, wb, rb, lb)
    after = spin(ma, va2, wa2, ra, la) + spin(mb, vb2, wb2, rb, lb)
    assert after == pytest.approx(before, abs=1e-10 * (1 + np.abs(before).max()))
    energy = lambda m, v, w, inertia: 0.5 * m * v @ v + 0.5 * w @ inertia @ w  # noqa: E731
    e0 = energy(ma, va, wa, la) + energy(mb, vb, wb, lb)
    e1 = energy(ma, va2, wa2, la) + energy(mb, vb2, wb2, lb)
    assert e1 <= e0 * (1 + 1e-12) + 1e-12
    # the tangent impulse stays in the cone; strictly inside it the contact stuck: the point
    # leaves at exactly -e times its approach speed, with no slip
    pn = p @ n
    tangent = float(np.linalg.norm(p - pn * n))
    assert tangent <= mu * pn * (1 + 1e-9) + 1e-15
    if tangent < mu * pn * (1 - 1e-6):
        u2 = _point_velocity(va2, wa2, ra) - _point_velocity(vb2, wb2, rb)
        assert u2 == pytest.approx(-e * (u @ n) * n, abs=1e-9 * np.abs(u).max())
