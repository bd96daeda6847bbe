"""From a World to the event-driven engine: what it takes, its surroundings, and the engine
built or restored (its plug in :mod:`carom.engines.registry`).

The engine runs spheres (disks in 2D) in a box of walls or a periodic one, with static planes;
walls and planes are smooth, each with its own restitution, not combined with the body's.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom.engines.base import WorldView
from carom.engines.edmd.driver import OVERLAP_TOLERANCE, EdmdEngine
from carom.engines.edmd.model import Environment
from carom.engines.edmd.settings import EdmdSettings
from carom.errors import CaromError
from carom.materials import pair_table
from carom.shape_base import SHAPE_CODES

__all__ = ["NAME", "build", "environment", "refuses", "restore"]

#: the engine's name in the table (:mod:`carom.engines.registry`)
NAME = "edmd"


def refuses(world: WorldView) -> str | None:
    """None when the engine can run ``world``: spheres (disks) alone, in walls or a periodic
    box; else why not."""
    if not world.bodies.spheres_only:
        i = int(np.argmax(world.bodies.shape != SHAPE_CODES["sphere"]))
        return (
            f"body {i} is not a sphere: the event-driven engine (engine='edmd') runs spheres "
            f"and disks only; use engine='rigid' or 'auto'"
        )
    if world.boundary == "open":
        return (
            "boundary 'open' (no walls) is the rigid-body engine's; the event-driven engine "
            "needs 'walls' or 'periodic'"
        )
    return None


def environment(world: WorldView) -> Environment:
    """The box, gravity, pair table and static faces of ``world``, as the engine takes them;
    a CaromError for a wall or plane that is not smooth."""
    for where, material in [("walls", m) for m in world.walls] + [
        (f"plane {k}", m) for k, (_, _, m) in enumerate(world.planes)
    ]:
        if material.law != "smooth":
            raise CaromError(
                f"{where}: the event-driven engine's walls and planes are smooth; give "
                f"them a material without beta or friction (got {material})"
            )
    dim = world.dim
    planes_p = np.array([p for p, _, _ in world.planes]).reshape(-1, dim)
    planes_n = np.array([q for _, q, _ in world.planes]).reshape(-1, dim)
    face_e = np.array(
        [m.restitution for m in world.walls] + [m.restitution for _, _, m in world.planes],
        dtype=np.float64,
    )
    return Environment(
        box=world.box.copy(),
        periodic=world.boundary == "periodic",
        gravity=world.gravity.copy(),
        pairs=pair_table(world.materials, world.combine, world.pair_overrides),
        face_e=face_e,
        plane_point=planes_p,
        plane_normal=planes_n,
    )


def check_placement(world: WorldView) -> None:
    """Refuse bodies outside the box or on the wrong side of a plane (overlaps between
    bodies: the engine's build)."""
    tol = OVERLAP_TOLERANCE
    x, a = world.bodies.position, world.bodies.radius
    if world.boundary == "walls":
        low = x - a[:, None]
        high = x + a[:, None] - world.box
        bad = (low < -tol * a[:, None]) | (high > tol * a[:, None])
        if bad.any():
            i = int(np.argmax(bad.any(axis=1)))
            raise CaromError(
                f"sphere {i} at {x[i].tolist()} with radius {a[i]:g} m reaches outside the "
                f"box [0, {world.box.tolist()}]; move it inside or enlarge the box"
            )
    for p_index, (p, nrm, _) in enumerate(world.planes):
        dist = (x - p) @ nrm - a
        bad = dist < -tol * a
        if bad.any():
            i = int(np.argmax(bad))
            raise CaromError(
                f"sphere {i} at {x[i].tolist()} is {-dist[i]:g} m on the wrong side of plane "
                f"{p_index} (point {p.tolist()}, normal {nrm.tolist()}); move it to the side "
                f"the normal points to"
            )


def _settings(world: WorldView) -> EdmdSettings:
    settings = world.settings_of(NAME)
    assert isinstance(settings, EdmdSettings)
    return settings


def build(world: WorldView) -> EdmdEngine:
    """The engine, from the world's bodies at its clock; a CaromError for a body outside the
    box or a plane's free side, or bodies that overlap. The bodies taken out of the world
    (:meth:`carom.World.remove_body`) stay out: nothing meets them."""
    check_placement(world)
    alive = getattr(world, "alive", None)  # (a World's, issue 43)
    gone = None if alive is None or np.all(alive) else ~np.asarray(alive, np.bool_)
    engine = EdmdEngine(world.bodies, environment(world), _settings(world), world.time, gone=gone)
    hand_over = getattr(world, "hand_over_loads", None)  # (a World's, issue 43)
    kept = hand_over() if hand_over is not None else None
    if kept is not None:  # (the forces given for the next step to the engine it replaces)
        engine.take_loads(kept)
    return engine


def restore(world: WorldView, arrays: Mapping[str, NDArray[Any]]) -> EdmdEngine:
    """The engine that wrote ``arrays`` into a checkpoint of ``world``."""
    return EdmdEngine.restore(world.bodies, environment(world), _settings(world), arrays)
