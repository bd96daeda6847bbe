"""carom: exact, impulse-based collision response.

The closed-form two-body laws (:func:`collide`), Hecker's impulse formula (:mod:`carom.hecker`),
the seven-case study (:mod:`carom.cases`), the event-driven engine (:class:`World`) and scene
files (:func:`load_scene`, ``docs/scenes.md``).
"""

from __future__ import annotations

from carom import hecker
from carom.errors import CaromError
from carom.response import CollisionResult, collide
from carom.scene import Scene, SceneError, load_scene
from carom.world import Frame, Material, World

__all__ = [
    "CaromError",
    "CollisionResult",
    "Frame",
    "Material",
    "Scene",
    "SceneError",
    "World",
    "__version__",
    "collide",
    "hecker",
    "load_scene",
]

__version__ = "0.1.0"
