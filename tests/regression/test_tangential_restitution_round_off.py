"""Regressions: the tangential restitution lost digits to cancellation (found by hypothesis)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom

EPS = float(np.finfo(np.float64).eps)


def test_walton_sliding_contact_keeps_coulomb_bound_to_round_off() -> None:
    # |g_t| = 3 m/s >> |g_n| = 7.1e-6 m/s: the cap puts beta at -1 + 8e-6. Computed as
    # -1 + x and then 1 + beta, |J_t| exceeded mu_f |J_n| by 2.6e-12 relative. In the
    # sliding regime |J_t| = mu_f |J_n| exactly, so the two must agree to a few eps.
    x1 = np.array([0.0, -math.sqrt(2.0), math.sqrt(2.0)])
    r = carom.collide(
        x1,
        [0.0, 1e-5, 0.0],
        1.0,
        [0.0, 0.0, 0.0],
        [0.0, 0.0, 0.0],
        1.0,
        e=0.0,
        friction=1.0,
        beta0=0.0,
        w2=[0.0, 0.0, 3.0],
        radius1=1.0,
        radius2=1.0,
    )
    n = x1 / np.linalg.norm(x1)
    j_n = float(r.impulse @ n)
    j_t = float(np.linalg.norm(r.impulse - j_n * n))
    assert j_t == pytest.approx(abs(j_n), rel=8 * EPS, abs=0)


def test_tangential_energy_loss_survives_beta_next_to_one() -> None:
    # beta = 1 - 2^-53: 1 + beta rounds to 2, and (1 + beta)(2 - (1 + beta)) gave 0 for
    # 1 - beta^2 = 2^-52 (approximately). The loss is 1/2 mu_t (1 - beta^2) |g_t|^2 plus the
    # normal part 1/2 mu u^2 (e = 0).
    beta = 1.0 - 2.0**-53
    x1 = [0.0, 0.0624695, 1.99902415]
    v1 = [0.0, -5.0, 0.0]
    r = carom.collide(
        x1, v1, 1.0, [0, 0, 0], [0.0, 0.0, -0.125], 1.0, e=0.0, beta=beta, radius1=1.0, radius2=1.0
    )
    n = np.array(x1) / np.linalg.norm(x1)
    g = np.array(v1) - np.array([0.0, 0.0, -0.125])
    u = float(g @ n)
    g_t = g - u * n
    mu, mu_t = 0.5, 1.0 / (2 * (1 + 1 / 0.4))
    one_minus_beta_squared = (1 - beta) * (1 + beta)  # 2^-53 * (2 - 2^-53), both exact
    expected = 0.5 * mu * u * u + 0.5 * mu_t * one_minus_beta_squared * float(g_t @ g_t)
    assert r.ke_lost == pytest.approx(expected, rel=16 * EPS, abs=0)
    assert 0.5 * mu_t * one_minus_beta_squared * float(g_t @ g_t) > 0  # the part that vanished
