"""The seven-case study: carom's law against Hecker's formula, read two ways.

The seed thesis compares its two-sphere model with Chris Hecker's impulse formula on seven
collision cases and claims its model is right for head-on and oblique impacts where Hecker's is
right only head-on. This module computes every case with

* ``carom``: :func:`carom.collide` (PHYSICS.md section 1);
* ``hecker_contact``: Hecker's formula with the contact normal on the line of centres;
* ``hecker_head_on``: Hecker's formula with the normal along the relative velocity;

and measures each against the exact answer (:func:`carom.reference.exact.smooth_exact`,
rational arithmetic rounded once). The conclusion is written from those numbers by
:func:`conclusions`; nothing in it is fixed in advance.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from typing import Any

import numpy as np

from carom.laws.spheres import CollisionResult, collide
from carom.reference.exact import smooth_exact
from carom.studies import hecker

__all__ = [
    "CASES",
    "MODELS",
    "Case",
    "ModelOutcome",
    "Record",
    "conclusions",
    "format_details",
    "format_table",
    "run_study",
]

#: Relative error below which a model "agrees with the exact answer to round-off": a few
#: dozen float64 operations, each off by at most half an ulp (2**-53), relative to the
#: approach speed.
ROUND_OFF = 64 * 2.0**-52

MODELS: dict[str, str] = {
    "carom": "carom",
    "hecker_contact": "Hecker, contact normal",
    "hecker_head_on": "Hecker, head-on reading",
}


@dataclass(frozen=True)
class Case:
    """One collision set-up, given at the instant of contact (|x1 - x2| = a1 + a2).

    Lengths in m, velocities in m/s, masses in kg; the impact happens in the x-y plane.
    """

    number: int
    title: str
    m1: float
    m2: float
    x1: tuple[float, float]
    x2: tuple[float, float]
    v1: tuple[float, float]
    v2: tuple[float, float]
    restitutions: tuple[float, ...]
    oblique: bool
    radius: float = 0.1

    @property
    def same_direction(self) -> bool:
        """Whether both spheres move the same way (positive dot product of the velocities)."""
        return float(np.dot(self.v1, self.v2)) > 0.0

    @property
    def equal_masses(self) -> bool:
        return self.m1 == self.m2


_ALL_E = (1.0, 0.5, 0.0)
ORIGIN = (0.0, 0.0)

# Sphere 1's centre when it touches sphere 2 (radius 0.1 m each, sphere 2 at the origin), written
# so that head-on cases lie exactly on the x axis and |x1 - x2| = 0.2 m to the last bit or two.
_LEFT = (-0.2, 0.0)
_CUT_SHOT = (-math.sqrt(3.0) * 0.1, -0.1)  # impact parameter b = 0.1 m = (a1 + a2)/2
_DIAGONAL = (-math.sqrt(0.02), -math.sqrt(0.02))  # line of centres at 45 degrees
_3_4_5 = (-0.16, -0.12)  # a 3-4-5 triangle: cos = 0.8, sin = 0.6
_4_3_5 = (-0.12, -0.16)

#: The seven cases. Case 4 is a billiard cut shot: impact parameter b = (a1 + a2)/2, so the
#: line of centres makes 30 degrees with the cue ball's path (sin 30 = 1/2).
CASES: tuple[Case, ...] = (
    Case(
        1,
        "head-on, equal masses, opposite directions",
        1.0,
        1.0,
        _LEFT,
        ORIGIN,
        (1.0, 0.0),
        (-1.0, 0.0),
        _ALL_E,
        oblique=False,
    ),
    Case(
        2,
        "head-on, masses 1:3, opposite directions",
        1.0,
        3.0,
        _LEFT,
        ORIGIN,
        (2.0, 0.0),
        (-1.0, 0.0),
        _ALL_E,
        oblique=False,
    ),
    Case(
        3,
        "head-on, same direction, faster catches slower",
        1.0,
        2.0,
        _LEFT,
        ORIGIN,
        (3.0, 0.0),
        (1.0, 0.0),
        _ALL_E,
        oblique=False,
    ),
    Case(
        4,
        "oblique, equal masses, one at rest (cut shot, b = a)",
        1.0,
        1.0,
        _CUT_SHOT,
        ORIGIN,
        (1.0, 0.0),
        (0.0, 0.0),
        _ALL_E,
        oblique=True,
    ),
    Case(
        5,
        "oblique, masses 1:3, moving towards each other",
        1.0,
        3.0,
        _DIAGONAL,
        ORIGIN,
        (2.0, 0.5),
        (-1.0, 0.0),
        _ALL_E,
        oblique=True,
    ),
    Case(
        6,
        "oblique, same direction, faster catches slower",
        1.0,
        1.0,
        _3_4_5,
        ORIGIN,
        (3.0, 0.0),
        (1.0, 0.0),
        _ALL_E,
        oblique=True,
    ),
    Case(
        7,
        "oblique, perfectly plastic, masses 1:2",
        1.0,
        2.0,
        _4_3_5,
        ORIGIN,
        (2.0, 0.0),
        (0.0, -1.0),
        (0.0,),
        oblique=True,
    ),
)


@dataclass(frozen=True)
class ModelOutcome:
    """What one model predicts for one case and restitution, and how good it is.

    Velocities in m/s, energies in J, angles in degrees, distances in m; errors relative
    (dimensionless).
    """

    v1_after: tuple[float, ...]
    v2_after: tuple[float, ...]
    error: float
    """max(|v1' - v1'_exact|, |v2' - v2'_exact|) / |v1 - v2| [-]"""
    momentum_error: float
    """|p' - p| / (m1 |v1| + m2 |v2|) [-]"""
    ke_before: float
    ke_after: float
    ke_lost: float
    energy_error: float
    """(KE lost by the model - KE lost exactly) / KE before [-]"""
    separation_speed: float
    """(v1' - v2') . n along the line of centres [m/s]; negative: still moving into each other"""
    relative_speed_after: float
    angle_deg: float
    """angle between v1' and v2' [deg]; NaN when either sphere is left at rest"""
    gap_after_1s: float
    """distance between the surfaces after one second of free flight [m]"""

    @property
    def ke_lost_shown(self) -> float:
        """``ke_lost`` for display [J]: below round-off of the kinetic energy a loss is noise,
        not a number to show, and reads 0."""
        return self.ke_lost if abs(self.ke_lost) > ROUND_OFF * self.ke_before else 0.0


