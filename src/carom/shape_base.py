"""What 2D and 3D shapes share (:mod:`carom.shapes`, :mod:`carom.shapes3d`): a shape is a
list of rounded convex pieces in its own frame; its mass properties come exactly from the
pieces' integrals, from a density or a mass; a capsule's two sizes; a compound's parts placed
one by one.

Each dimension names its integrals (which add, start from ``zero()`` and have a ``measure``:
area or volume), the density's unit, and how its mass properties are made from a density and
the integrals.
"""

from __future__ import annotations

from collections.abc import Callable, Iterable, Sequence
from dataclasses import dataclass
from typing import Any, ClassVar, Generic, Protocol, Self, TypeVar

from carom._inputs import finite_positive
from carom.errors import CaromError

__all__ = [
    "SHAPES",
    "SHAPE_CODES",
    "SHAPE_NAMES",
    "CapsuleSize",
    "Integrals",
    "RoundSize",
    "ShapeBase",
    "ShapeName",
    "compound_part",
    "compound_pieces",
]


@dataclass(frozen=True)
class ShapeName:
    """What a shape's name stands for, wherever it is written: a scene's ``shape = ...``, a
    body's stored code, an H5MD file's ``particles/all/shape``.

    Attributes
    ----------
    code : int
        The code stored per body (:attr:`carom.bodies.Bodies.shape`).
    dims : tuple of int
        The worlds it is a shape of (2, 3 or both).
    piece : bool
        Whether a compound's piece may have it.
    about : str
        What it is.
    """

    code: int
    dims: tuple[int, ...]
    piece: bool
    about: str


#: every shape name carom knows, in one table (TOML, World, checkpoints, H5MD and the
#: pictures read it). A "sphere" is the event-driven engine's hard sphere (a disk in 2D); a
#: "ball" is a 3D rigid body of the stepped engine (:class:`carom.shapes3d.Sphere`), which
#: turns and rolls; the two are kept apart because they are different bodies, not spellings.
SHAPES: dict[str, ShapeName] = {
    "sphere": ShapeName(0, (2, 3), False, "a hard sphere of the event-driven engine"),
    "circle": ShapeName(1, (2,), True, "a rigid disk"),
    "capsule": ShapeName(2, (2, 3), True, "the points within a radius of a segment"),
    "box": ShapeName(3, (2, 3), True, "a rectangle or a cuboid, optionally rounded in 2D"),
    "polygon": ShapeName(4, (2,), True, "a convex polygon, optionally rounded"),
    "compound": ShapeName(5, (2, 3), False, "convex pieces on one rigid body"),
    "segment": ShapeName(6, (2,), False, "a static line segment"),
    "chain": ShapeName(7, (2,), False, "a static polyline (terrain)"),
    "ball": ShapeName(10, (3,), True, "a rigid 3D ball"),
    "hull": ShapeName(8, (3,), True, "the convex hull of points"),
    "mesh": ShapeName(9, (3,), False, "a triangle mesh: static as it is, dynamic cut convex"),
}
#: each shape's stored code, and each code's name
SHAPE_CODES = {name: shape.code for name, shape in SHAPES.items()}
SHAPE_NAMES = {shape.code: name for name, shape in SHAPES.items()}


class Integrals(Protocol):
    """A region's or a solid's integrals per unit density
    (:class:`carom.geometry.outline.MassIntegrals`, :class:`carom.geometry.mass3d.SolidIntegrals`):
    they add, and their ``measure`` is the area [m^2] or volume [m^3]."""

    def __add__(self, other: Self) -> Self: ...

    @property
    def measure(self) -> float: ...


class Piece(Protocol):
    """A convex piece: its own integrals per unit density."""

    def integrals(self) -> Any: ...


PieceT = TypeVar("PieceT", bound=Piece)
IntegralsT = TypeVar("IntegralsT", bound=Integrals)
PropertiesT = TypeVar("PropertiesT")


