"""Shapes in 3D for the rigid-body engine: what a body is, as data only (no pose, no engine).

:class:`Sphere`, :class:`Capsule` (along z), :class:`Box`, :class:`Hull` (the convex hull of
points, through qhull) and :class:`Compound` (several convex pieces on one rigid body: a
concave body); :class:`Plane` is static ground. Each solid is a list of *rounded convex
pieces* (:class:`ConvexPiece3D`: a core of 1 point (a ball), 2 points (a capsule) or a convex
polyhedron, and a radius), so the contact functions and the mass formulas serve them all.

Mass properties are exact (:mod:`carom.geometry.mass3d`): a density is per volume [kg/m^3];
the inertia tensor is about the centre of mass, in the shape's frame [kg m^2]. Rotations are
unit quaternions ``(w, x, y, z)`` or 3x3 matrices, shape to parent.

>>> float(Box([0.3, 0.4, 0.5]).mass_properties(mass=2.0).inertia[2, 2])  # m (a^2 + b^2)/12
0.04166666666666667
>>> round(float(Sphere(0.1).mass_properties(mass=2.0).inertia[0, 0]), 15)  # 2/5 m r^2 [kg m^2]
0.008
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
from carom.geometry.mass3d import (
    SolidIntegrals,
    box_integrals,
    capsule_integrals,
    check_closed,
    inertia_tensor,
    polyhedron_integrals,
    sphere_integrals,
)
from carom.geometry.rotation import rotation_matrices, turn_z_onto
from carom.limits import check_magnitude
from carom.shape_base import CapsuleSize, RoundSize, ShapeBase, compound_part, compound_pieces

__all__ = [
    "Box",
    "Capsule",
    "Compound",
    "ConvexPiece3D",
    "Hull",
    "MassProperties3D",
    "Plane",
    "Shape3D",
    "Sphere",
    "TrianglePieces",
    "rotation_matrix",
]

FloatArray = NDArray[np.float64]


def _vector(name: str, value: ArrayLike, unit: str) -> FloatArray:
    """A finite (3,) vector, or a CaromError naming it."""
    try:
        out = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        raise CaromError(f"{name} must be 3 numbers [{unit}]; got {value!r}") from None
    if out.shape != (3,) or not np.all(np.isfinite(out)):
        raise CaromError(f"{name} must be 3 finite numbers [{unit}]; got {value!r}")
    return out


def rotation_matrix(rotation: ArrayLike, name: str = "rotation") -> FloatArray:
    """A rotation as a 3x3 matrix, from a unit quaternion ``(w, x, y, z)`` (normalised here;
    a zero one is refused) or a matrix (refused unless orthonormal with determinant +1 to
    1e-9).

    >>> rotation_matrix([math.cos(math.pi / 4), 0, 0, math.sin(math.pi / 4)]).round(12)[0]
    array([ 0., -1.,  0.])
    """
    try:
        r = np.asarray(rotation, dtype=float)
    except (TypeError, ValueError):
        raise CaromError(f"{name} must be a quaternion (w, x, y, z) or a 3x3 matrix") from None
    if not np.all(np.isfinite(r)):
        raise CaromError(f"{name} must be finite; got {rotation!r}")
    if r.shape == (4,):
        norm = float(np.linalg.norm(r))
        if norm == 0.0:
            raise CaromError(
                f"{name}: the quaternion (0, 0, 0, 0) is no rotation; use (1, 0, 0, 0)"
            )
        turned: FloatArray = rotation_matrices(r / norm)[0]
        return turned
    if r.shape == (3, 3):
        if np.max(np.abs(r @ r.T - np.eye(3))) > 1e-9 or abs(np.linalg.det(r) - 1.0) > 1e-9:
            raise CaromError(f"{name}: a 3x3 matrix must be a rotation (orthonormal, det +1)")
        return r.copy()
    raise CaromError(f"{name} must be a quaternion (w, x, y, z) or a 3x3 matrix; got {rotation!r}")


@dataclass(frozen=True)
class MassProperties3D:
    """A 3D body's ``mass`` [kg], its ``centroid`` (3,) [m] in the shape's frame and its
    ``inertia`` (3, 3) [kg m^2]: the tensor about the centre of mass along the shape's axes,
    symmetric and positive definite.
    """

    mass: float
    centroid: FloatArray
    inertia: FloatArray

    def principal(self) -> tuple[FloatArray, FloatArray]:
        """Principal moments [kg m^2] (3,) ascending, and the axes as the columns of a
        rotation matrix (3, 3) (right-handed): ``inertia = axes @ diag(moments) @ axes.T``."""
        moments, axes = np.linalg.eigh(self.inertia)
        if np.linalg.det(axes) < 0.0:
            axes[:, 2] = -axes[:, 2]
        return moments, axes


@dataclass(frozen=True, eq=False)
class ConvexPiece3D:
    """A rounded convex solid: the points within ``radius`` of a convex core.

    Parameters
    ----------
    vertices : (k, 3) float64
        The core's corners [m]: one for a ball, two for a capsule, four or more for a
        polyhedron (then ``radius`` is 0).
    triangles : (F, 3) int64
        The polyhedron's faces, outward counter-clockwise; empty for k < 4.
    radius : float
        [m], >= 0.
    """

    vertices: FloatArray
    triangles: NDArray[np.int64]
    radius: float

    @property
    def reach(self) -> float:
        """The farthest point of the piece from its frame's origin [m]."""
        return float(np.max(np.linalg.norm(self.vertices, axis=1))) + self.radius

    def moved(self, rotation: FloatArray, offset: FloatArray) -> ConvexPiece3D:
        """The piece turned by ``rotation`` (3, 3) about the origin, then moved by ``offset``."""
        return ConvexPiece3D(self.vertices @ rotation.T + offset, self.triangles, self.radius)

    def integrals(self) -> SolidIntegrals:
        """Volume and moments about the frame's origin (per unit density)."""
        k = self.vertices.shape[0]
        if k >= 4:
            return polyhedron_integrals(self.vertices, self.triangles)
        if k == 1:
            return sphere_integrals(self.radius).moved(np.eye(3), self.vertices[0])
        # a capsule between two points: the one along z, turned onto the segment
        a, b = self.vertices
        axis = b - a
        length = float(np.linalg.norm(axis))
        return capsule_integrals(self.radius, length).moved(
            turn_z_onto(axis / length), 0.5 * (a + b)
        )