@dataclass(frozen=True)
class Record:
    """One case at one restitution: the inputs, the exact answer and every model."""

    case: int
    title: str
    e: float
    oblique: bool
    m1: float
    m2: float
    radius: float
    x1: tuple[float, float]
    x2: tuple[float, float]
    v1: tuple[float, float]
    v2: tuple[float, float]
    exact: ModelOutcome
    models: dict[str, ModelOutcome]

    def to_dict(self) -> dict[str, Any]:
        """A JSON-ready dictionary (NaN becomes None)."""
        safe: dict[str, Any] = _json_safe(asdict(self))
        return safe


def _json_safe(value: Any) -> Any:
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: _json_safe(v) for k, v in value.items()}
    if isinstance(value, list | tuple):
        return [_json_safe(v) for v in value]
    return value


def _angle_deg(a: np.ndarray, b: np.ndarray) -> float:
    na, nb = float(np.hypot(*a)), float(np.hypot(*b))
    if na == 0.0 or nb == 0.0:
        return math.nan
    cosine = float(np.dot(a, b)) / (na * nb)
    return math.degrees(math.acos(min(1.0, max(-1.0, cosine))))


def _outcome(
    case: Case,
    v1a: np.ndarray,
    v2a: np.ndarray,
    exact: tuple[np.ndarray, np.ndarray],
    ke_lost_exact: float,
) -> ModelOutcome:
    """Measure one model's post-impact velocities against the exact ones."""
    v1, v2 = np.array(case.v1), np.array(case.v2)
    x1, x2 = np.array(case.x1), np.array(case.x2)
    scale = float(np.hypot(*(v1 - v2)))
    error = max(float(np.hypot(*(v1a - exact[0]))), float(np.hypot(*(v2a - exact[1])))) / scale
    p_before = case.m1 * v1 + case.m2 * v2
    p_after = case.m1 * v1a + case.m2 * v2a
    p_scale = case.m1 * float(np.hypot(*v1)) + case.m2 * float(np.hypot(*v2))
    ke_before = 0.5 * case.m1 * float(v1 @ v1) + 0.5 * case.m2 * float(v2 @ v2)
    ke_after = 0.5 * case.m1 * float(v1a @ v1a) + 0.5 * case.m2 * float(v2a @ v2a)
    ke_lost = ke_before - ke_after
    n_c = (x1 - x2) / float(np.hypot(*(x1 - x2)))
    rel = v1a - v2a
    gap = float(np.hypot(*(x1 - x2 + rel * 1.0))) - 2 * case.radius
    return ModelOutcome(
        v1_after=tuple(float(c) for c in v1a),
        v2_after=tuple(float(c) for c in v2a),
        error=error,
        momentum_error=float(np.hypot(*(p_after - p_before))) / p_scale,
        ke_before=ke_before,
        ke_after=ke_after,
        ke_lost=ke_lost,
        energy_error=(ke_lost - ke_lost_exact) / ke_before,
        separation_speed=float(rel @ n_c),
        relative_speed_after=float(np.hypot(*rel)),
        angle_deg=_angle_deg(v1a, v2a),
        gap_after_1s=gap,
    )


