"""The event-driven engine's settings: what a user may choose, checked, with its defaults."""

from __future__ import annotations

import math
from dataclasses import dataclass

from carom.errors import CaromError

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
        if not (self.t_c >= 0.0 and math.isfinite(self.t_c)):
            raise CaromError(f"t_c must be >= 0 and finite [s]; got {self.t_c!r}")
        s = self.shell_thickness
        if s is not None and not (s > 0.0 and math.isfinite(s)):
            raise CaromError(f"shell_thickness must be > 0 and finite [m]; got {s!r}")
