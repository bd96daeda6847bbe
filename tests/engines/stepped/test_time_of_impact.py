"""The exact impacts' search for a time of impact, shared by both dimensions
(:mod:`carom.engines.stepped.impacts`): conservative advancement, fed the gap of a closed form.

The gap between two points closing at a constant speed ``v`` is ``d(t) = d0 - v t``: it
touches at ``t* = d0 / v``. Advancing by ``d / v`` lands on ``t*`` in one step (round-off
aside); a bound that underestimates the speed overshoots, and the bisection brings the time
back to within the tolerance ``tol`` of touching (|d| <= tol, so |t - t*| <= tol / v).
"""

from __future__ import annotations

import math

import pytest

from carom.engines.stepped.impacts import BISECTIONS, MAX_ITERATIONS, advance, search


def _search(gap, closing, tol, horizon, parting=False):
    """Run the search on ``gap(t)`` with the closing-speed bound ``closing(t)``; return the
    time and how many gaps it took."""
    state = search(parting)
    t = 0.0
    for taken in range(1, MAX_ITERATIONS + BISECTIONS + 2):
        done, t, state = advance(state, t, gap(t), closing(t), tol, horizon)
        if done:
            return t, taken
    raise AssertionError("the search did not end")


@pytest.mark.parametrize(("d0", "v"), [(1.0, 2.0), (0.3, 7.0), (5.0, 0.25)])
def test_a_true_bound_lands_on_the_touch(d0: float, v: float) -> None:
    tol = 1e-12
    t, taken = _search(lambda t: d0 - v * t, lambda t: v, tol, horizon=10.0 * d0 / v)
    assert abs(t - d0 / v) <= tol / v + 4e-16 * d0 / v  # round-off of d0 / v and d0 - v t
    assert taken <= 3


def test_an_underestimated_speed_overshoots_and_bisects_back_within_tol() -> None:
    d0, v, tol = 1.0, 2.0, 1e-9
    # the bound says a third of the speed: the first step goes to 3 t*, past the touch
    t, taken = _search(lambda t: d0 - v * t, lambda t: v / 3.0, tol, horizon=10.0)
    assert abs(d0 - v * t) <= tol  # within tol of touching, from either side
    assert taken <= 2 + BISECTIONS


def test_a_gap_that_opens_or_a_late_touch_is_no_impact() -> None:
    tol = 1e-9
    # parting: the bound on closing is negative from the start
    assert _search(lambda t: 1.0 + t, lambda t: -1.0, tol, horizon=5.0)[0] == -1.0
    # the touch comes after the horizon
    assert _search(lambda t: 1.0 - t, lambda t: 1.0, tol, horizon=0.5)[0] == -1.0


def test_a_pair_just_hit_apart_must_part_before_it_can_touch_again() -> None:
    # Touching at t = 0 and parting: not an impact until the gap has opened beyond tol, then
    # comes back (d = t (1 - t): open until t = 1, touching again at t = 1).
    tol = 1e-6
    t, _ = _search(lambda t: t * (1.0 - t), lambda t: 1.0, tol, horizon=2.0, parting=True)
    assert abs(t * (1.0 - t)) <= tol
    assert t > 0.5
    # without parting, the contact it starts in is the impact
    assert _search(lambda t: t * (1.0 - t), lambda t: 1.0, tol, 2.0)[0] == 0.0


def test_a_search_that_starts_overlapping_ends_at_once_on_its_start() -> None:
    # Overlapping by more than tol at t = 0: there is no safe time before it to bisect back
    # to, so the safe end, t = 0, is the answer at the first gap (it took 61 gaps, the
    # bisections measuring t = 0 again and again, before the same answer).
    t, taken = _search(lambda t: -1e-3 + t, lambda t: 1.0, 1e-9, horizon=1.0)
    assert (t, taken) == (0.0, 1)


def test_a_bisection_ends_once_no_time_is_left_between_its_ends() -> None:
    # A gap that jumps from open to overlapping between two adjacent floats: the bisection
    # narrows to them in about 53 halvings of [0, 3 t*] and then ends on the safe side, where
    # the 60 halvings would have measured the same two times over again and ended there too.
    jump = 0.5
    t, taken = _search(lambda t: 1.0 if t < jump else -1.0, lambda t: 1.0 / 1.5, 1e-9, horizon=10.0)
    assert t == math.nextafter(jump, 0.0)  # the last time known open
    assert taken < 1 + BISECTIONS
