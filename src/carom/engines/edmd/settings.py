"""The event-driven engine's settings: what a user may choose, checked, with its defaults."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from carom.errors import CaromError
from carom.limits import LARGEST, SMALLEST

__all__ = ["SHELL_DEFAULT", "EdmdSettings"]

#: default neighbour-shell thickness, as a fraction of the mean diameter of the moving bodies:
#: measured in cycles per collision, the fastest for 3D at packing 0.3 (18% ahead of 0.35) and
#: 2D at 0.5 (35% ahead), and within 10% of the best at 0.45 in 3D (docs/engine.md)
SHELL_DEFAULT = 0.5


@dataclass(frozen=True)
class EdmdSettings:
    """Settings of the event-driven engine.

    Parameters
    ----------
    t_c : float, default 1e-6
        TC-model time [s]: a collision within ``t_c`` of a body's previous collision is
        elastic, and a body that would bounce off a floor for less than ``t_c`` rests on it.
        Keep it well below the time between collisions of interest.
    shell_thickness : float, optional
        Neighbour-shell thickness [m]: how far a body moves before its neighbour list is
        rebuilt. Default ``SHELL_DEFAULT`` of the mean diameter of the moving bodies.
    """

    t_c: float = 1e-6
    shell_thickness: float | None = None

    def __post_init__(self) -> None:
        t_c = self.t_c
        if not (_real(t_c) and t_c >= 0.0 and t_c <= LARGEST):
            raise CaromError(f"t_c must be a number of seconds >= 0 and finite; got {t_c!r}")
        s = self.shell_thickness
        if s is not None and not (_real(s) and SMALLEST <= s <= LARGEST):
            raise CaromError(
                f"shell_thickness must be a length from {SMALLEST:g} to {LARGEST:g} m; got {s!r}"
            )


def _real(x: object) -> bool:
    return isinstance(x, int | float | np.integer | np.floating) and not isinstance(x, bool)
