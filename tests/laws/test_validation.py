"""Every invalid input raises CaromError (a ValueError) naming the argument and the value."""

from __future__ import annotations

import math

import pytest

import carom
from carom import CaromError, hecker

GOOD = {
    "x1": [0.0, 0.0],
    "v1": [1.0, 0.0],
    "m1": 1.0,
    "x2": [0.2, 0.0],
    "v2": [0.0, 0.0],
    "m2": 1.0,
}
ROUGH = {"radius1": 0.1, "radius2": 0.1}


def _call(**changes: object) -> None:
    args = {**GOOD, **changes}
    carom.collide(**args)  # type: ignore[arg-type]


@pytest.mark.parametrize(
    ("changes", "pattern"),
    [
        ({"m1": 0.0}, r"m1 must lie in \(0, inf\] \[kg\].*got m1 = 0\.0"),
        ({"m2": -2.0}, r"m2 .*got m2 = -2\.0"),
        ({"m1": math.nan}, r"m1 .*nan"),
        ({"m1": [1.0, -1.0]}, r"m1\[1\] = -1\.0"),
        ({"m1": math.inf, "m2": math.inf}, r"both infinite"),
        ({"v1": [1.0, math.nan]}, r"v1 must be finite \[m/s\]"),
        ({"x2": [math.inf, 0.0]}, r"x2 must be finite \[m\]"),
        ({"v2": [[0.0, 0.0], [0.0, math.inf]]}, r"v2\[1\] = \[0\.0, inf\]"),
        ({"e": 1.5}, r"e must lie in \[0, 1\].*got e = 1\.5"),
        ({"e": -0.1}, r"e must lie in \[0, 1\]"),
        ({"e": math.nan}, r"e must lie in \[0, 1\]"),
        ({"x1": [0.2, 0.0]}, r"x1 and x2 coincide at index 0"),
        ({"x1": [[0.0, 0.0]] * 3, "v1": [[1.0, 0.0]] * 2}, r"do not broadcast.*x1: 3.*v1: 2"),
        (
            {
                "x1": [0.0, 0.0, 0.0, 0.0],
                "v1": [1.0, 0, 0, 0],
                "x2": [1.0, 0, 0, 0],
                "v2": [0.0, 0, 0, 0],
            },
            r"x1 has 4 components; carom works in 2 or 3 dimensions",
        ),
        ({"x1": [0.0]}, r"x1 has 1 components"),
        ({"v1": [1.0, 0.0, 0.0]}, r"v1 is 3-dimensional but x1 is 2-dimensional"),
        ({"x1": [[[0.0, 0.0]]]}, r"x1 must have shape \(d,\).*got shape \(1, 1, 2\)"),
        ({"m1": "heavy"}, r"m1 must be numeric"),
        ({"beta": 1.2, **ROUGH}, r"beta must lie in \[-1, 1\].*got beta = 1\.2"),
        ({"beta": -1.5, **ROUGH}, r"beta must lie in \[-1, 1\]"),
        ({"friction": -0.1, **ROUGH}, r"friction must lie in \[0, inf\].*-0\.1"),
        ({"friction": math.nan, **ROUGH}, r"friction must lie"),
        ({"friction": 0.2, "beta0": 2.0, **ROUGH}, r"beta0 must lie in \[-1, 1\]"),
        ({"friction": 0.2, "beta": 0.1, **ROUGH}, r"either beta .* or friction"),
        ({"beta0": 0.3}, r"beta0 .* needs friction"),
        ({"beta": 0.5}, r"radius1 is required with the rough laws"),
        ({"w1": 3.0}, r"radius1 is required with spins"),
        ({"beta": 0.5, "radius1": 0.0, "radius2": 0.1}, r"radius1 must lie in \(0, inf\]"),
        ({"w1": [[1.0, 2.0]], **ROUGH}, r"w1 is the spin \[rad/s\] and in 2D must be a scalar"),
        ({"w1": math.nan, **ROUGH}, r"w1 must be finite \[rad/s\]"),
        ({"beta": 0.5, "q": 0.0, **ROUGH}, r"q must lie in \(0, 1\].*q1 = 0\.0"),
        ({"beta": 0.5, "q": (0.4, 2.0), **ROUGH}, r"q2 = 2\.0"),
    ],
)
def test_invalid_input_is_named(changes: dict[str, object], pattern: str) -> None:
    with pytest.raises(CaromError, match=pattern):
        _call(**changes)


def test_carom_error_is_a_value_error() -> None:
    with pytest.raises(ValueError, match="m1"):
        _call(m1=-1.0)


def test_3d_spin_shape_is_checked() -> None:
    with pytest.raises(CaromError, match=r"w2 is the spin .* in 3D must be shape \(3,\)"):
        carom.collide(
            [0, 0, 0],
            [1, 0, 0],
            1,
            [0.2, 0, 0],
            [0, 0, 0],
            1,
            w2=[1.0, 2.0],
            radius1=0.1,
            radius2=0.1,
        )


def test_hecker_checks_its_inputs_too() -> None:
    with pytest.raises(CaromError, match="reading must be one of"):
        hecker.collide(**GOOD, reading="sideways")  # type: ignore[arg-type]
    with pytest.raises(CaromError, match=r"e must lie in \[0, 1\]"):
        hecker.collide(**GOOD, e=2.0)  # type: ignore[arg-type]
    with pytest.raises(CaromError, match="inertia_a is required"):
        hecker.impulse([0.0, -1.0], [0.0, 1.0], 1.0, 1.0, r_a=[0.5, 0.0])
    with pytest.raises(CaromError, match="n must not be the zero vector"):
        hecker.impulse([0.0, -1.0], [0.0, 0.0], 1.0, 1.0)
    with pytest.raises(CaromError, match="positive definite"):
        hecker.impulse(
            [0.0, 0.0, -1.0],
            [0.0, 0.0, 1.0],
            1.0,
            1.0,
            r_a=[0.1, 0.0, 0.0],
            inertia_a=[[1.0, 0, 0], [0, -1.0, 0], [0, 0, 1.0]],
        )
