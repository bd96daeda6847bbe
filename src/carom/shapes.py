"""Shapes: what a body is, as data only (no position, no engine).

:class:`Sphere` is the event-driven engine's ball (a disk in 2D). The 2D rigid-body engine
takes :class:`Circle`, :class:`Capsule`, :class:`Box`, :class:`Polygon` (convex, optionally
rounded), :class:`Compound` (several convex pieces on one rigid body: a concave body) and, for
static terrain, :class:`Segment` and :class:`Chain`. Each of these is a list of *rounded
convex polygons* (:class:`ConvexPiece`: a core of 1, 2 or more corners and a radius), so one
set of contact functions and one set of mass formulas serves them all.

Mass properties are exact (:mod:`carom.geometry.outline`): in 2D a density is per area
[kg/m^2] and a moment of inertia is about the z axis through the centre of mass [kg m^2].

>>> Sphere(0.1).moment_of_inertia(mass=2.0)  # 2/5 m a^2 [kg m^2]
0.008000000000000002
>>> Box(0.3, 0.4).mass_properties(mass=2.0).inertia  # m (w^2 + h^2)/12 [kg m^2]
0.04166666666666667
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from carom._inputs import finite_positive
from carom.errors import CaromError
from carom.geometry.outline import (
    MassIntegrals,
    convex_outline,
    hull,
    outward_normals,
    rounded_polygon_integrals,
)
from carom.laws.spheres import default_inertia_factor
from carom.limits import check_magnitude
from carom.shape_base import (
    CapsuleSize,
    RoundSize,
    ShapeBase,
    compound_part,
    compound_pieces,
)

__all__ = [
    "Box",
    "Capsule",
    "Chain",
    "Circle",
    "Compound",
    "ConvexPiece",
    "MassProperties",
    "Polygon",
    "Segment",
    "Shape2D",
    "Sphere",
    "check_inertia_factor",
    "default_inertia_factor",
]

FloatArray = NDArray[np.float64]


def check_inertia_factor(q: float) -> float:
    """``q`` if it is a valid factor in ``I = q m a^2``, in (0, 1]; else a CaromError."""
    if isinstance(q, bool) or not isinstance(q, int | float) or not 0.0 < q <= 1.0:
        raise CaromError(
            f"inertia_factor must lie in (0, 1] (I = q m a^2; 2/5 solid sphere, 2/3 shell, "
            f"1/2 disk); got {q!r}"
        )
    return float(q)


@dataclass(frozen=True)
class Sphere:
    """A sphere (a disk in 2D).

    Parameters
    ----------
    radius : float
        [m], positive.
    inertia_factor : float, optional
        ``q`` in the moment of inertia ``I = q m a^2`` [-], in (0, 1]: 2/5 for a solid
        sphere (the default in 3D), 2/3 for a thin shell, 1/2 for a disk (the default in 2D).
    """

    radius: float
    inertia_factor: float | None = None

    def __post_init__(self) -> None:
        if not (self.radius > 0.0 and math.isfinite(self.radius)):
            raise CaromError(f"radius must be positive and finite [m]; got {self.radius!r}")
        if self.inertia_factor is not None:
            check_inertia_factor(self.inertia_factor)

    def moment_of_inertia(self, mass: float, dim: int = 3) -> float:
        """``q m a^2`` about any axis through the centre [kg m^2]."""
        q = self.inertia_factor if self.inertia_factor is not None else default_inertia_factor(dim)
        return q * mass * self.radius**2


def _points(name: str, value: ArrayLike, count: int | None = None) -> FloatArray:
    """``value`` as finite (k, 2) float64 points, else a CaromError naming the bad entry."""
    try:
        points = np.array(value, dtype=float)
    except (TypeError, ValueError):
        raise CaromError(f"{name} must be a list of [x, y] points [m]; got {value!r}") from None
    if count is not None and points.shape == (2,) and count == 1:
        points = points[None, :]
    if points.ndim != 2 or points.shape[1] != 2 or (count is not None and points.shape[0] != count):
        want = f"{count} " if count is not None else ""
        raise CaromError(
            f"{name} must be {want}[x, y] points (shape ({count or 'k'}, 2)) [m]; "
            f"got shape {points.shape}"
        )
    bad = np.flatnonzero(~np.isfinite(points).all(axis=1))
    if bad.size:
        i = int(bad[0])
        raise CaromError(f"{name}[{i}] = {points[i].tolist()} is not finite; give numbers [m]")
    return check_magnitude(name, points, "m")


@dataclass(frozen=True)
class MassProperties:
    """Mass, centre of mass and moment of inertia of a 2D body.

    Attributes
    ----------
    mass : float
        [kg].
    centroid : (2,) float64
        Centre of mass in the shape's frame [m].
    inertia : float
        Moment of inertia about the z axis through the centre of mass [kg m^2].
    """

    mass: float
    centroid: FloatArray
    inertia: float


@dataclass(frozen=True, eq=False)
class ConvexPiece:
    """A rounded convex polygon: the points within ``radius`` of the core polygon.

    Parameters
    ----------
    vertices : (k, 2) float64
        The core's corners, counter-clockwise [m]: one for a circle, two for a capsule or a
        segment, three or more for a polygon.
    radius : float
        Rounding radius [m], >= 0 (positive when k < 3, except a static segment).
    """

    vertices: FloatArray
    radius: float

    @property
    def normals(self) -> FloatArray:
        """Unit outward normal of each core edge ``i -> i+1``, (k, 2); empty for a circle."""
        if self.vertices.shape[0] < 2:
            return np.zeros((0, 2))
        return outward_normals(self.vertices)

    @property
    def reach(self) -> float:
        """The farthest point of the piece from its frame's origin [m]."""
        return float(np.max(np.hypot(self.vertices[:, 0], self.vertices[:, 1]))) + self.radius

    def moved(self, offset: FloatArray, angle: float) -> ConvexPiece:
        """The piece turned by ``angle`` [rad] about the origin, then moved by ``offset`` [m]."""
        c, s = math.cos(angle), math.sin(angle)
        turned = self.vertices @ np.array([[c, s], [-s, c]])
        return ConvexPiece(turned + offset, self.radius)

    def integrals(self) -> MassIntegrals:
        """Area and moments about the frame's origin (per unit density)."""
        return rounded_polygon_integrals(self.vertices, self.radius)