class TrianglePieces(Sequence[ConvexPiece3D]):
    """A static mesh's triangles as a body's pieces, held as two arrays, not one object a
    triangle: a terrain of millions of triangles is added, built and saved in seconds
    (issue 45). Each triangle reads as a flat :class:`ConvexPiece3D` (three corners, one
    face, radius 0), made when it is asked for.

    Parameters
    ----------
    vertices : (V, 3) float64
        The corners [m], in the body's frame.
    triangles : (T, 3) int64
        Each triangle's corners, counter-clockwise seen from its front.
    """

    def __init__(self, vertices: ArrayLike, triangles: ArrayLike) -> None:
        self.vertices: FloatArray = np.asarray(vertices, dtype=np.float64)
        self.triangles: NDArray[np.int64] = np.asarray(triangles, dtype=np.int64)

    def __len__(self) -> int:
        return int(self.triangles.shape[0])

    def __getitem__(self, i: Any) -> Any:
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        return ConvexPiece3D(self.vertices[self.triangles[i]], _ONE_FACE, 0.0)

    @property
    def reach(self) -> float:
        """The farthest corner of any triangle from the frame's origin [m]."""
        used = self.vertices[np.unique(self.triangles)]
        return float(np.max(np.linalg.norm(used, axis=1))) if used.size else 0.0

    def corners(self) -> FloatArray:
        """Every triangle's corners, (T, 3, 3) [m]."""
        corners: FloatArray = self.vertices[self.triangles]
        return corners


#: a flat piece's one face
_ONE_FACE = np.array([[0, 1, 2]], np.int64)


class Shape3D(ShapeBase[ConvexPiece3D, SolidIntegrals, MassProperties3D]):
    """A 3D solid made of rounded convex pieces in its own frame. Its integrals, and its mass
    properties (a :class:`MassProperties3D`) from a density [kg/m^3] or a mass, are
    :class:`carom.shape_base.ShapeBase`'s."""

    MEASURE = "volume"
    DENSITY_UNIT = "kg/m^3"
    INTEGRALS = SolidIntegrals

    @staticmethod
    def _properties(density: float, integrals: SolidIntegrals) -> MassProperties3D:
        return MassProperties3D(
            density * integrals.volume,
            integrals.centroid,
            density * inertia_tensor(integrals.second_about_centroid()),
        )

    @property
    def volume(self) -> float:
        """[m^3]."""
        return self.integrals().volume

    @property
    def centroid(self) -> FloatArray:
        """Centre of the volume in the shape's frame [m], (3,)."""
        return self.integrals().centroid


