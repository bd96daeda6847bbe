"""The seven-case study: coverage of the thesis' claims, accuracy, and honest conclusions."""

from __future__ import annotations

import dataclasses
import math

import pytest

from carom.studies.two_spheres import CASES, ROUND_OFF, Record, conclusions, run_study


@pytest.fixture(scope="module")
def records() -> list[Record]:
    return run_study()


def test_cases_cover_every_claim(records: list[Record]) -> None:
    # 1-6 at e = 1, 0.5, 0 and case 7 perfectly plastic: 6 * 3 + 1 = 19 impacts
    assert len(records) == 19
    assert {(r.case, r.e) for r in records if r.case < 7} == {
        (c, e) for c in range(1, 7) for e in (1.0, 0.5, 0.0)
    }
    assert [r.e for r in records if r.case == 7] == [0.0]
    by_case = {c.number: c for c in CASES}
    assert not by_case[1].oblique
    assert by_case[1].equal_masses
    assert not by_case[1].same_direction
    assert by_case[2].m2 == 3 * by_case[2].m1
    assert not by_case[2].same_direction
    assert by_case[3].same_direction
    assert not by_case[3].oblique
    assert by_case[4].oblique
    assert by_case[4].v2 == (0.0, 0.0)
    assert by_case[4].equal_masses
    assert by_case[5].oblique
    assert not by_case[5].equal_masses
    assert not by_case[5].same_direction
    assert by_case[6].oblique
    assert by_case[6].same_direction
    for case in CASES:  # every case is given at the instant of contact, approaching
        gap = math.dist(case.x1, case.x2) - 2 * case.radius
        assert abs(gap) < 1e-15
        u = sum(
            (a - b) * (p - q) for a, b, p, q in zip(case.v1, case.v2, case.x1, case.x2, strict=True)
        )
        assert u < 0


def test_cut_shot_impact_parameter_is_half_the_sum_of_radii() -> None:
    # b = distance from sphere 2's centre to sphere 1's line of motion (along x): |y1 - y2|
    case = CASES[3]
    assert case.v1[1] == 0.0
    assert abs(case.x1[1] - case.x2[1]) == pytest.approx(case.radius, rel=1e-15, abs=0)


def test_carom_and_hecker_contact_are_exact_head_on_reading_only_head_on(
    records: list[Record],
) -> None:
    for r in records:
        assert r.models["carom"].error <= ROUND_OFF
        assert r.models["hecker_contact"].error <= ROUND_OFF
        if r.oblique:
            # velocity components across the line of centres differ by O(|v|): > 10 percent
            assert r.models["hecker_head_on"].error > 0.1
        else:
            assert r.models["hecker_head_on"].error <= ROUND_OFF


def test_rebound_quantities(records: list[Record]) -> None:
    for r in records:
        exact = r.exact
        u = math.hypot(*(a - b for a, b in zip(r.v1, r.v2, strict=True)))
        # the gap opens at e |u| (PHYSICS.md section 1); |u| here is the normal part of v1-v2
        dx = [a - b for a, b in zip(r.x1, r.x2, strict=True)]
        n = [c / math.hypot(*dx) for c in dx]
        un = -sum((a - b) * c for a, b, c in zip(r.v1, r.v2, n, strict=True))
        assert exact.separation_speed == pytest.approx(r.e * un, abs=ROUND_OFF * u)
        # momentum conserved, energy lost as 1/2 mu (1 - e^2) u_n^2
        mu = r.m1 * r.m2 / (r.m1 + r.m2)
        assert exact.ke_lost == pytest.approx(
            0.5 * mu * (1 - r.e**2) * un**2, abs=ROUND_OFF * exact.ke_before
        )
    cut_shot_elastic = next(r for r in records if r.case == 4 and r.e == 1.0)
    # the cosine is 0 to a few eps, and acos has slope -1 there: 90 degrees to ~1e-14
    assert cut_shot_elastic.exact.angle_deg == pytest.approx(90.0, abs=1e-12)


def test_conclusions_follow_the_numbers(records: list[Record]) -> None:
    text = "\n".join(conclusions(records))
    assert "carom: matches the exact answer to round-off in all 19 impacts" in text
    assert "Hecker, head-on reading: wrong in 10 of 19 impacts (10 oblique)" in text
    assert "Verdict" in text
    # Corrupt carom's answer in one record: the conclusions must say so and drop the verdict.
    bad = dataclasses.replace(records[5].models["carom"], error=0.25)
    doctored = list(records)
    doctored[5] = dataclasses.replace(records[5], models={**records[5].models, "carom": bad})
    text = "\n".join(conclusions(doctored))
    assert "carom: wrong in 1 of 19 impacts" in text
    assert "Verdict" not in text