class Shape2D(ShapeBase[ConvexPiece, MassIntegrals, MassProperties]):
    """A 2D shape for the rigid-body engine: a list of rounded convex pieces in its own frame
    (:class:`carom.shape_base.ShapeBase`: ``integrals``, ``mass_properties`` from a density
    [kg/m^2] or a mass, giving a :class:`MassProperties`)."""

    INTEGRALS = MassIntegrals
    MEASURE = "area"
    DENSITY_UNIT = "kg/m^2"

    @staticmethod
    def _properties(density: float, integrals: MassIntegrals) -> MassProperties:
        return MassProperties(
            density * integrals.area, integrals.centroid, density * integrals.second_about_centroid
        )

    @property
    def area(self) -> float:
        """[m^2]."""
        return self.integrals().area

    @property
    def centroid(self) -> FloatArray:
        """Centre of the area in the shape's frame [m], (2,)."""
        integrals = self.integrals()
        if integrals.area <= 0.0:
            return np.zeros(2)
        return integrals.centroid


@dataclass(frozen=True)
class Circle(RoundSize, Shape2D):
    """A disk of ``radius`` [m]: ``I = m r^2/2``."""

    kind = "circle"

    def pieces(self) -> tuple[ConvexPiece, ...]:
        return (ConvexPiece(np.zeros((1, 2)), float(self.radius)),)


@dataclass(frozen=True)
class Capsule(CapsuleSize, Shape2D):
    """A stadium: the points within ``radius`` [m] of a segment of ``length`` [m] along the x
    axis (:class:`carom.shape_base.CapsuleSize`)."""

    def pieces(self) -> tuple[ConvexPiece, ...]:
        h = float(self.length) / 2.0
        return (ConvexPiece(np.array([[-h, 0.0], [h, 0.0]]), float(self.radius)),)


@dataclass(frozen=True)
class Box(Shape2D):
    """A ``width`` x ``height`` rectangle centred on the origin [m], optionally rounded.

    With ``radius`` the corners are rounded and the box grows by ``radius`` on every side.
    ``I = m (w^2 + h^2)/12`` when sharp.
    """

    width: float
    height: float
    radius: float = 0.0
    kind = "box"

    def __post_init__(self) -> None:
        finite_positive("Box width", self.width, "m")
        finite_positive("Box height", self.height, "m")
        finite_positive("Box radius", self.radius, "m", zero=True)

    def pieces(self) -> tuple[ConvexPiece, ...]:
        w, h = float(self.width) / 2.0, float(self.height) / 2.0
        corners = np.array([[-w, -h], [w, -h], [w, h], [-w, h]])
        return (ConvexPiece(corners, float(self.radius)),)


@dataclass(frozen=True, eq=False)
class Polygon(Shape2D):
    """A convex polygon through ``vertices``, optionally rounded by ``radius``.

    The outline may run either way round; points along an edge and repeats are dropped.
    A concave outline, one that crosses itself, or one with no area is refused with a message
    (build concave bodies as a :class:`Compound`).

    Parameters
    ----------
    vertices : (k, 2) array_like
        The outline [m], k >= 3, any number of vertices.
    radius : float, default 0
        Rounding radius [m].
    """

    vertices: Any
    radius: float = 0.0
    corners: FloatArray = field(init=False, repr=False)
    kind = "polygon"

    def __post_init__(self) -> None:
        points = _points("Polygon vertices", self.vertices)
        finite_positive("Polygon radius", self.radius, "m", zero=True)
        object.__setattr__(self, "corners", convex_outline(points, "Polygon vertices"))

    @classmethod
    def regular(cls, sides: int, circumradius: float, radius: float = 0.0) -> Polygon:
        """A regular polygon with a corner on the +x axis, centred on the origin."""
        if isinstance(sides, bool) or not isinstance(sides, int) or sides < 3:
            raise CaromError(f"sides must be an integer >= 3; got {sides!r}")
        finite_positive("circumradius", circumradius, "m")
        phi = 2.0 * np.pi * np.arange(sides) / sides
        return cls(circumradius * np.stack([np.cos(phi), np.sin(phi)], axis=1), radius)

    @classmethod
    def hull_of(cls, points: ArrayLike, radius: float = 0.0) -> Polygon:
        """The convex hull of any points (their order and inner points do not matter)."""
        cloud = _points("points", points)
        return cls(cloud[hull(cloud)], radius)

    def pieces(self) -> tuple[ConvexPiece, ...]:
        return (ConvexPiece(self.corners, float(self.radius)),)