@dataclass(frozen=True)
class Sphere(RoundSize, Shape3D):
    """A ball of ``radius`` [m]: ``I = 2/5 m r^2`` about any axis."""

    kind = "sphere"

    def pieces(self) -> tuple[ConvexPiece3D, ...]:
        return (ConvexPiece3D(np.zeros((1, 3)), np.zeros((0, 3), np.int64), float(self.radius)),)


@dataclass(frozen=True)
class Capsule(CapsuleSize, Shape3D):
    """The points within ``radius`` [m] of a segment of ``length`` [m] along the z axis
    (:class:`carom.shape_base.CapsuleSize`)."""

    def pieces(self) -> tuple[ConvexPiece3D, ...]:
        h = float(self.length) / 2.0
        ends = np.array([[0.0, 0.0, -h], [0.0, 0.0, h]])
        return (ConvexPiece3D(ends, np.zeros((0, 3), np.int64), float(self.radius)),)


# the 12 outward triangles of a box's 8 corners, corner i at (+-a, +-b, +-c) by the bits of i
_BOX_TRIANGLES = np.array(
    [
        [0, 3, 2], [0, 1, 3],  # x = -a
        [4, 7, 5], [4, 6, 7],  # x = +a
        [0, 5, 1], [0, 4, 5],  # y = -b
        [2, 7, 6], [2, 3, 7],  # y = +b
        [0, 6, 4], [0, 2, 6],  # z = -c
        [1, 7, 3], [1, 5, 7],  # z = +c
    ],
    np.int64,
)  # fmt: skip


@dataclass(frozen=True, eq=False)
class Box(Shape3D):
    """A box of full edge lengths ``size`` = (a, b, c) [m] along x, y, z, centred on the
    origin: ``I = m diag(b^2 + c^2, a^2 + c^2, a^2 + b^2)/12``."""

    size: Sequence[float] | FloatArray
    kind = "box"

    def __post_init__(self) -> None:
        size = _vector("Box size", self.size, "m")
        for axis, value in zip("xyz", size, strict=True):
            finite_positive(f"Box size along {axis}", float(value), "m")
        object.__setattr__(self, "size", size)

    def corners(self) -> FloatArray:
        """The 8 corners (8, 3) [m], corner i at (+-a, +-b, +-c)/2 by the bits of i (x: 4,
        y: 2, z: 1)."""
        half = 0.5 * np.asarray(self.size)
        bits = np.array([[(i >> 2) & 1, (i >> 1) & 1, i & 1] for i in range(8)], float)
        return (2.0 * bits - 1.0) * half

    def integrals(self) -> SolidIntegrals:
        return box_integrals(np.asarray(self.size))

    def pieces(self) -> tuple[ConvexPiece3D, ...]:
        return (ConvexPiece3D(self.corners(), _BOX_TRIANGLES, 0.0),)


@dataclass(frozen=True, eq=False)
class Hull(Shape3D):
    """The convex hull of ``points`` (qhull, through :class:`scipy.spatial.ConvexHull`).

    Points inside the hull are dropped; flat or degenerate point sets (all on one plane or
    line) are refused. Needs SciPy (``pip install carom[rigid3d]``).

    Parameters
    ----------
    points : (k, 3) float64
        [m], k >= 4 not all on one plane.
    """

    points: ArrayLike
    vertices: FloatArray = field(init=False, repr=False)
    triangles: NDArray[np.int64] = field(init=False, repr=False)
    kind = "hull"

    def __post_init__(self) -> None:
        vertices, triangles = convex_hull(self.points)
        object.__setattr__(self, "vertices", vertices)
        object.__setattr__(self, "triangles", triangles)

    def pieces(self) -> tuple[ConvexPiece3D, ...]:
        return (ConvexPiece3D(self.vertices, self.triangles, 0.0),)


