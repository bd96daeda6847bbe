"""The closed forms ``carom compare`` holds every engine to (no peer needed)."""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest

from carom.compare.closed_form import expectation
from carom.compare.driver import peer_scene
from carom.reference.exact import smooth_exact
from carom.scene import Scene
from carom.studies.two_spheres import CASES, ROUND_OFF


@pytest.mark.parametrize("case", CASES, ids=lambda c: f"case-{c.number}")
def test_two_sphere_scenes_give_the_study_answer(case):
    # case-k.toml starts the spheres 0.5 s before the study's contact configuration; the
    # closed form flies them there and applies the impulse law in rational arithmetic, so its
    # velocities are the study's exact answer to a few ulps of the approach speed
    expected = expectation(peer_scene(f"case-{case.number}"))
    assert expected is not None
    assert expected.source.startswith("two smooth spheres")
    (check,) = expected.checks
    v1, v2, lost = smooth_exact(
        case.x1, case.v1, case.m1, case.x2, case.v2, case.m2, case.restitutions[0]
    )
    speed = math.dist(case.v1, case.v2)
    # sqrt(u . u) against math.dist: one length rounded two ways, a few ulps apart at most
    # (1e-15 is 4.5 eps)
    assert expected.speed == pytest.approx(speed, rel=1e-15, abs=0)
    assert check.velocities is not None
    error = np.abs(check.velocities - np.array([v1, v2])).max() / speed
    assert error <= ROUND_OFF
    kinetic = 0.5 * (case.m1 * np.dot(case.v1, case.v1) + case.m2 * np.dot(case.v2, case.v2))
    assert check.energy == pytest.approx(kinetic - lost, rel=ROUND_OFF, abs=0)
    assert 0.5 < check.time < 1.0  # after the impact at 0.5 s, before the scene ends


def test_newtons_cradle_passes_the_striker_velocity_to_the_last_ball():
    # equal masses, e = 1: each collision swaps the velocities, so after the four collisions
    # only the last ball moves, at the striker's 1 m/s; kinetic energy 1/2 m v^2 = 0.5 J
    expected = expectation(peer_scene("newtons-cradle"))
    assert expected is not None
    assert expected.source.startswith("bodies on one line")
    (check,) = expected.checks
    assert check.velocities is not None
    np.testing.assert_array_equal(check.velocities, [[0, 0], [0, 0], [0, 0], [0, 0], [1, 0]])
    assert check.energy == 0.5
    # the striker (x = 0.2 m, 1 m/s) touches the row (first ball at 0.6 m, radii 0.05 m) at
    # 0.3 s; the last ball, leaving x = 0.9 m at 1 m/s, touches the right wall (x = 1.35 m)
    # at 0.75 s: the check sits halfway between
    assert check.time == pytest.approx(0.5 * (0.3 + 0.75), rel=1e-12, abs=0)


def _line_scene(masses, restitution):
    n = len(masses)
    return Scene.from_dict(
        {
            "world": {"dimension": 2, "box": [40.0, 1.0]},
            "materials": [{"name": "m", "restitution": restitution}],
            "bodies": [
                {
                    "positions": [[10.0 + 0.5 * k, 0.5] for k in range(n)],
                    "velocities": [[2.0, 0.0]] + [[0.0, 0.0]] * (n - 1),
                    "radius": 0.2,
                    "mass": list(masses),
                    "material": "m",
                }
            ],
            "run": {"until": 5.0},
        }
    )


@pytest.mark.parametrize("restitution", [1.0, 0.5])
def test_a_line_of_unequal_masses_conserves_momentum_and_ends_parting(restitution):
    masses = [1.0, 3.0, 0.5, 2.0]
    spec = peer_scene(_line_scene(masses, restitution), name="line")
    expected = expectation(spec)
    assert expected is not None
    assert expected.source.startswith("bodies on one line")
    (check,) = expected.checks
    v = check.velocities[:, 0]
    # momentum m v is conserved by every impulse: 1 kg x 2 m/s
    assert float(np.dot(masses, v)) == pytest.approx(2.0, rel=8 * 2.0**-52, abs=0)
    # after the last collision no neighbours approach each other
    assert np.all(np.diff(v) >= -1e-15)
    if restitution == 1.0:
        kinetic = 0.5 * float(np.dot(masses, v * v))
        assert kinetic == pytest.approx(2.0, rel=16 * 2.0**-52, abs=0)
        assert check.energy == 2.0


def test_a_plastic_line_has_no_finite_sequence_of_collisions():
    # e = 0: once two bodies move together, the next collision ahead slows the front one and
    # the one behind hits it again at zero gap: infinitely many collisions in no time, so
    # the sequential model has no closed form (carom's TC model makes them elastic instead)
    assert expectation(peer_scene(_line_scene([1.0, 3.0, 0.5, 2.0], 0.0), name="line")) is None


def test_the_bouncing_ball_rebounds_to_e_squared_heights():
    # dropped from rest with its centre 1.55 m up, radius 0.05 m: it falls h = 1.5 m and hits
    # at V1 = sqrt(2 g h) after t1 = V1 / g; the k-th rebound leaves at e^k V1 and peaks
    # e^k V1 / g later, e^(2k) h above the floor (PHYSICS.md, bouncing ball)
    expected = expectation(peer_scene("bouncing-ball"))
    assert expected is not None
    assert expected.source.startswith("a ball dropped")
    g, h, r, e = 9.81, 1.5, 0.05, 0.8
    v1 = math.sqrt(2 * g * h)
    # the same root from the scene's numbers (h = 1.55 - 0.05 rounds once): a few ulps
    assert expected.speed == pytest.approx(v1, rel=1e-15, abs=0)
    t = v1 / g
    assert len(expected.checks) == 3
    for k, check in enumerate(expected.checks, start=1):
        apex = t + e**k * v1 / g
        # half a dozen float64 operations on both sides, each within half an ulp, summed
        # differently: ~10 eps at most; 1e-14 is 45 eps
        assert check.time == pytest.approx(apex, rel=1e-14, abs=0)
        np.testing.assert_array_equal(check.velocities, [[0.0, 0.0]])
        # all energy potential at the apex: m g (r + e^(2k) h), m = 1 kg
        assert check.energy == pytest.approx(g * (r + e ** (2 * k) * h), rel=1e-14, abs=0)
        t += 2 * e**k * v1 / g


def test_an_elastic_gas_has_its_energy_as_the_only_closed_form():
    spec = peer_scene("gas-2d", until=0.1)
    expected = expectation(spec)
    assert expected is not None
    (check,) = expected.checks
    assert check.velocities is None
    assert check.time == 0.1
    assert check.energy == spec.energy(spec.positions, spec.velocities)


def test_fractions_are_exact_for_the_cradle_chain():
    # the 1D law with e = 1 and equal masses swaps velocities exactly (no rounding at all)
    w1, w2, e = Fraction(1), Fraction(0), Fraction(1)
    after1 = w1 - (1 + e) / 2 * (w1 - w2)
    after2 = w2 + (1 + e) / 2 * (w1 - w2)
    assert (after1, after2) == (0, 1)
