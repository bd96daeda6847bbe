"""From a World to the rigid engine's arrays: bodies, the box's walls and the planes as static
bodies, and the pair tables of restitution and friction.

The engine sees one kind of thing, bodies made of rounded convex pieces. A sphere (disk) of
the body table becomes a circle piece; each wall of a walled box becomes a static slab as
thick as the box is wide, just outside it; each plane a static slab below it, wider than the
box many times over. The caller's bodies keep their numbers, ``0`` to ``N - 1``; walls and
planes follow, and :class:`Partners` maps them back to ``KIND_WALL`` faces and ``KIND_PLANE``
indices for the collision records.

A wall's or plane's restitution and friction are its own, not combined with the body's (as
in the event-driven engine).
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Protocol, TypeVar, cast

import numpy as np
from numpy.typing import NDArray

from carom.bodies import KIND_STATIC, Bodies
from carom.engines.base import (
    KIND_PAIR,
    KIND_PLANE,
    KIND_WALL,
    Partners,
    WorldView,
    describe_partner,
)
from carom.engines.rigid.driver import RigidEngine
from carom.engines.rigid.model import RigidModel, RigidState, build_model, new_state
from carom.engines.rigid.settings import RigidSettings
from carom.errors import CaromError
from carom.materials import CombineRule, Material, combine, pair_table
from carom.shapes import ConvexPiece

__all__ = [
    "NAME",
    "Partners",
    "assemble",
    "build",
    "check_material",
    "pair_arrays",
    "refuses",
    "restore",
    "world_parts",
]

#: the engine's name in the table (:mod:`carom.engines.registry`), in 2D and 3D
NAME = "rigid"

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


def check_material(where: str, material: Material) -> None:
    """Refuse a material the rigid engine cannot honour (it knows restitution and Coulomb
    friction: a rough or Walton law is the event-driven engine's)."""
    if material.law == "rough" or (material.beta0 is not None and material.beta0 != 0.0):
        raise CaromError(
            f"{where}: {material} has a tangential restitution (beta or beta0), which only the "
            f"event-driven engine's sphere laws know; rigid bodies take friction= (Coulomb)"
        )


def pair_arrays(
    materials: Sequence[Material],
    rule: CombineRule,
    overrides: Mapping[tuple[int, int], float],
    extra: Sequence[Material],
) -> tuple[FloatArray, FloatArray, FloatArray]:
    """Restitution [-], friction [-] and rolling resistance [m] of every pair of the bodies'
    ``materials`` (combined by ``rule``, ``overrides`` kept) and of the walls' and planes'
    ``extra`` materials after them, (M + E, M + E) each. A wall's or plane's coefficients are
    its own, not combined with the body's."""
    mats = list(materials) or [Material()]
    table = pair_table(mats, rule, overrides)
    n_mat, m = table.e.shape[0], len(extra)
    e = np.zeros((n_mat + m, n_mat + m))
    mu = np.zeros_like(e)
    roll = np.zeros_like(e)
    e[:n_mat, :n_mat] = table.e
    mu[:n_mat, :n_mat] = table.friction
    for i, a in enumerate(mats):
        for j, b in enumerate(mats):
            roll[i, j] = combine(rule, a.rolling, b.rolling)
    for k, mat in enumerate(extra):
        row = n_mat + k
        e[row, :] = e[:, row] = mat.restitution
        mu[row, :] = mu[:, row] = mat.friction or 0.0
        roll[row, :] = roll[:, row] = mat.rolling
    return e, mu, roll


def _slab(centre: FloatArray, angle: float, width: float, height: float) -> ConvexPiece:
    """A static ``width`` x ``height`` rectangle turned by ``angle`` about ``centre``, as a
    piece in the world frame (its body sits at the origin)."""
    w, h = width / 2.0, height / 2.0
    core = ConvexPiece(np.array([[-w, -h], [w, -h], [w, h], [-w, h]]), 0.0)
    return core.moved(centre, angle)


def assemble(
    bodies: Bodies,
    box: FloatArray,
    walled: bool,
    walls: Sequence[Material],
    planes: Sequence[tuple[FloatArray, FloatArray, Material]],
    gravity: FloatArray,
    materials: Sequence[Material],
    combine: CombineRule,
    overrides: Mapping[tuple[int, int], float],
) -> tuple[RigidModel, RigidState, Partners]:
    """The rigid engine's model and state for a 2D world, and the partner map.

    Parameters
    ----------
    bodies : Bodies
        The caller's bodies (spheres become circles).
    box : (2,) float64
        Box sides [m]; ``walled`` gives it four walls with materials ``walls`` (x-, x+, y-, y+).
    planes : sequence of (point (2,), unit normal (2,), Material)
    gravity : (2,) float64
        [m/s^2].
    materials, combine, overrides
        The bodies' materials, how two combine, and pairs given their own restitution.
    """
    for k, each in enumerate(materials):
        check_material(f"material {k}", each)
    n = bodies.n
    pieces: list[tuple[ConvexPiece, ...]] = []
    for i in range(n):
        own = cast("tuple[ConvexPiece, ...]", bodies.pieces[i])
        pieces.append(own if own else (ConvexPiece(np.zeros((1, 2)), float(bodies.radius[i])),))
    mass = bodies.mass.copy()
    inertia = bodies.inertia
    kind = bodies.kind.astype(np.int64)
    material = bodies.material.copy()
    x, v = bodies.position.copy(), bodies.velocity.copy()
    angle = bodies.orientation[:, 0].copy()
    omega = bodies.angular_velocity[:, 2].copy()

    # walls and planes: static slabs, each with a material of its own
    extra_pieces: list[tuple[ConvexPiece, ...]] = []
    extra_materials: list[Material] = []
    partner_kind = [KIND_PAIR] * n
    partner_index = list(range(n))
    lx, ly = float(box[0]), float(box[1])
    if walled:
        t = max(lx, ly)  # thick: nothing tunnels through a slab as thick as the box
        slabs = [
            ((-t / 2, ly / 2), t, ly + 2 * t),
            ((lx + t / 2, ly / 2), t, ly + 2 * t),
            ((lx / 2, -t / 2), lx + 2 * t, t),
            ((lx / 2, ly + t / 2), lx + 2 * t, t),
        ]
        for face, (middle, w, h) in enumerate(slabs):
            check_material(f"wall {face}", walls[face])
            extra_pieces.append((_slab(np.array(middle), 0.0, w, h),))
            extra_materials.append(walls[face])
            partner_kind.append(KIND_WALL)
            partner_index.append(face)
    diagonal = math.hypot(lx, ly)
    for k, (point, normal, mat) in enumerate(planes):
        check_material(f"plane {k}", mat)
        depth = diagonal
        centre = np.asarray(point) - normal * depth / 2.0
        turn = math.atan2(normal[1], normal[0]) - math.pi / 2.0  # the slab's +y face is n
        extra_pieces.append((_slab(centre, turn, 100.0 * diagonal, depth),))
        extra_materials.append(mat)
        partner_kind.append(KIND_PLANE)
        partner_index.append(k)

    m = len(extra_pieces)
    e, mu, _ = pair_arrays(materials, combine, overrides, extra_materials)
    n_mat = e.shape[0] - m
    model = build_model(
        pieces + extra_pieces,
        np.concatenate([kind, np.full(m, KIND_STATIC, np.int64)]),
        np.concatenate([mass, np.full(m, np.inf)]),
        np.concatenate([inertia, np.full(m, np.inf)]),
        np.concatenate([material, n_mat + np.arange(m, dtype=np.int64)]),
        e,
        mu,
        np.asarray(gravity, float),
    )
    state = new_state(
        model,
        np.concatenate([x, np.zeros((m, 2))]),
        np.concatenate([v, np.zeros((m, 2))]),
        np.concatenate([angle, np.zeros(m)]),
        np.concatenate([omega, np.zeros(m)]),
    )
    partners = Partners(np.array(partner_kind, np.int8), np.array(partner_index, np.int64))
    return model, state, partners


# -- the plug (carom.engines.registry): 2D, and the 3D engine through its own parts ------------


def refuses(world: WorldView) -> str | None:
    """None when the rigid engine can run ``world`` (any bodies, walls or an open box); else
    why not."""
    if world.boundary == "periodic":
        return "the rigid-body engine has no periodic boundary; use boundary='walls' or 'open'"
    return None


def settings_of(world: WorldView) -> RigidSettings:
    """The rigid engine's settings that ``world`` keeps."""
    settings = world.settings_of(NAME)
    assert isinstance(settings, RigidSettings)
    return settings


Parts = TypeVar("Parts")


def world_parts(
    world: WorldView,
    assembly: Callable[..., Parts],
) -> Parts:
    """The rigid engine's view of ``world``, as the engine would start from it: the model,
    the state and the partners that ``assembly`` (:func:`assemble` in 2D, ``assemble3d``
    in 3D) makes of its bodies, box, walls, planes, gravity and materials."""
    why = refuses(world)
    if why is not None:
        raise CaromError(why)
    return assembly(
        world.bodies,
        world.box,
        world.boundary == "walls",
        world.walls,
        world.planes,
        world.gravity,
        world.materials,
        world.combine,
        world.pair_overrides,
    )


class _Stepped(Protocol):
    """What :func:`checked_start` asks of a rigid engine, in either dimension."""

    def deepest_overlap(self) -> tuple[int, int, float]: ...


Built = TypeVar("Built", bound=_Stepped)


def checked_start(engine: Built, partners: Partners, world: WorldView) -> Built:
    """``engine``, once no dynamic body starts overlapping another body, a wall or a plane
    deeper than the linear slop (the solver would throw them apart); else a CaromError
    naming the two."""
    a, b, depth = engine.deepest_overlap()
    slop = settings_of(world).linear_slop
    if depth > slop:
        names = [
            describe_partner(int(partners.kind[body]), int(partners.number[body]))
            for body in (a, b)
        ]
        raise CaromError(
            f"{names[0]} and {names[1]} overlap by {depth:.3g} m at the start (more than "
            f"the linear slop, {slop:g} m): move them apart"
        )
    return engine


def build(world: WorldView) -> RigidEngine:
    """The 2D rigid engine, from the world's bodies at its clock (:func:`checked_start`)."""
    model, state, partners = world_parts(world, assemble)
    engine = RigidEngine(model, state, settings_of(world), world.time, partners)
    return checked_start(engine, partners, world)


def restore(world: WorldView, arrays: Mapping[str, NDArray[Any]]) -> RigidEngine:
    """The 2D rigid engine that wrote ``arrays`` into a checkpoint of ``world``."""
    model, _, partners = world_parts(world, assemble)
    return RigidEngine.restore(model, settings_of(world), partners, arrays)