def run_study(cases: tuple[Case, ...] = CASES) -> list[Record]:
    """Compute every case at each of its restitutions with the exact answer and all models.

    Returns
    -------
    list of Record
        One record per case and restitution, in case order (19 for the built-in cases).

    Examples
    --------
    >>> records = run_study()
    >>> len(records), records[0].models["carom"].v1_after
    (19, (-1.0, 0.0))
    """
    records = []
    for case in cases:
        for e in case.restitutions:
            v1x, v2x, ke_lost_exact = smooth_exact(
                case.x1, case.v1, case.m1, case.x2, case.v2, case.m2, e
            )
            exact_v = (np.array(v1x), np.array(v2x))
            args = (case.x1, case.v1, case.m1, case.x2, case.v2, case.m2)
            results: dict[str, CollisionResult] = {
                "carom": collide(*args, e=e),
                "hecker_contact": hecker.collide(*args, e=e, reading="contact"),
                "hecker_head_on": hecker.collide(*args, e=e, reading="head-on"),
            }
            models = {
                name: _outcome(case, r.v1, r.v2, exact_v, ke_lost_exact)
                for name, r in results.items()
            }
            records.append(
                Record(
                    case=case.number,
                    title=case.title,
                    e=e,
                    oblique=case.oblique,
                    m1=case.m1,
                    m2=case.m2,
                    radius=case.radius,
                    x1=case.x1,
                    x2=case.x2,
                    v1=case.v1,
                    v2=case.v2,
                    exact=_outcome(case, exact_v[0], exact_v[1], exact_v, ke_lost_exact),
                    models=models,
                )
            )
    return records


def _fmt_error(err: float) -> str:
    if err == 0.0:
        return "0"
    if err <= ROUND_OFF:
        return f"{err:.0e}"
    return f"{100 * err:.1f}%"


def _fmt(value: float, spec: str = ".3f") -> str:
    if not math.isfinite(value):
        return "-"
    text = format(value, spec)
    # round-off below the last digit shown is not a sign worth printing
    return text[1:] if text.startswith("-") and float(text) == 0.0 else text


def _vec(v: tuple[float, ...]) -> str:
    return "(" + ", ".join(_fmt(c, "6.3f") for c in v) + ")"


def format_details(records: list[Record]) -> str:
    """Every case: its inputs, then per restitution the exact answer and each model's.

    Columns: post-impact velocities [m/s]; error (as in :func:`format_table`); dp, the
    momentum balance |p' - p| / sum m|v|; KE lost [J]; sep., the normal opening speed
    (v1' - v2') . n [m/s] (negative: still approaching); angle between v1' and v2' [deg].
    """
    lines: list[str] = []
    head = (
        f"    {'e':>4}  {'':<24}{'v1 after [m/s]':<18}{'v2 after [m/s]':<18}{'error':>7}"
        f"{'dp':>8}{'KE lost [J]':>13}{'sep. [m/s]':>12}{'angle':>7}"
    )
    for number in sorted({r.case for r in records}):
        rows = [r for r in records if r.case == number]
        first = rows[0]
        lines.append(f"Case {number}: {first.title}")
        lines.append(
            f"  m1 = {first.m1:g} kg, m2 = {first.m2:g} kg, radii {first.radius:g} m; "
            f"x1 = {_vec(first.x1)} m, x2 = {_vec(first.x2)} m; "
            f"v1 = {_vec(first.v1)} m/s, v2 = {_vec(first.v2)} m/s"
        )
        lines.append(head)
        for r in rows:
            outcomes = [("exact", r.exact)] + [(MODELS[k], m) for k, m in r.models.items()]
            for i, (label, m) in enumerate(outcomes):
                e_col = f"{r.e:>4.1f}" if i == 0 else " " * 4
                error = "" if label == "exact" else _fmt_error(m.error)
                lines.append(
                    f"    {e_col}  {label:<24}{_vec(m.v1_after):<18}{_vec(m.v2_after):<18}"
                    f"{error:>7}{_fmt_error(m.momentum_error):>8}{_fmt(m.ke_lost_shown):>13}"
                    f"{_fmt(m.separation_speed):>12}{_fmt(m.angle_deg, '.1f'):>7}"
                )
        lines.append("")
    return "\n".join(lines)