def convex_hull(points: ArrayLike, name: str = "Hull") -> tuple[FloatArray, NDArray[np.int64]]:
    """The hull's corners (h, 3) and its outward triangles (F, 3) of ``points`` (k, 3) [m]."""
    try:
        p = np.asarray(points, dtype=float)
    except (TypeError, ValueError):
        raise CaromError(f"{name} points must be a (k, 3) list of numbers [m]") from None
    if p.ndim != 2 or p.shape[1] != 3 or p.shape[0] < 4:
        raise CaromError(f"{name} needs at least 4 points as (k, 3) [m]; got shape {p.shape}")
    bad = np.flatnonzero(~np.all(np.isfinite(p), axis=1))
    if bad.size:
        i = int(bad[0])
        raise CaromError(f"{name} point {i} = {p[i].tolist()} is not finite; give numbers [m]")
    p = check_magnitude(f"{name} points", p, "m")
    try:
        from scipy.spatial import ConvexHull, QhullError
    except ImportError:
        raise CaromError(
            f"{name} needs SciPy for qhull: pip install 'carom[rigid3d]' (or scipy)"
        ) from None
    try:
        qhull = ConvexHull(p)
    except QhullError:
        raise CaromError(
            f"{name}: the points are flat (all on one plane or line) and enclose no volume; "
            "give points that span 3D, or use a Box for a thin slab"
        ) from None
    keep = np.asarray(qhull.vertices, np.int64)
    index = np.full(p.shape[0], -1, np.int64)
    index[keep] = np.arange(keep.size)
    triangles = index[np.asarray(qhull.simplices, np.int64)]
    # qhull's facets come in no fixed turn: make each one's normal (right-hand rule) agree
    # with the facet's outward plane normal, qhull's ``equations``
    corners = p[keep]
    normals = np.cross(
        corners[triangles[:, 1]] - corners[triangles[:, 0]],
        corners[triangles[:, 2]] - corners[triangles[:, 0]],
    )
    flip = np.einsum("ij,ij->i", normals, qhull.equations[:, :3]) < 0.0
    triangles[flip] = triangles[flip][:, [0, 2, 1]]
    check_closed(triangles, corners.shape[0], name)
    return corners, triangles


@dataclass(frozen=True, eq=False)
class Compound(Shape3D):
    """Several convex pieces on one rigid body: a table, a dumbbell, a mug.

    Parameters
    ----------
    parts : sequence of shape, (shape, offset) or (shape, offset, rotation)
        Each part is placed by turning it by ``rotation`` (a quaternion (w, x, y, z) or a 3x3
        matrix) about its own origin, then moving it by ``offset`` [m]. Parts may touch but
        should not overlap: overlapping volume counts twice in the mass.
    solid : SolidIntegrals, optional
        The body's own volume integrals, when known better than the parts' sum: a mesh cut
        into convex pieces (:func:`carom.meshes.decompose`) weighs what the closed mesh
        weighs, not what its slightly overlapping pieces add up to.
    """

    parts: Sequence[Any]
    solid: SolidIntegrals | None = field(default=None, kw_only=True)
    placed: tuple[ConvexPiece3D, ...] = field(init=False, repr=False)
    kind = "compound"

    def __post_init__(self) -> None:
        placed = compound_pieces(self.parts, Shape3D, "rotation", _placed)
        object.__setattr__(self, "placed", placed)

    def pieces(self) -> tuple[ConvexPiece3D, ...]:
        return self.placed

    def integrals(self) -> SolidIntegrals:
        return self.solid if self.solid is not None else super().integrals()


def _placed(i: int, part: Any) -> list[ConvexPiece3D]:
    """Compound part ``i``'s pieces, turned and moved, or a CaromError naming the part."""
    unbounded = f"Compound part {i}: a Plane is unbounded; it can only be static ground"
    if isinstance(part, Plane):
        raise CaromError(unbounded)
    shape, at, turn = compound_part(i, part, Shape3D, "rotation")
    if isinstance(shape, Plane):
        raise CaromError(unbounded)
    offset = np.zeros(3) if at is None else _vector(f"Compound part {i} offset", at, "m")
    rotation = np.eye(3) if turn is None else rotation_matrix(turn, f"Compound part {i} rotation")
    return [piece.moved(rotation, offset) for piece in shape.pieces()]


@dataclass(frozen=True, eq=False)
class Plane(Shape3D):
    """Static ground: the half-space below the plane ``normal . x = offset``.

    Parameters
    ----------
    normal : (3,) float64
        Points out of the solid side [-]; normalised here.
    offset : float
        The plane's distance from the origin along ``normal`` [m].
    """

    normal: Sequence[float] | FloatArray = (0.0, 0.0, 1.0)
    offset: float = 0.0
    kind = "plane"

    def __post_init__(self) -> None:
        n = _vector("Plane normal", self.normal, "-")
        norm = float(np.linalg.norm(n))
        if norm == 0.0:
            raise CaromError("Plane normal (0, 0, 0) has no direction; e.g. (0, 0, 1) for a floor")
        object.__setattr__(self, "normal", n / norm)
        if not math.isfinite(float(self.offset)):
            raise CaromError(f"Plane offset must be finite [m]; got {self.offset!r}")

    def pieces(self) -> tuple[ConvexPiece3D, ...]:
        raise CaromError("a Plane is unbounded: it has no pieces and no mass; make it static")

    def integrals(self) -> SolidIntegrals:
        raise CaromError("a Plane is unbounded: it has no mass; make it a static body")
