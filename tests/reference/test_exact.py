"""The exact rational reference against answers worked out by hand."""

from __future__ import annotations

import math

from carom.reference.exact import smooth_exact


def test_head_on_masses_1_and_3() -> None:
    # 1D elastic: v1' = (m1 - m2)/(m1 + m2) v1 = -1/2, v2' = 2 m1/(m1 + m2) v1 = 1/2;
    # nothing is lost at e = 1.
    assert smooth_exact([0, 0], [1, 0], 1.0, [1, 0], [0, 0], 3.0, 1.0) == (
        (-0.5, 0.0),
        (0.5, 0.0),
        0.0,
    )


def test_plastic_3_4_5_normal() -> None:
    # n along (3, 4)/5, v1 = (5, 0) into a static wall, e = 0: the normal part,
    # u = (5, 0) . (-3, -4)/5 = -3, is removed: v1' = v1 - u n = (5, 0) + 3 (-3, -4)/5
    # = (3.2, -2.4); KE lost = 1/2 m u^2 = 4.5 J for m = 1 kg.
    v1, v2, lost = smooth_exact([0, 0], [5, 0], 1.0, [3, 4], [0, 0], math.inf, 0.0)
    assert v1 == (3.2, -2.4)
    assert v2 == (0.0, 0.0)
    assert lost == 4.5


def test_separating_pair_is_unchanged() -> None:
    assert smooth_exact([0, 0], [-1, 0], 1.0, [1, 0], [1, 0], 1.0, 0.5) == (
        (-1.0, 0.0),
        (1.0, 0.0),
        0.0,
    )