def format_table(records: list[Record]) -> str:
    """The study in one fixed-width table: errors of each model, then the exact rebound."""
    head = (
        f"{'#':>2}  {'case':<53} {'e':>4}  {'carom':>8} {'Hecker n':>9} {'head-on':>8}"
        f"  {'KE lost':>8} {'sep.':>6} {'angle':>6}  {'head-on':>7}"
    )
    sub = (
        f"{'':>2}  {'':<53} {'':>4}  {'error in v, relative to |v1 - v2|':^27}"
        f"  {'[J]':>8} {'[m/s]':>6} {'[deg]':>6}  {'sep.':>7}"
    )
    lines = [head, sub, "-" * len(head)]
    for r in records:
        m = r.models
        lines.append(
            f"{r.case:>2}  {r.title:<53} {r.e:>4.1f}  {_fmt_error(m['carom'].error):>8} "
            f"{_fmt_error(m['hecker_contact'].error):>9} {_fmt_error(m['hecker_head_on'].error):>8}"
            f"  {_fmt(r.exact.ke_lost):>8} {_fmt(r.exact.separation_speed):>6} "
            f"{_fmt(r.exact.angle_deg, '.1f'):>6}  {_fmt(m['hecker_head_on'].separation_speed):>7}"
        )
    lines.append("")
    lines.append(
        "error: largest |v' - v'_exact| of the two spheres over |v1 - v2| (exact: rational "
        "arithmetic); sep.: (v1' - v2') . n, the rate\nthe gap opens along the line of centres "
        "(exact, then under the head-on reading); angle: between the outgoing velocities."
    )
    return "\n".join(lines)


def _describe(records: list[Record]) -> str:
    kinds = []
    for label, pick in (("head-on", lambda r: not r.oblique), ("oblique", lambda r: r.oblique)):
        count = sum(1 for r in records if pick(r))
        if count:
            kinds.append(f"{count} {label}")
    return " and ".join(kinds)


def conclusions(records: list[Record]) -> list[str]:
    """Findings derived from the computed numbers, one sentence each.

    Each statement is chosen by comparing the measured errors with :data:`ROUND_OFF`; change
    the cases and the text follows the numbers.
    """
    out: list[str] = []
    exact_models: list[str] = []
    for name, label in MODELS.items():
        errors = [(r.models[name].error, r) for r in records]
        worst, worst_rec = max(errors, key=lambda t: t[0])
        wrong = [r for err, r in errors if err > ROUND_OFF]
        if not wrong:
            exact_models.append(name)
            out.append(
                f"{label}: matches the exact answer to round-off in all {len(records)} impacts "
                f"({_describe(records)}; largest error {worst:.1e} of |v1 - v2|)."
            )
            continue
        right = [r for r in records if r not in wrong]
        sentence = (
            f"{label}: wrong in {len(wrong)} of {len(records)} impacts ({_describe(wrong)}), by "
            f"up to {100 * worst:.0f}% of |v1 - v2| (case {worst_rec.case}, e = {worst_rec.e:g})"
        )
        if right:
            sentence += f"; exact to round-off in the other {len(right)} ({_describe(right)})"
        out.append(sentence + ".")
        penetrating = [r for r in wrong if r.models[name].separation_speed < 0]
        if penetrating:
            cases = sorted({r.case for r in penetrating})
            out.append(
                f"  After its impulse the spheres still move into each other in case(s) "
                f"{', '.join(map(str, cases))}."
            )
        energy = max(abs(r.models[name].energy_error) for r in wrong)
        out.append(f"  Its energy loss is off by up to {100 * energy:.0f}% of the kinetic energy.")

    momentum = max(r.models[n].momentum_error for r in records for n in MODELS)
    if momentum <= ROUND_OFF:
        out.append(
            f"All three conserve momentum to round-off (largest {momentum:.1e}): an "
            f"equal and opposite impulse always does; being right needs the right normal."
        )
    for name in exact_models:
        by_mass = {r.m1 == r.m2 for r in records}
        by_dir = {_same_direction(r) for r in records}
        if by_mass == {True, False} and by_dir == {True, False}:
            out.append(
                f"{MODELS[name]} is exact for equal and unequal masses, for spheres moving "
                f"towards each other and the same way, at every e from 1 to 0."
            )
            break
    oblique_wrong_head_on = any(
        r.oblique and r.models["hecker_head_on"].error > ROUND_OFF for r in records
    )
    if "carom" in exact_models and "hecker_contact" in exact_models and oblique_wrong_head_on:
        out.append(
            "Verdict: the thesis' claim that its model beats Hecker's on oblique impacts holds "
            "only against the head-on reading. Given the line of centres as its normal, Hecker's "
            "published formula is the same law and gives the same velocities as carom."
        )
    return out


def _same_direction(r: Record) -> bool:
    return float(np.dot(r.v1, r.v2)) > 0.0
