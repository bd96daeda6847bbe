"""carom: exact, impulse-based collision response.

The closed-form two-body laws (:func:`collide`), Hecker's impulse formula (:mod:`carom.hecker`)
and the seven-case study (:mod:`carom.cases`).
"""

from __future__ import annotations

from carom import hecker
from carom.errors import CaromError
from carom.response import CollisionResult, collide
from carom.world import Frame, Material, World

__all__ = [
    "CaromError",
    "CollisionResult",
    "Frame",
    "Material",
    "World",
    "__version__",
    "collide",
    "hecker",
]

__version__ = "0.1.0"
