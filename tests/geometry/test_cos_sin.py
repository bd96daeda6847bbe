"""The solver's cos and sin of a substep's turn (:func:`carom.geometry.rotation.cos_sin`):
a Taylor series below 1/4 rad, the library beyond."""

from __future__ import annotations

import math

import numpy as np

from carom.geometry.rotation import cos_sin

ULP = 2.0**-52  # relative spacing of float64 at 1


def test_the_series_agrees_with_the_library_to_an_ulp() -> None:
    # The first term left out is phi^14/14! < 5e-20 and phi^15/15! < 8e-22 at phi = 1/4, far
    # under half an ulp of cos (~0.97) and of sin (~phi); what is left is the rounding of a
    # dozen multiply-adds against the library's correctly rounded result: an ulp.
    phis = np.concatenate(
        [np.linspace(-0.2499, 0.2499, 20001), np.geomspace(1e-12, 0.2499, 400), [0.0]]
    )
    for phi in phis.tolist():
        c, s = cos_sin(phi)
        assert abs(c - math.cos(phi)) <= ULP
        assert abs(s - math.sin(phi)) <= ULP * abs(math.sin(phi))
        assert cos_sin(-phi) == (c, -s)  # even and odd, as the series is


def test_large_turns_take_the_library() -> None:
    for phi in (0.25, -0.25, 1.0, -3.0, 100.0):
        assert cos_sin(phi) == (math.cos(phi), math.sin(phi))
