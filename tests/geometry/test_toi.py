"""Times of impact for bodies that touch and part slowly while pulled back.

A ball at a floor, or on a ball resting on the floor, that leaves it slower than round-off can
resolve must still be predicted to come back; told "never" (INF), it fell through the floor
(a Galton board's balls ended 7 cm below it) or through the ball beneath.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from carom.geometry.toi import INF, first_root_quartic, toi_gap

G = 9.81  # m/s^2
EPS = float(np.finfo(np.float64).eps)


@pytest.mark.parametrize("d0", [0.0, -1.4e-17, -1e-12])
@pytest.mark.parametrize("u", [3.8e-15, 1e-6, 0.1])
def test_a_body_leaving_a_floor_comes_back_after_2u_over_g(d0: float, u: float) -> None:
    # d(t) = d0 + u t - g t^2 / 2 is back at d0 after 2 u / g (closed form); with d0 < 0
    # and u < sqrt(2 g |d0|) the gap never opens, which once gave INF
    assert toi_gap(d0, u, -G) == pytest.approx(2 * u / G, rel=1e-15, abs=0)


def test_a_body_leaving_a_floor_without_gravity_never_comes_back() -> None:
    assert toi_gap(-1e-17, 1e-3, 0.0) == INF


@pytest.mark.parametrize("t_max", [10.0, INF])
@pytest.mark.parametrize("overlap", [0.0, 1e-17, 1e-13])
@pytest.mark.parametrize("u", [3.8e-15, 2.4e-3, 0.5])
def test_a_ball_bouncing_on_a_resting_ball_comes_back(
    overlap: float, u: float, t_max: float
) -> None:
    # Ball 1 on top of ball 2 (at rest, static or supported), touching up to `overlap`, moving
    # up at u under g. f(t) = |r(t)|^2 - R^2 with r(t) = (0, R - overlap + u t - g t^2 / 2):
    # back at its start height after 2 u / g (closed form). With no horizon (t_max = INF: the
    # resting ball's own prediction, which has no shell to leave) the search once bisected
    # towards infinity and found nothing, and the upper ball sank into the lower one.
    R = 0.016
    r0 = R - overlap
    c4, c3, c2, c1 = G * G / 4, -u * G, u * u - r0 * G, 2 * r0 * u
    c0 = r0 * r0 - R * R
    t = first_root_quartic(c4, c3, c2, c1, c0, t_max)
    # the root is polished to round-off even when c0 cancels: measured at most 1 eps off
    assert t == pytest.approx(2 * u / G, rel=16 * EPS, abs=0)


@pytest.mark.parametrize("t_max", [10.0, INF])
def test_a_ball_falling_onto_a_resting_ball_meets_it(t_max: float) -> None:
    # from h above contact, falling at speed w: h - w t - g t^2 / 2 = 0 (closed form), seen
    # by either ball (the resting one has no horizon)
    R, h, w = 0.016, 0.3, 0.7
    r0 = R + h
    c4, c3, c2, c1 = G * G / 4, w * G, w * w - r0 * G, -2 * r0 * w
    t = first_root_quartic(c4, c3, c2, c1, r0 * r0 - R * R, t_max)
    expected = 2 * h / (w + math.sqrt(w * w + 2 * G * h))
    assert t == pytest.approx(expected, rel=16 * EPS, abs=0)


def test_touching_and_closing_is_now_and_parting_for_good_is_never() -> None:
    assert first_root_quartic(1.0, 0.0, 0.0, -1.0, -1e-17, 10.0) == 0.0
    # parting with nothing pulling back (f grows for ever)
    assert first_root_quartic(0.0, 0.0, 1.0, 1.0, 0.0, 10.0) == INF
    assert first_root_quartic(0.0, 0.0, 1.0, 1.0, 0.0, INF) == INF
    assert first_root_quartic(0.0, 0.0, 0.0, 0.0, 1.0, INF) == INF  # apart, nothing moves
