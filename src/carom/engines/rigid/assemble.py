"""From a World to the rigid engine's arrays: bodies, the box's walls and the planes as static
bodies, and the pair tables of restitution and friction.

The engine sees one kind of thing, bodies made of rounded convex pieces. A sphere (disk) of
the body table becomes a circle piece; each wall of a walled box becomes a static slab as
thick as the box is wide, just outside it; each plane a static slab below it, wider than the
box many times over. The caller's bodies keep their numbers, ``0`` to ``N - 1``; walls and
planes follow, and :class:`Partners` maps them back to ``PARTNER_WALL`` faces and ``PARTNER_PLANE``
indices for the collision records.

A wall's or plane's restitution and friction are its own, not combined with the body's (as
in the event-driven engine).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, cast

import numpy as np
from numpy.typing import NDArray

from carom.bodies import KIND_STATIC
from carom.engines.base import (
    Partners,
    WorldView,
)
from carom.engines.rigid.driver import RigidEngine
from carom.engines.rigid.model import RigidModel, RigidState, build_model, new_state
from carom.engines.stepped.assemble import (
    checked_start,
    pair_arrays,
    settings_of,
    statics,
    world_parts,
)
from carom.engines.stepped.assemble import refuses as refuses
from carom.shapes import ConvexPiece

__all__ = ["assemble", "build", "refuses", "restore"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def _slab(centre: FloatArray, angle: float, width: float, height: float) -> ConvexPiece:
    """A static ``width`` x ``height`` rectangle turned by ``angle`` about ``centre``, as a
    piece in the world frame (its body sits at the origin)."""
    w, h = width / 2.0, height / 2.0
    core = ConvexPiece(np.array([[-w, -h], [w, -h], [w, h], [-w, h]]), 0.0)
    return core.moved(centre, angle)


def assemble(world: WorldView) -> tuple[RigidModel, RigidState, Partners]:
    """The rigid engine's model and state for a 2D ``world``, and the partner map: its
    bodies (spheres become circles), then a walled box's four walls (x-, x+, y-, y+) as
    static slabs as thick as the box is wide, then each plane as a static slab below it, wider
    than the box many times over (:func:`carom.engines.stepped.assemble.statics`)."""
    bodies = world.bodies
    lx, ly = float(world.box[0]), float(world.box[1])
    diagonal = math.hypot(lx, ly)

    def walls() -> list[tuple[ConvexPiece, ...]]:
        t = max(lx, ly)  # thick: nothing tunnels through a slab as thick as the box
        slabs = [
            ((-t / 2, ly / 2), t, ly + 2 * t),
            ((lx + t / 2, ly / 2), t, ly + 2 * t),
            ((lx / 2, -t / 2), lx + 2 * t, t),
            ((lx / 2, ly + t / 2), lx + 2 * t, t),
        ]
        return [(_slab(np.array(middle), 0.0, w, h),) for middle, w, h in slabs]

    def plane(point: FloatArray, normal: FloatArray) -> tuple[ConvexPiece, ...]:
        depth = diagonal
        centre = np.asarray(point) - normal * depth / 2.0
        turn = math.atan2(normal[1], normal[0]) - math.pi / 2.0  # the slab's +y face is n
        return (_slab(centre, turn, 100.0 * diagonal, depth),)

    extra, extra_materials, partners = statics(world, walls, plane)
    pieces: list[tuple[ConvexPiece, ...]] = []
    for i in range(bodies.n):
        own = cast("tuple[ConvexPiece, ...]", bodies.pieces[i])
        pieces.append(own if own else (ConvexPiece(np.zeros((1, 2)), float(bodies.radius[i])),))
    m = len(extra)
    e, mu, _ = pair_arrays(world.materials, world.combine, world.pair_overrides, extra_materials)
    n_mat = e.shape[0] - m
    model = build_model(
        pieces + extra,
        np.concatenate([bodies.kind.astype(np.int64), np.full(m, KIND_STATIC, np.int64)]),
        np.concatenate([bodies.mass, np.full(m, np.inf)]),
        np.concatenate([bodies.inertia, np.full(m, np.inf)]),
        np.concatenate([bodies.material, n_mat + np.arange(m, dtype=np.int64)]),
        e,
        mu,
        np.asarray(world.gravity, float),
    )
    state = new_state(
        model,
        np.concatenate([bodies.position, np.zeros((m, 2))]),
        np.concatenate([bodies.velocity, np.zeros((m, 2))]),
        np.concatenate([bodies.orientation[:, 0], np.zeros(m)]),
        np.concatenate([bodies.angular_velocity[:, 2], np.zeros(m)]),
    )
    return model, state, partners


# -- the plug (carom.engines.registry) --------------------------------------------------------


def build(world: WorldView) -> RigidEngine:
    """The 2D rigid engine, from the world's bodies at its clock (:func:`checked_start`)."""
    model, state, partners = world_parts(world, assemble)
    engine = RigidEngine(model, state, settings_of(world), world.time, partners)
    return checked_start(engine, partners, world)


def restore(world: WorldView, arrays: Mapping[str, NDArray[Any]]) -> RigidEngine:
    """The 2D rigid engine that wrote ``arrays`` into a checkpoint of ``world``."""
    model, _, partners = world_parts(world, assemble)
    return RigidEngine.restore(model, settings_of(world), partners, arrays)