@dataclass(frozen=True, eq=False)
class Compound(Shape2D):
    """Several convex pieces on one rigid body: an L, a cup, a gear, a concave hull.

    Parameters
    ----------
    parts : sequence of shape, (shape, offset) or (shape, offset, angle)
        Each part is placed by turning it by ``angle`` [rad] about its own origin, then moving
        it by ``offset`` [m]. Parts may touch but should not overlap: overlapping area counts
        twice in the mass.
    """

    parts: Sequence[Any]
    placed: tuple[ConvexPiece, ...] = field(init=False, repr=False)
    kind = "compound"

    def __post_init__(self) -> None:
        object.__setattr__(self, "placed", compound_pieces(self.parts, Shape2D, "angle", _placed))

    def pieces(self) -> tuple[ConvexPiece, ...]:
        return self.placed


def _placed(i: int, part: Any) -> list[ConvexPiece]:
    """Compound part ``i``'s pieces, turned and moved, or a CaromError naming the part."""
    shape, at, turn = compound_part(i, part, Shape2D, "angle")
    offset = np.zeros(2) if at is None else _points(f"Compound part {i} offset", at, count=1)[0]
    angle = 0.0 if turn is None else float(turn)
    if not math.isfinite(angle):
        raise CaromError(f"Compound part {i} angle must be finite [rad]; got {turn!r}")
    if isinstance(shape, Segment | Chain):
        raise CaromError(
            f"Compound part {i}: a {shape.kind} has no area; it can only be a static body of "
            "its own"
        )
    return [piece.moved(offset, angle) for piece in shape.pieces()]


@dataclass(frozen=True, eq=False)
class Segment(Shape2D):
    """A static line segment from ``p1`` to ``p2`` [m], thickened by ``radius`` (default 0).

    With no radius a segment has no area: it can only be a static body (terrain, a wall).
    """

    p1: Any
    p2: Any
    radius: float = 0.0
    ends: FloatArray = field(init=False, repr=False)
    kind = "segment"

    def __post_init__(self) -> None:
        ends = np.concatenate(
            [_points("Segment p1", self.p1, count=1), _points("Segment p2", self.p2, count=1)]
        )
        if np.array_equal(ends[0], ends[1]):
            raise CaromError(f"Segment p1 and p2 are the same point {ends[0].tolist()}; move one")
        finite_positive("Segment radius", self.radius, "m", zero=True)
        object.__setattr__(self, "ends", ends)

    def pieces(self) -> tuple[ConvexPiece, ...]:
        return (ConvexPiece(self.ends, float(self.radius)),)


@dataclass(frozen=True, eq=False)
class Chain(Shape2D):
    """Static terrain: the segments joining ``points`` in order (closed when ``loop``).

    A chain may be concave (a valley, a bowl, the inside of a tumbler); bodies meet its
    segments from either side.
    """

    points: Any
    loop: bool = False
    radius: float = 0.0
    vertices: FloatArray = field(init=False, repr=False)
    kind = "chain"

    def __post_init__(self) -> None:
        points = _points("Chain points", self.points)
        need = 3 if self.loop else 2
        if points.shape[0] < need:
            raise CaromError(
                f"a {'closed ' if self.loop else ''}Chain needs at least {need} points; "
                f"got {points.shape[0]}"
            )
        same = np.flatnonzero(np.all(points == np.roll(points, -1, axis=0), axis=1))
        same = same[same < points.shape[0] - (0 if self.loop else 1)]
        if same.size:
            i = int(same[0])
            raise CaromError(
                f"Chain points[{i}] and points[{(i + 1) % points.shape[0]}] are the same point "
                f"{points[i].tolist()}; drop one"
            )
        finite_positive("Chain radius", self.radius, "m", zero=True)
        object.__setattr__(self, "vertices", points)

    def pieces(self) -> tuple[ConvexPiece, ...]:
        k = self.vertices.shape[0]
        count = k if self.loop else k - 1
        ends = [np.array([self.vertices[i], self.vertices[(i + 1) % k]]) for i in range(count)]
        return tuple(ConvexPiece(pair, float(self.radius)) for pair in ends)
