"""What both dimensions' rigid engines share of their plug (:mod:`carom.engines.registry`):
which worlds they take, the materials they honour, the pair tables of restitution, friction
and rolling resistance (walls' and planes' coefficients their own), the world's parts made by
a dimension's assembly, and the check that nothing starts overlapping.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from typing import Any, NamedTuple, Protocol, TypeVar

import numpy as np
from numpy.typing import NDArray

from carom.engines.base import (
    PARTNER_BODY,
    PARTNER_PLANE,
    PARTNER_WALL,
    Partners,
    WorldView,
    describe_partner,
)
from carom.engines.stepped.memory import Remembered
from carom.engines.stepped.settings import RigidSettings
from carom.errors import CaromError
from carom.materials import CombineRule, Material, combine, pair_table

__all__ = [
    "NAME",
    "Statics",
    "check_material",
    "checked_start",
    "pair_arrays",
    "refuses",
    "settings_of",
    "statics",
    "world_parts",
]

FloatArray = NDArray[np.float64]

#: the engine's name in the table (:mod:`carom.engines.registry`), in 2D and 3D
NAME = "rigid"


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


class Statics(NamedTuple):
    """The walls and planes as the static bodies that follow the caller's: each one's
    pieces, its own material, and the partner map of every body (:class:`Partners`)."""

    pieces: list[Any]
    materials: list[Material]
    partners: Partners


def statics(
    world: WorldView,
    walls: Callable[[], list[Any]],
    plane: Callable[[FloatArray, FloatArray], Any],
) -> Statics:
    """The box's walls (``walls()``: each face's pieces, x-, x+, y-, ... ; only for a walled
    box) and the planes (``plane(point, normal)``: its pieces) of ``world`` as static bodies,
    after its N bodies; every material checked (:func:`check_material`)."""
    for k, each in enumerate(world.materials):
        check_material(f"material {k}", each)
    n = world.bodies.n
    kind, number = [PARTNER_BODY] * n, list(range(n))
    pieces: list[Any] = []
    materials: list[Material] = []
    if world.boundary == "walls":
        for face, wall in enumerate(walls()):
            check_material(f"wall {face}", world.walls[face])
            pieces.append(wall)
            materials.append(world.walls[face])
            kind.append(PARTNER_WALL)
            number.append(face)
    for k, (point, normal, mat) in enumerate(world.planes):
        check_material(f"plane {k}", mat)
        pieces.append(plane(point, normal))
        materials.append(mat)
        kind.append(PARTNER_PLANE)
        number.append(k)
    partners = Partners(np.array(kind, np.int8), np.array(number, np.int64))
    return Statics(pieces, materials, partners)


Parts = TypeVar("Parts")


def world_parts(world: WorldView, assembly: Callable[[WorldView], Parts]) -> Parts:
    """The rigid engine's view of ``world``, as the engine would start from it: the model,
    the state and the partners that ``assembly`` (the 2D or the 3D one) makes of it."""
    why = refuses(world)
    if why is not None:
        raise CaromError(why)
    return assembly(world)


class _Stepped(Protocol):
    """What :func:`checked_start` asks of a rigid engine, in either dimension."""

    def deepest_overlap(self) -> tuple[int, int, float]: ...

    def use_filters(self, table: NDArray[np.int64]) -> None: ...

    def use_sensors(
        self, sensor: NDArray[np.bool_], changed: NDArray[np.int64],
        pieces: NDArray[np.int64] | None = None,
    ) -> None: ...  # fmt: skip

    def retire(self, ids: NDArray[np.int64]) -> None: ...

    def take_loads(self, kept: tuple[NDArray[np.float64], NDArray[np.float64]]) -> None: ...

    def take_memory(self, kept: Remembered) -> None: ...


Built = TypeVar("Built", bound=_Stepped)


def checked_start(engine: Built, partners: Partners, world: WorldView) -> Built:
    """``engine``, once no dynamic body starts overlapping another body, a wall or a plane
    deeper than the linear slop (the solver would throw them apart); else a CaromError
    naming the two. The world's collision filters (:meth:`carom.World.set_filter`), sensors
    (:meth:`carom.World.set_sensor`) and joints (:meth:`carom.World.add_joint`) are the
    engine's first: a pair they keep apart may start overlapping; so are the forces and
    torques given for the next step to an engine the world dropped (bodies added or switched
    between steps). An engine built in place of a running one (bodies added, kinds or
    settings changed) takes the overlaps the running one had (``world.overlap_kept``, the
    deepest of them), which its solver made and resolves."""
    table = getattr(world, "collision_filters", None)
    if table is not None and len(table):
        engine.use_filters(np.asarray(table, np.int64))
    sensors = getattr(world, "sensors", None)
    pieces = getattr(world, "sensor_pieces", None)
    if sensors is not None and (np.any(sensors) or (pieces is not None and len(pieces))):
        engine.use_sensors(np.asarray(sensors, np.bool_), np.zeros(0, np.int64), pieces)
    share_joints = getattr(world, "share_joints", None)  # (a World's, issue 43)
    if share_joints is not None:
        share_joints(engine)
    alive = getattr(world, "alive", None)
    if alive is not None and not np.all(alive):
        engine.retire(np.flatnonzero(~np.asarray(alive)))
    a, b, depth = engine.deepest_overlap()
    slop = settings_of(world).linear_slop
    kept = float(getattr(world, "overlap_kept", 0.0))
    if depth > max(slop, kept):
        names = [
            describe_partner(int(partners.kind[body]), int(partners.number[body]))
            for body in (a, b)
        ]
        most = (
            f"the deepest overlap the running engine had, {kept:.3g} m"
            if kept > slop
            else f"the linear slop, {slop:g} m"
        )
        raise CaromError(
            f"{names[0]} and {names[1]} overlap by {depth:.3g} m at the start (more than "
            f"{most}): move them apart"
        )
    # what the running engine left, taken once the engine is taken (refused, the world keeps
    # it for the next try)
    for given, take in (
        ("hand_over_loads", engine.take_loads),  # (a World's, issue 43)
        ("hand_over_memory", engine.take_memory),
    ):
        hand_over = getattr(world, given, None)
        left = hand_over() if hand_over is not None else None
        if left is not None:
            take(left)
    return engine
