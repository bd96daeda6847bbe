"""Shapes: what a body is, as data only (no position, no engine).

Today carom simulates spheres (disks in 2D) with the event-driven engine; the rigid-body engine
adds capsules, boxes, polygons, hulls and compounds here. A shape is stored per body in the
body table by its code (:data:`SHAPE_CODES`), with its parameters in the table's columns.

>>> Sphere(0.1).moment_of_inertia(mass=2.0)  # 2/5 m a^2 [kg m^2]
0.008000000000000002
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from carom.errors import CaromError
from carom.laws.spheres import default_inertia_factor

__all__ = [
    "SHAPE_CODES",
    "SHAPE_NAMES",
    "Sphere",
    "check_inertia_factor",
    "default_inertia_factor",
]

#: shape codes, as stored per body (H5MD ``particles/all/shape`` holds these names)
SHAPE_CODES = {"sphere": 0}
SHAPE_NAMES = {code: name for name, code in SHAPE_CODES.items()}


def check_inertia_factor(q: float) -> float:
    """``q`` if it is a valid factor in ``I = q m a^2``, in (0, 1]; else a CaromError."""
    if isinstance(q, bool) or not isinstance(q, int | float) or not 0.0 < q <= 1.0:
        raise CaromError(
            f"inertia_factor must lie in (0, 1] (I = q m a^2; 2/5 solid sphere, 2/3 shell, "
            f"1/2 disk); got {q!r}"
        )
    return float(q)


@dataclass(frozen=True)
class Sphere:
    """A sphere (a disk in 2D).

    Parameters
    ----------
    radius : float
        [m], positive.
    inertia_factor : float, optional
        ``q`` in the moment of inertia ``I = q m a^2`` [-], in (0, 1]: 2/5 for a solid
        sphere (the default in 3D), 2/3 for a thin shell, 1/2 for a disk (the default in 2D).
    """

    radius: float
    inertia_factor: float | None = None

    def __post_init__(self) -> None:
        if not (self.radius > 0.0 and math.isfinite(self.radius)):
            raise CaromError(f"radius must be positive and finite [m]; got {self.radius!r}")
        if self.inertia_factor is not None:
            check_inertia_factor(self.inertia_factor)

    def moment_of_inertia(self, mass: float, dim: int = 3) -> float:
        """``q m a^2`` about any axis through the centre [kg m^2]."""
        q = self.inertia_factor if self.inertia_factor is not None else default_inertia_factor(dim)
        return q * mass * self.radius**2
