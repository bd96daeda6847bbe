"""carom: exact, impulse-based collision response.

The closed-form two-body laws (:func:`collide`, :mod:`carom.laws`), Hecker's impulse formula
and its readings (:mod:`carom.hecker`), the seven-case study (:mod:`carom.studies.two_spheres`),
the :class:`World` and its engines (:mod:`carom.engines`), and scene files (:func:`load_scene`,
``docs/scenes.md``), and parameter sweeps on Dask (:func:`sweep`, ``docs/sweeps.md``).
"""

from __future__ import annotations

from carom.errors import CaromError, CaromWarning
from carom.laws.spheres import CollisionResult, collide
from carom.scene import Scene, SceneError, load_scene
from carom.studies import hecker
from carom.sweeps import sweep
from carom.world import Frame, Material, Recording, World

__all__ = [
    "CaromError",
    "CaromWarning",
    "CollisionResult",
    "Frame",
    "Material",
    "Recording",
    "Scene",
    "SceneError",
    "World",
    "__version__",
    "collide",
    "hecker",
    "load_scene",
    "sweep",
]

__version__ = "0.1.0"
