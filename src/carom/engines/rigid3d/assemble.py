"""From a 3D World to the 3D rigid engine's arrays, as :mod:`carom.engines.rigid.assemble` does
in 2D: the caller's bodies first (spheres become balls), then the box's six walls as static
slabs as thick as the box is wide, then the planes as static plane pieces.

A static mesh body's pieces are its triangles (three corners and the one triangle), each a
flat polytope. A wall's or plane's restitution, friction and rolling resistance are its own.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom.bodies import KIND_STATIC
from carom.engines.base import Partners, WorldView
from carom.engines.rigid3d.driver import RigidEngine3D
from carom.engines.rigid3d.model import (
    Model3D,
    Piece3D,
    State3D,
    build_model,
    engine_pieces,
    new_state,
    piece_of,
    plane_piece,
)
from carom.engines.stepped.assemble import (
    checked_start,
    pair_arrays,
    settings_of,
    statics,
)
from carom.engines.stepped.assemble import refuses as refuses
from carom.engines.stepped.assemble import world_parts as parts_of
from carom.shapes3d import Box

__all__ = ["assemble3d", "build", "refuses", "restore", "world_parts"]

FloatArray = NDArray[np.float64]


def assemble3d(world: WorldView) -> tuple[Model3D, State3D, Partners]:
    """The 3D rigid engine's model and state for a 3D ``world``, and the partner map: its
    bodies (spheres become balls), then a walled box's six walls (x-, x+, y-, y+, z-, z+) as
    static slabs as thick as the box is wide, then each plane as a static plane piece
    (:func:`carom.engines.stepped.assemble.statics`)."""
    bodies = world.bodies
    side = np.asarray(world.box, float)

    def walls() -> list[list[Piece3D]]:
        t = float(side.max())  # thick: nothing tunnels through a slab as thick as the box
        faces = []
        for face in range(6):
            axis, upper = divmod(face, 2)
            size = side + 2.0 * t
            size[axis] = t
            centre = side / 2.0
            centre[axis] = side[axis] + t / 2.0 if upper else -t / 2.0
            faces.append([piece_of(p, centre) for p in Box(size).pieces()])
        return faces

    def plane(point: FloatArray, normal: FloatArray) -> list[Piece3D]:
        return [plane_piece(normal, float(np.dot(point, normal)))]

    extra, extra_materials, partners = statics(world, walls, plane)
    pieces = [
        engine_pieces(bodies.pieces[i], float(bodies.radius[i]))  # type: ignore[arg-type]
        for i in range(bodies.n)
    ]
    m = len(extra)
    overrides = world.pair_overrides
    e, mu, roll = pair_arrays(world.materials, world.combine, overrides, extra_materials)
    n_mat = e.shape[0] - m
    inertia = np.concatenate([bodies.inertia_tensor, np.zeros((m, 3, 3))])
    model = build_model(
        pieces + extra,
        np.concatenate([bodies.kind.astype(np.int64), np.full(m, KIND_STATIC, np.int64)]),
        np.concatenate([bodies.mass, np.full(m, np.inf)]),
        inertia,
        np.concatenate([bodies.material, n_mat + np.arange(m, dtype=np.int64)]),
        e,
        mu,
        roll,
        np.asarray(world.gravity, float),
    )
    q = np.zeros((m, 4))
    q[:, 0] = 1.0
    state = new_state(
        model,
        np.concatenate([bodies.position, np.zeros((m, 3))]),
        np.concatenate([bodies.velocity, np.zeros((m, 3))]),
        np.concatenate([bodies.orientation, q]),
        np.concatenate([bodies.angular_velocity, np.zeros((m, 3))]),
    )
    return model, state, partners


# -- the plug (carom.engines.registry) --------------------------------------------------------


def world_parts(world: WorldView) -> tuple[Model3D, State3D, Partners]:
    """The 3D rigid engine's view of ``world``, as the engine would start from it
    (:func:`assemble3d` of its bodies, box, walls, planes, gravity and materials)."""
    return parts_of(world, assemble3d)


def build(world: WorldView) -> RigidEngine3D:
    """The 3D rigid engine, from the world's bodies at its clock (overlaps refused as in
    2D, :func:`carom.engines.stepped.assemble.checked_start`)."""
    model, state, partners = world_parts(world)
    engine = RigidEngine3D(model, state, settings_of(world), world.time, partners)
    return checked_start(engine, partners, world)


def restore(world: WorldView, arrays: Mapping[str, NDArray[Any]]) -> RigidEngine3D:
    """The 3D rigid engine that wrote ``arrays`` into a checkpoint of ``world``."""
    model, _, partners = world_parts(world)
    return RigidEngine3D.restore(model, settings_of(world), partners, arrays)
