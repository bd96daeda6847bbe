"""Repository-wide pytest set-up: the doctests of src/carom import each module, and the
modules that drive a peer engine import that engine; skip those the environment lacks."""

from __future__ import annotations

import importlib.util

collect_ignore = [
    f"src/carom/compare/engines/{peer}_engine.py"
    for peer in ("pymunk", "pybullet", "mujoco")
    if importlib.util.find_spec(peer) is None
]
