"""Exact mass properties of solids in 3D (NumPy; used when shapes are built, never per step).

A closed polyhedron's volume integrals follow from the divergence theorem as sums over its
faces (Mirtich, "Fast and accurate computation of polyhedral mass properties", J. Graphics
Tools 1(2), 1996). carom takes the equivalent and shorter route of signed tetrahedra (Tonon,
"Explicit exact formulas for the 3-D tetrahedron inertia tensor in terms of its vertex
coordinates", J. Math. Stat. 1(1), 2004): each outward triangle ``(p0, p1, p2)`` and the
origin span a tetrahedron of signed volume ``D/6``, ``D = p0 . (p1 x p2)``, and

    int 1 dV = D/6,    int x dV = D/24 (p0 + p1 + p2),
    int x x^T dV = D/120 (p0 p0^T + p1 p1^T + p2 p2^T + s s^T),   s = p0 + p1 + p2,

summed over the faces: the parts outside the solid cancel, so the sums are exact for any
closed, consistently outward polyhedron, convex or not. The vertices are first shifted to
their mean, so a solid far from the origin loses no digits to cancellation.

Round solids (sphere, capsule, cylinder) have their closed forms here too, all as
:class:`SolidIntegrals` (per unit density) that add, move and turn, so a compound of any
pieces is a sum.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from carom.errors import CaromError

__all__ = [
    "SolidIntegrals",
    "box_integrals",
    "capsule_integrals",
    "check_closed",
    "inertia_tensor",
    "polyhedron_integrals",
    "sphere_integrals",
]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class SolidIntegrals:
    """Volume integrals of a solid about its frame's origin, per unit density.

    Attributes
    ----------
    volume : float
        ``int 1 dV`` [m^3].
    first : (3,) float64
        ``int x dV`` [m^4].
    second : (3, 3) float64
        ``int x x^T dV`` [m^5] (symmetric).
    """

    volume: float
    first: FloatArray
    second: FloatArray

    def __add__(self, other: SolidIntegrals) -> SolidIntegrals:
        return SolidIntegrals(
            self.volume + other.volume, self.first + other.first, self.second + other.second
        )

    @classmethod
    def zero(cls) -> SolidIntegrals:
        """The integrals of nothing."""
        return cls(0.0, np.zeros(3), np.zeros((3, 3)))

    @property
    def measure(self) -> float:
        """The volume [m^3] (a region's measure is its area)."""
        return self.volume

    @property
    def centroid(self) -> FloatArray:
        """Centre of the volume [m], (3,)."""
        return self.first / self.volume

    def second_about_centroid(self) -> FloatArray:
        """``int (x - c)(x - c)^T dV`` about the centroid ``c`` [m^5], (3, 3)."""
        c = self.centroid
        return self.second - self.volume * np.outer(c, c)

    def moved(self, rotation: FloatArray, offset: FloatArray) -> SolidIntegrals:
        """The integrals of the solid turned by ``rotation`` (3, 3) about the origin, then
        moved by ``offset`` [m] (3,): ``x -> R x + t``."""
        r = np.asarray(rotation, float)
        t = np.asarray(offset, float)
        f = r @ self.first
        second = r @ self.second @ r.T + np.outer(f, t) + np.outer(t, f)
        second += self.volume * np.outer(t, t)
        return SolidIntegrals(self.volume, f + self.volume * t, 0.5 * (second + second.T))


def inertia_tensor(second: FloatArray) -> FloatArray:
    """The inertia tensor ``int (|x|^2 I - x x^T) dV`` from ``int x x^T dV`` (3, 3)."""
    tensor: FloatArray = np.trace(second) * np.eye(3) - second
    return tensor


def polyhedron_integrals(vertices: FloatArray, triangles: NDArray[np.int64]) -> SolidIntegrals:
    """Exact volume integrals of a closed polyhedron (module docstring).

    Parameters
    ----------
    vertices : (V, 3) float64
        Corners [m].
    triangles : (F, 3) int64
        Faces as corner indices, counter-clockwise seen from outside (outward normals by the
        right-hand rule).

    Returns
    -------
    SolidIntegrals
        About the frame's origin.

    Examples
    --------
    >>> corners = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], float)
    >>> faces = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    >>> round(polyhedron_integrals(corners, faces).volume, 12)  # 1/6 [m^3]
    0.166666666667
    """
    points = np.asarray(vertices, float)
    faces = np.asarray(triangles, np.int64)
    shift = points.mean(axis=0)
    p0 = points[faces[:, 0]] - shift
    p1 = points[faces[:, 1]] - shift
    p2 = points[faces[:, 2]] - shift
    d = np.einsum("ij,ij->i", p0, np.cross(p1, p2))
    s = p0 + p1 + p2
    volume = float(d.sum()) / 6.0
    first = (d[:, None] * s).sum(axis=0) / 24.0
    outer = (
        np.einsum("i,ij,ik->jk", d, p0, p0)
        + np.einsum("i,ij,ik->jk", d, p1, p1)
        + np.einsum("i,ij,ik->jk", d, p2, p2)
        + np.einsum("i,ij,ik->jk", d, s, s)
    ) / 120.0
    local = SolidIntegrals(volume, first, 0.5 * (outer + outer.T))
    return local.moved(np.eye(3), shift)


def box_integrals(size: FloatArray) -> SolidIntegrals:
    """A box of full edge lengths ``size`` (3,) [m], centred on the origin, axes along the
    frame's: ``V = a b c``, ``int x^2 dV = V a^2 / 12`` and the like."""
    a, b, c = (float(x) for x in size)
    volume = a * b * c
    return SolidIntegrals(volume, np.zeros(3), np.diag([a * a, b * b, c * c]) * volume / 12.0)


def sphere_integrals(radius: float) -> SolidIntegrals:
    """A ball of ``radius`` [m] centred on the origin: ``V = 4/3 pi r^3``,
    ``int x^2 dV = V r^2 / 5``."""
    volume = 4.0 / 3.0 * math.pi * radius**3
    return SolidIntegrals(volume, np.zeros(3), np.eye(3) * volume * radius * radius / 5.0)


def capsule_integrals(radius: float, length: float) -> SolidIntegrals:
    """A capsule along z centred on the origin: the points within ``radius`` [m] of the
    segment from ``z = -length/2`` to ``+length/2`` [m].

    A cylinder (``V_c = pi r^2 L``; ``int x^2 = V_c r^2/4``, ``int z^2 = V_c L^2/12``) and two
    half balls whose centres sit at ``+-L/2``: a half ball of volume ``V_h = 2/3 pi r^3`` has
    ``int x^2 = V_h r^2/5`` and, measured from its flat face, ``int z^2 = V_h r^2/5`` and
    ``int z = V_h 3r/8``; moved out by ``L/2``, ``int z^2 = V_h (r^2/5 + 3 r L/8 + L^2/4)``.
    """
    r = float(radius)
    half = 0.5 * float(length)
    cylinder = math.pi * r * r * 2.0 * half
    caps = 4.0 / 3.0 * math.pi * r**3  # both half balls
    xx = cylinder * r * r / 4.0 + caps * r * r / 5.0
    zz = cylinder * (2.0 * half) ** 2 / 12.0 + caps * (r * r / 5.0 + 0.75 * r * half + half * half)
    return SolidIntegrals(cylinder + caps, np.zeros(3), np.diag([xx, xx, zz]))


def check_closed(triangles: NDArray[np.int64], count: int, name: str = "mesh") -> None:
    """Refuse a triangle list that is not a closed, consistently oriented surface: each
    directed edge must appear once and its reverse once (a CaromError naming the first edge
    that does not)."""
    faces = np.asarray(triangles, np.int64)
    if faces.ndim != 2 or faces.shape[1] != 3 or faces.shape[0] < 4:
        raise CaromError(f"{name}: needs at least 4 triangles as (F, 3) corner indices")
    if faces.min() < 0 or faces.max() >= count:
        raise CaromError(f"{name}: a triangle names a corner outside 0..{count - 1}")
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]], faces[:, [2, 0]]])
    # (sorted keys rather than np.unique and np.isin: 2e5 triangles in milliseconds)
    keys = np.sort(edges[:, 0] * count + edges[:, 1])
    twice = keys[1:] == keys[:-1]
    if np.any(twice):
        k = int(keys[np.argmax(twice)])
        raise CaromError(
            f"{name}: edge {k // count} -> {k % count} is used twice the same way: the faces "
            "are not consistently oriented (or the surface is not manifold)"
        )
    reverse = edges[:, 1] * count + edges[:, 0]
    # every reversed edge is an edge, once: then the reversed keys sorted are the keys (a
    # second sort is faster than looking each one up; the lookup names the first missing)
    if np.array_equal(np.sort(reverse), keys):
        return
    at = np.minimum(np.searchsorted(keys, reverse), keys.size - 1)
    missing = keys[at] != reverse
    if np.any(missing):
        a, b = edges[np.argmax(missing)]
        raise CaromError(
            f"{name}: edge {a} -> {b} has no face on its other side: the surface is not closed"
        )
