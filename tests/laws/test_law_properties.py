"""Property tests of the two-body laws (PHYSICS.md sections 1 and 3), in 2D and 3D.

Random masses 1e-3 to 1e3 kg (mass ratios to 1e6), velocities to 10 m/s, spins to 50 rad/s,
radii 0.01 to 1 m, any normal, e in [0, 1], beta in [-1, 1].

Tolerances. Momentum: the issue's 1e-12 relative. Everything else: every output is a few
dozen float64 operations on inputs of size ``scale``, so its error is a few dozen eps times
``scale``; ``TOL = 1024 eps`` (2.3e-13) covers the worst case with the 1e6 mass ratio (where
``v' = v + J/m`` subtracts quantities up to twice ``scale``) and is still nine orders of
magnitude below any real mistake in a law.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given
from hypothesis import strategies as st

import carom
from carom.laws.spheres import CollisionResult
from tests.strategies import (
    EPS,
    Pair,
    betas,
    pairs,
    random_rotation,
    restitutions,
    spins,
    vectors,
)

TOL = 1024 * EPS
DIMS = [2, 3]


def _speed_scale(pair: Pair, *spin: np.ndarray | float) -> float:
    scale = float(np.abs(pair.v1).sum() + np.abs(pair.v2).sum())
    for a, w in zip((pair.a1, pair.a2), spin, strict=False):
        scale += a * float(np.abs(w).sum())
    return scale + 1e-300


def _contact_velocity(pair: Pair, r: CollisionResult | None, w1, w2) -> np.ndarray:  # type: ignore[no-untyped-def]
    """g = v1 - v2 - (a1 w1 + a2 w2) x n, before (r None) or after the impact."""
    v1, v2 = (pair.v1, pair.v2) if r is None else (r.v1, r.v2)
    if r is not None:
        w1, w2 = r.w1, r.w2
    spin = pair.a1 * np.asarray(w1) + pair.a2 * np.asarray(w2)
    n = pair.n
    turn = spin * np.array([-n[1], n[0]]) if n.size == 2 else np.cross(spin, n)
    return v1 - v2 - turn


def _split(g: np.ndarray, n: np.ndarray) -> tuple[float, np.ndarray]:
    """(g . n, tangential part of g)."""
    gn = float(g @ n)
    return gn, g - gn * n


def _approach(pair: Pair) -> float:
    """u = (v1 - v2) . n: exactly the normal part of g (spin adds (w x n) . n = 0), without
    the round-off of the spin term that ``g . n`` picks up."""
    return float((pair.v1 - pair.v2) @ pair.n)


# --- smooth spheres -------------------------------------------------------------------------


@pytest.mark.parametrize("dim", DIMS)
@given(data=st.data(), e=restitutions)
def test_smooth_conserves_momentum(dim: int, data: st.DataObject, e: float) -> None:
    # J on body 1, -J on body 2: m1 v1' + m2 v2' = m1 v1 + m2 v2 exactly in real arithmetic.
    pair = data.draw(pairs(dim))
    r = carom.collide(*pair.args, e=e)
    p_before = pair.m1 * pair.v1 + pair.m2 * pair.v2
    p_after = pair.m1 * r.v1 + pair.m2 * r.v2
    scale = (
        pair.m1 * np.abs(pair.v1).sum() + pair.m2 * np.abs(pair.v2).sum() + np.abs(r.impulse).sum()
    )
    assert np.abs(p_after - p_before).max() <= 1e-12 * scale


@pytest.mark.parametrize("dim", DIMS)
@given(data=st.data(), e=restitutions)
def test_smooth_newton_restitution_and_tangential_components(
    dim: int, data: st.DataObject, e: float
) -> None:
    # u' = -e u along n; the impulse is along n, so each body's tangential velocity is kept.
    pair = data.draw(pairs(dim))
    r = carom.collide(*pair.args, e=e)
    n = pair.n
    u = float((pair.v1 - pair.v2) @ n)
    u_after = float((r.v1 - r.v2) @ n)
    scale = _speed_scale(pair)
    assert r.applied == (u < 0)
    assert u_after == pytest.approx(-e * u if u < 0 else u, abs=TOL * scale)
    for before, after in ((pair.v1, r.v1), (pair.v2, r.v2)):
        tangential = (after - before) - float((after - before) @ n) * n
        assert np.abs(tangential).max() <= TOL * scale


@pytest.mark.parametrize("dim", DIMS)
@given(data=st.data(), e=restitutions)
def test_smooth_energy_loss_formula(dim: int, data: st.DataObject, e: float) -> None:
    # dKE = 1/2 mu (1 - e^2) u^2 (PHYSICS.md section 1); ke_lost is that closed form and the
    # kinetic energies computed from the velocities must differ by it.
    pair = data.draw(pairs(dim))
    r = carom.collide(*pair.args, e=e)
    u = float((pair.v1 - pair.v2) @ pair.n)
    mu = pair.m1 * pair.m2 / (pair.m1 + pair.m2)
    expected = 0.5 * mu * (1 - e * e) * u * u if u < 0 else 0.0
    ke = float(r.ke_before)
    assert r.ke_lost == pytest.approx(expected, rel=TOL, abs=1e-300)
    assert float(r.ke_before - r.ke_after) == pytest.approx(expected, abs=TOL * ke + 1e-300)
    assert r.ke_lost >= 0.0


@pytest.mark.parametrize("dim", DIMS)
@given(data=st.data(), e=restitutions)
def test_swapping_the_bodies_swaps_the_result(dim: int, data: st.DataObject, e: float) -> None:
    # Relabelling 1 <-> 2 flips n and the impulse and swaps the velocities.
    pair = data.draw(pairs(dim))
    r = carom.collide(*pair.args, e=e)
    s = carom.collide(pair.x2, pair.v2, pair.m2, pair.x1, pair.v1, pair.m1, e=e)
    scale = _speed_scale(pair)
    assert np.allclose(s.v1, r.v2, rtol=0, atol=TOL * scale)
    assert np.allclose(s.v2, r.v1, rtol=0, atol=TOL * scale)
    assert np.allclose(s.impulse, -r.impulse, rtol=0, atol=TOL * (np.abs(r.impulse).sum() + 1e-300))
    assert s.applied == r.applied


@pytest.mark.parametrize("dim", DIMS)
@given(data=st.data(), e=restitutions, seed=st.integers(0, 2**32 - 1))
def test_rotation_invariance(dim: int, data: st.DataObject, e: float, seed: int) -> None:
    # The law is built from dot products and n: rotating every input rotates every output.
    pair = data.draw(pairs(dim))
    R = random_rotation(dim, seed)
    r = carom.collide(*pair.args, e=e)
    s = carom.collide(R @ pair.x1, R @ pair.v1, pair.m1, R @ pair.x2, R @ pair.v2, pair.m2, e=e)
    scale = _speed_scale(pair)
    assume(abs(float((pair.v1 - pair.v2) @ pair.n)) > 1e-9 * scale)  # not grazing: same verdict
    assert np.allclose(s.v1, R @ r.v1, rtol=0, atol=TOL * scale)
    assert np.allclose(s.v2, R @ r.v2, rtol=0, atol=TOL * scale)


@pytest.mark.parametrize("dim", DIMS)
@given(data=st.data(), e=restitutions)
def test_galilean_boost_invariance(dim: int, data: st.DataObject, e: float) -> None:
    # Only v1 - v2 enters J, so adding V to both velocities adds V to both results.
    pair = data.draw(pairs(dim))
    boost = data.draw(vectors(dim))
    r = carom.collide(*pair.args, e=e)
    s = carom.collide(pair.x1, pair.v1 + boost, pair.m1, pair.x2, pair.v2 + boost, pair.m2, e=e)
    scale = _speed_scale(pair) + float(np.abs(boost).sum())
    assert np.allclose(s.v1, r.v1 + boost, rtol=0, atol=TOL * scale)
    assert np.allclose(s.v2, r.v2 + boost, rtol=0, atol=TOL * scale)
    # ke_lost ~ mu u^2, and forming v + V already rounds u by up to eps |V|: the bound is
    # absolute, mu * scale^2 * TOL (a boost of 1 m/s erases a relative speed of 1e-90 m/s)
    mu = pair.m1 * pair.m2 / (pair.m1 + pair.m2)
    assert s.ke_lost == pytest.approx(float(r.ke_lost), rel=TOL, abs=TOL * mu * scale**2)


# --- rough spheres ----------------------------------------------------------------------------


@pytest.mark.parametrize("dim", DIMS)
@given(data=st.data(), e=restitutions, beta=betas)
def test_rough_restitution_laws_and_energy(
    dim: int, data: st.DataObject, e: float, beta: float
) -> None:
    # Constant tangential restitution (PHYSICS.md section 3): g_n' = -e g_n, g_t' = -beta g_t,
    # dKE = 1/2 mu (1 - e^2) g_n^2 + 1/2 mu_t (1 - beta^2) |g_t|^2 >= 0 (rotational KE counted).
    pair = data.draw(pairs(dim))
    w1, w2 = data.draw(spins(dim)), data.draw(spins(dim))
    r = carom.collide(*pair.args, e=e, beta=beta, w1=w1, w2=w2, radius1=pair.a1, radius2=pair.a2)
    _, gt = _split(_contact_velocity(pair, None, w1, w2), pair.n)
    gn_after, gt_after = _split(_contact_velocity(pair, r, None, None), pair.n)
    gn = _approach(pair)
    scale = _speed_scale(pair, w1, w2)
    if gn < 0:
        assert gn_after == pytest.approx(-e * gn, abs=TOL * scale)
        assert np.allclose(gt_after, -beta * gt, rtol=0, atol=TOL * scale)
        q = 0.4 if dim == 3 else 0.5
        mu = pair.m1 * pair.m2 / (pair.m1 + pair.m2)
        mu_t = 1.0 / ((1 + 1 / q) / pair.m1 + (1 + 1 / q) / pair.m2)  # = mu q / (1 + q)
        expected = 0.5 * mu * (1 - e * e) * gn * gn + 0.5 * mu_t * (1 - beta**2) * (gt @ gt)
        # 1 - beta**2 here is itself off by up to 2 eps, i.e. by 2 eps * (KE of g_t) absolute
        ke = float(r.ke_before)
        assert r.ke_lost == pytest.approx(expected, rel=TOL, abs=8 * EPS * ke + 1e-300)
    ke = float(r.ke_before)
    assert float(r.ke_before - r.ke_after) == pytest.approx(float(r.ke_lost), abs=TOL * ke)
    assert float(r.ke_after) <= ke * (1 + TOL)


@pytest.mark.parametrize("dim", DIMS)
@given(data=st.data(), e=restitutions, beta=betas)
def test_rough_conserves_angular_momentum_about_contact(
    dim: int, data: st.DataObject, e: float, beta: float
) -> None:
    # The impulse acts at the contact point c, so each body's angular momentum about c,
    # L = m (x - c) x v + I w, is unchanged, and linear momentum is conserved.
    pair = data.draw(pairs(dim))
    w1, w2 = data.draw(spins(dim)), data.draw(spins(dim))
    r = carom.collide(*pair.args, e=e, beta=beta, w1=w1, w2=w2, radius1=pair.a1, radius2=pair.a2)
    c = pair.x1 - pair.a1 * pair.n
    q = 0.4 if dim == 3 else 0.5
    for x, m, a, v, w, v_after, w_after in (
        (pair.x1, pair.m1, pair.a1, pair.v1, w1, r.v1, r.w1),
        (pair.x2, pair.m2, pair.a2, pair.v2, w2, r.v2, r.w2),
    ):

        def L(vel: np.ndarray, spin, x=x, m=m, a=a) -> np.ndarray:  # type: ignore[no-untyped-def]
            arm = x - c
            orbital = (
                m * (arm[0] * vel[1] - arm[1] * vel[0]) if dim == 2 else m * np.cross(arm, vel)
            )
            return orbital + q * m * a * a * np.asarray(spin)

        scale = (
            m
            * (np.abs(v).sum() + a * np.abs(w).sum() + np.abs(v_after).sum())
            * (a + pair.a1 + pair.a2)
        )
        assert np.allclose(L(v_after, w_after), L(v, w), rtol=0, atol=TOL * scale)


@pytest.mark.parametrize("dim", DIMS)
@given(data=st.data(), e=restitutions, mu_f=st.floats(0.0, 2.0), beta0=betas)
def test_walton_obeys_coulomb_and_never_gains_energy(
    dim: int, data: st.DataObject, e: float, mu_f: float, beta0: float
) -> None:
    # Walton: beta = min(beta0, -1 + mu_f (1 + e)(mu/mu_t)|g_n|/|g_t|) so |J_t| <= mu_f |J_n|;
    # g_t' = -beta g_t with that beta; the energy lost is never negative.
    pair = data.draw(pairs(dim))
    w1, w2 = data.draw(spins(dim)), data.draw(spins(dim))
    r = carom.collide(
        *pair.args, e=e, friction=mu_f, beta0=beta0, w1=w1, w2=w2, radius1=pair.a1, radius2=pair.a2
    )
    n = pair.n
    _, gt = _split(_contact_velocity(pair, None, w1, w2), n)
    _, gt_after = _split(_contact_velocity(pair, r, None, None), n)
    gn = _approach(pair)
    scale = _speed_scale(pair, w1, w2)
    J = np.asarray(r.impulse)
    Jn = float(J @ n)
    Jt = J - Jn * n
    assert np.sqrt(Jt @ Jt) <= mu_f * abs(Jn) * (1 + TOL) + TOL * np.abs(J).sum() + 1e-300
    assert r.beta is not None
    assert -1.0 <= r.beta <= beta0
    if gn < 0:
        assert np.allclose(gt_after, -float(r.beta) * gt, rtol=0, atol=TOL * scale)
    ke = float(r.ke_before)
    assert float(r.ke_after) <= ke * (1 + TOL)
    assert r.ke_lost >= 0


@pytest.mark.parametrize("dim", DIMS)
@given(data=st.data(), e=restitutions, beta0=betas)
def test_walton_limits(dim: int, data: st.DataObject, e: float, beta0: float) -> None:
    # friction = 0: no tangential impulse, the smooth law. Friction so large that the cap is
    # never reached: the constant-beta law with beta = beta0.
    pair = data.draw(pairs(dim))
    w1, w2 = data.draw(spins(dim)), data.draw(spins(dim))
    kw = {"w1": w1, "w2": w2, "radius1": pair.a1, "radius2": pair.a2}
    scale = _speed_scale(pair, w1, w2)
    frictionless = carom.collide(*pair.args, e=e, friction=0.0, **kw)
    smooth = carom.collide(*pair.args, e=e, **kw)
    assert np.allclose(frictionless.v1, smooth.v1, rtol=0, atol=TOL * scale)
    assert np.allclose(frictionless.w1, smooth.w1, rtol=0, atol=TOL * scale)
    assume(_approach(pair) < -1e-6 * scale)  # a real normal impulse, so a finite friction can stick
    huge = carom.collide(*pair.args, e=e, friction=1e12, beta0=beta0, **kw)
    constant = carom.collide(*pair.args, e=e, beta=beta0, **kw)
    assert huge.beta == beta0  # the cap mu_f ~ 1e12 is never reached: beta0 itself
    assert np.allclose(huge.v1, constant.v1, rtol=0, atol=TOL * scale)
    assert np.allclose(huge.w2, constant.w2, rtol=0, atol=TOL * scale / min(pair.a1, pair.a2))


def test_rough_static_wall_rolls_a_sliding_ball() -> None:
    # A ball sliding without spin on a static floor at speed V, plastic (e = 0) and beta = 0:
    # the contact point stops, so the ball rolls: v' = w' a. Angular momentum about the contact
    # point, m V a = m v' a + (2/5) m a^2 w', with w' = v'/a gives v' = V / (1 + 2/5) = 5V/7.
    V, a = 7.0, 0.5
    # ball above the floor (n = +z), moving along x and slightly into the floor
    r = carom.collide(
        [0.0, 0.0, a],
        [V, 0.0, -1.0],
        1.0,
        [0.0, 0.0, -1.0],
        [0.0, 0.0, 0.0],
        math.inf,
        e=0.0,
        beta=0.0,
        radius1=a,
        radius2=1.0,
    )
    assert r.v1[0] == pytest.approx(5.0, rel=TOL, abs=0)  # 5/7 of 7 m/s
    # rolling: contact point v + w x (-a z) = 0  =>  w_y = v_x / a (right-hand rule)
    assert r.w1 is not None
    assert r.w1[1] == pytest.approx(5.0 / a, rel=TOL, abs=0)
    assert r.v1[2] == pytest.approx(0.0, abs=TOL)
    assert r.w2 is not None
    assert r.w2.tolist() == [0.0, 0.0, 0.0]  # a static body does not turn