class ShapeBase(Generic[PieceT, IntegralsT, PropertiesT]):
    """A shape for a rigid-body engine: rounded convex pieces in its own frame.

    A body's position is its centre of mass; the engine places the pieces relative to the
    shape's ``centroid``. A dimension's shape class names its integrals' class
    ``INTEGRALS`` (with ``zero()``), its ``MEASURE`` ("area" or "volume") and
    ``DENSITY_UNIT``, and makes its mass properties (:meth:`_properties`).
    """

    kind: str = ""
    INTEGRALS: ClassVar[Any]
    MEASURE: ClassVar[str]
    DENSITY_UNIT: ClassVar[str]

    def pieces(self) -> tuple[PieceT, ...]:
        """The convex pieces in the shape's frame."""
        raise NotImplementedError

    @staticmethod
    def _properties(density: float, integrals: IntegralsT) -> PropertiesT:
        """The mass properties of a body of ``density`` with these ``integrals``."""
        raise NotImplementedError

    def integrals(self) -> IntegralsT:
        """The area [m^2] or volume [m^3] and its first and second moments about the
        shape's origin, per unit density: the sum of the pieces'."""
        total: IntegralsT = self.INTEGRALS.zero()
        for piece in self.pieces():
            total = total + piece.integrals()
        return total

    def mass_properties(
        self, density: float | None = None, *, mass: float | None = None
    ) -> PropertiesT:
        """Exact mass, centre of mass and inertia, from a density or a mass.

        Parameters
        ----------
        density : float, optional
            Mass per area [kg/m^2] or per volume [kg/m^3].
        mass : float, optional
            Total mass [kg]; give this or ``density``, not both.

        Returns
        -------
        MassProperties or MassProperties3D
            The inertia about the centroid: ``density * int |x - c|^2 dA`` [kg m^2] in 2D,
            ``density * int (|r|^2 I - r r^T) dV``, ``r = x - c``, in 3D.

        Raises
        ------
        CaromError
            Neither or both given, either not finite and positive, or a shape with no area or
            volume (it can only be static).
        """
        unit = self.DENSITY_UNIT
        if (density is None) == (mass is None):
            raise CaromError(f"give density [{unit}] or mass [kg] (one of them)")
        integrals = self.integrals()
        measure = integrals.measure
        if not measure > 0.0:
            raise CaromError(
                f"a {self.kind} with no {self.MEASURE} has no mass: give it a radius, or make "
                'the body kind="static"'
            )
        if density is not None:
            rho = finite_positive("density", density, unit)
        else:
            rho = finite_positive("mass", mass, "kg") / measure
        return self._properties(rho, integrals)


@dataclass(frozen=True)
class RoundSize:
    """A round shape's ``radius`` [m], > 0 (a circle, a sphere)."""

    radius: float

    def __post_init__(self) -> None:
        finite_positive(f"{type(self).__name__} radius", self.radius, "m")


@dataclass(frozen=True)
class CapsuleSize:
    """A capsule's sizes: the distance between its two cap centres ``length`` [m] (the
    capsule is ``length + 2 radius`` long overall) and its ``radius`` [m], both > 0."""

    length: float
    radius: float
    kind: ClassVar[str] = "capsule"

    def __post_init__(self) -> None:
        finite_positive("Capsule length", self.length, "m")
        finite_positive("Capsule radius", self.radius, "m")


def compound_pieces(
    parts: Any, shape: type, turn: str, place: Callable[[int, Any], Iterable[Any]]
) -> tuple[Any, ...]:
    """A compound's pieces: ``place(i, part)`` for each of the ``parts``, a non-empty list of
    shapes (instances of ``shape``), (shape, offset) or (shape, offset, ``turn``)."""
    if isinstance(parts, shape) or not isinstance(parts, Sequence) or not parts:
        raise CaromError(
            "Compound takes a non-empty list of parts: shape, (shape, offset) or "
            f"(shape, offset, {turn}); got {parts!r}"
        )
    placed: list[Any] = []
    for i, part in enumerate(parts):
        placed.extend(place(i, part))
    return tuple(placed)


def compound_part(i: int, part: Any, shape: type, turn: str) -> tuple[Any, Any, Any]:
    """Compound part ``i`` as (shape, offset, turn), the last two as given (None when left
    out), or a :class:`CaromError` naming it."""
    if isinstance(part, shape):
        return part, None, None
    if isinstance(part, tuple | list) and len(part) in (2, 3) and isinstance(part[0], shape):
        return part[0], part[1], part[2] if len(part) == 3 else None
    raise CaromError(
        f"Compound part {i} must be a shape, (shape, offset) or (shape, offset, {turn}); "
        f"got {part!r}"
    )
