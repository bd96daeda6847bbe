"""From a 3D World to the 3D rigid engine's arrays, as :mod:`carom.engines.rigid.assemble` does
in 2D: the caller's bodies first (spheres become balls), then the box's six walls as static
slabs as thick as the box is wide, then the planes as static plane pieces.

A static mesh body's pieces are its triangles (three corners and the one triangle), each a
flat polytope. A wall's or plane's restitution, friction and rolling resistance are its own.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom.bodies import KIND_STATIC, Bodies
from carom.engines.base import KIND_PAIR, KIND_PLANE, KIND_WALL, Partners, WorldView
from carom.engines.rigid.assemble import (
    check_material,
    checked_start,
    pair_arrays,
    settings_of,
)
from carom.engines.rigid.assemble import refuses as refuses
from carom.engines.rigid.assemble import world_parts as parts_of
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
from carom.materials import CombineRule, Material
from carom.shapes3d import Box

__all__ = ["assemble3d", "build", "refuses", "restore", "world_parts"]

FloatArray = NDArray[np.float64]


def assemble3d(
    bodies: Bodies,
    box: FloatArray,
    walled: bool,
    walls: Sequence[Material],
    planes: Sequence[tuple[FloatArray, FloatArray, Material]],
    gravity: FloatArray,
    materials: Sequence[Material],
    rule: CombineRule,
    overrides: Mapping[tuple[int, int], float],
) -> tuple[Model3D, State3D, Partners]:
    """The 3D rigid engine's model and state for a 3D world, and the partner map.

    Parameters
    ----------
    bodies : Bodies
        The caller's bodies.
    box : (3,) float64
        Box sides [m]; ``walled`` gives it six walls with materials ``walls``
        (x-, x+, y-, y+, z-, z+).
    planes : sequence of (point (3,), unit normal (3,), Material)
    gravity : (3,) float64
        [m/s^2].
    materials, rule, overrides
        The bodies' materials, how two combine, and pairs given their own restitution.
    """
    for k, each in enumerate(materials):
        check_material(f"material {k}", each)
    n = bodies.n
    pieces = [
        engine_pieces(bodies.pieces[i], float(bodies.radius[i]))  # type: ignore[arg-type]
        for i in range(n)
    ]
    extra: list[list[Piece3D]] = []
    extra_materials: list[Material] = []
    partner_kind = [KIND_PAIR] * n
    partner_index = list(range(n))
    side = np.asarray(box, float)
    if walled:
        t = float(side.max())  # thick: nothing tunnels through a slab as thick as the box
        for face in range(6):
            axis, upper = divmod(face, 2)
            size = side + 2.0 * t
            size[axis] = t
            centre = side / 2.0
            centre[axis] = side[axis] + t / 2.0 if upper else -t / 2.0
            check_material(f"wall {face}", walls[face])
            extra.append([piece_of(p, centre) for p in Box(size).pieces()])
            extra_materials.append(walls[face])
            partner_kind.append(KIND_WALL)
            partner_index.append(face)
    for k, (point, normal, mat) in enumerate(planes):
        check_material(f"plane {k}", mat)
        extra.append([plane_piece(normal, float(np.dot(point, normal)))])
        extra_materials.append(mat)
        partner_kind.append(KIND_PLANE)
        partner_index.append(k)

    m = len(extra)
    e, mu, roll = pair_arrays(materials, rule, overrides, extra_materials)
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
        np.asarray(gravity, float),
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
    partners = Partners(np.array(partner_kind, np.int8), np.array(partner_index, np.int64))
    return model, state, partners


# -- the plug (carom.engines.registry) --------------------------------------------------------


def world_parts(world: WorldView) -> tuple[Model3D, State3D, Partners]:
    """The 3D rigid engine's view of ``world``, as the engine would start from it
    (:func:`assemble3d` of its bodies, box, walls, planes, gravity and materials)."""
    return parts_of(world, assemble3d)


def build(world: WorldView) -> RigidEngine3D:
    """The 3D rigid engine, from the world's bodies at its clock (overlaps refused as in
    2D, :func:`carom.engines.rigid.assemble.checked_start`)."""
    model, state, partners = world_parts(world)
    engine = RigidEngine3D(model, state, settings_of(world), world.time, partners)
    return checked_start(engine, partners, world)


def restore(world: WorldView, arrays: Mapping[str, NDArray[Any]]) -> RigidEngine3D:
    """The 3D rigid engine that wrote ``arrays`` into a checkpoint of ``world``."""
    model, _, partners = world_parts(world)
    return RigidEngine3D.restore(model, settings_of(world), partners, arrays)
