"""Convex outlines in 2D: the hull, the checks a user's outline must pass, and the exact mass
properties of a rounded convex polygon (NumPy; used when shapes are built, never per step).

A *rounded convex polygon* is the set of points within ``radius`` of a convex core polygon
with ``k >= 1`` vertices (Box2D's ``b2Polygon`` with its ``radius``). One vertex is a circle,
two a capsule (or a segment when the radius is 0), three or more a polygon, rounded or sharp.
Every convex shape of the 2D rigid-body engine is one of these, so one set of formulas serves
them all.
"""

from __future__ import annotations

import math

import numpy as np
from numpy.typing import NDArray

from carom.errors import CaromError

__all__ = ["MassIntegrals", "convex_outline", "hull", "rounded_polygon_integrals"]

FloatArray = NDArray[np.float64]


def _cross(o: FloatArray, a: FloatArray, b: FloatArray) -> float:
    """z of ``(a - o) x (b - o)``: positive when o, a, b turn left."""
    return float((a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0]))


def _tolerance(points: FloatArray) -> float:
    """Collinearity tolerance on a cross product [m^2]: round-off of the outline's size."""
    span = float(np.max(np.abs(points - points.mean(axis=0)))) if points.size else 0.0
    return 64.0 * np.finfo(float).eps * max(span, np.finfo(float).tiny) ** 2


def hull(points: FloatArray) -> NDArray[np.int64]:
    """Indices of the convex hull's corners, counter-clockwise, starting from the lowest-x point.

    Andrew's monotone chain: collinear and repeated points are left out, so every returned
    corner turns strictly left (to round-off of the outline's size).

    Parameters
    ----------
    points : (k, 2) float64
        [m].

    Returns
    -------
    (h,) int64
        Indices into ``points``; ``h`` is 1 for coincident points and 2 for collinear ones.
    """
    order = np.lexsort((points[:, 1], points[:, 0]))
    tol = _tolerance(points)
    lower: list[int] = []
    upper: list[int] = []
    for chain, sequence in ((lower, order), (upper, order[::-1])):
        for i in sequence:
            while len(chain) >= 2 and _cross(points[chain[-2]], points[chain[-1]], points[i]) <= (
                tol
            ):
                chain.pop()
            chain.append(int(i))
    corners = lower[:-1] + upper[:-1]
    if not corners:  # a single point
        return np.array([int(order[0])], np.int64)
    if len(corners) == 2 and np.array_equal(points[corners[0]], points[corners[1]]):
        return np.array(corners[:1], np.int64)
    return np.array(corners, np.int64)


def convex_outline(vertices: FloatArray, name: str = "vertices") -> FloatArray:
    """The corners of a convex outline, counter-clockwise; a clear CaromError otherwise.

    The outline may run either way round and may repeat a point or hold points along an edge
    (both are dropped). Refused: fewer than three distinct corners or no area (a degenerate
    polygon), a point strictly inside the hull (a concave outline: build it as a
    :class:`carom.shapes.Compound` of convex pieces), and an outline that visits the hull's
    corners out of order (it crosses itself).

    Parameters
    ----------
    vertices : (k, 2) float64
        The outline, in order [m].

    Returns
    -------
    (h, 2) float64
        The hull's corners, counter-clockwise, in the outline's order from its first corner.
    """
    k = vertices.shape[0]
    if k < 3:
        raise CaromError(
            f"{name}: a polygon needs at least 3 vertices; got {k} (use Circle, Capsule or "
            "Segment for fewer)"
        )
    corners = hull(vertices)
    if corners.size < 3:
        raise CaromError(
            f"{name}: the {k} vertices lie on one line (zero area); a polygon needs three "
            "corners that do not"
        )
    tol = _tolerance(vertices)
    hull_points = vertices[corners]
    # a vertex strictly inside the hull: the outline dents inwards there
    for i in range(k):
        inside = True
        for c in range(corners.size):
            a, b = hull_points[c], hull_points[(c + 1) % corners.size]
            if _cross(a, b, vertices[i]) <= tol:
                inside = False
                break
        if inside:
            raise CaromError(
                f"{name}[{i}] = {vertices[i].tolist()} lies inside the hull of the others: the "
                "outline is concave. A body must be convex piece by piece: build a concave "
                "body as carom.shapes.Compound([...]) of convex pieces (TOML: shape.pieces)"
            )
    # every vertex is on the hull's boundary; the outline must go round it once, in order
    position = {int(c): p for p, c in enumerate(corners)}
    visits = [position[i] for i in range(k) if i in position]
    h = corners.size
    steps = {(visits[(j + 1) % h] - visits[j]) % h for j in range(h)}
    if len(visits) != h or not (steps == {1} or steps == {h - 1}):
        raise CaromError(
            f"{name}: the outline crosses itself (its corners are not listed in order around "
            "the polygon); list the vertices as you walk round the outline, either way"
        )
    start = visits[0]
    return np.roll(hull_points, -start, axis=0)


class MassIntegrals:
    """Area, first and second moments of a region about the origin of its frame.

    Attributes
    ----------
    area : float
        ``A = int dA`` [m^2].
    first : (2,) float64
        ``S = int x dA`` [m^3]; the centroid is ``S / A``.
    second : float
        ``J = int |x|^2 dA`` [m^4], the polar moment about the origin.
    """

    __slots__ = ("area", "first", "second")

    def __init__(self, area: float, first: FloatArray, second: float) -> None:
        self.area = area
        self.first = first
        self.second = second

    def __add__(self, other: MassIntegrals) -> MassIntegrals:
        return MassIntegrals(
            self.area + other.area, self.first + other.first, self.second + other.second
        )

    @classmethod
    def zero(cls) -> MassIntegrals:
        """The integrals of nothing."""
        return cls(0.0, np.zeros(2), 0.0)

    @property
    def measure(self) -> float:
        """The area [m^2] (a solid's measure is its volume)."""
        return self.area

    @property
    def centroid(self) -> FloatArray:
        """``S / A`` [m], (2,)."""
        return self.first / self.area

    @property
    def second_about_centroid(self) -> float:
        """``J - A |c|^2`` [m^4]: the parallel-axis theorem run backwards."""
        c = self.centroid
        return self.second - self.area * float(c @ c)


def polygon_integrals(corners: FloatArray) -> MassIntegrals:
    """Exact integrals of a polygon (counter-clockwise corners) about the origin.

    Each edge ``(p, q)`` with ``c = p x q`` adds a triangle with the origin:
    ``A += c/2``, ``S += c (p + q)/6``, ``J += c (p.p + p.q + q.q)/12``
    (the shoelace formulas; Eberly, "Polyhedral mass properties", 2D form).
    """
    p = corners
    q = np.roll(corners, -1, axis=0)
    c = p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0]
    area = float(np.sum(c)) / 2.0
    first = np.sum(c[:, None] * (p + q), axis=0) / 6.0
    squares = np.sum(p * p, axis=1) + np.sum(p * q, axis=1) + np.sum(q * q, axis=1)
    second = float(np.sum(c * squares))
    return MassIntegrals(area, first, second / 12.0)


def sector_integrals(apex: FloatArray, radius: float, start: float, stop: float) -> MassIntegrals:
    """Exact integrals of the circular sector ``apex + rho (cos phi, sin phi)``,
    ``0 <= rho <= radius``, ``start <= phi <= stop`` [rad], about the origin.

    About its apex a sector has ``A = r^2 t/2``, ``S0 = r^3/3 (sin b - sin a, cos a - cos b)``
    and ``J0 = r^4 t/4`` with ``t = b - a``; moved by ``v``: ``S = S0 + A v`` and
    ``J = J0 + 2 v.S0 + A |v|^2``.
    """
    sweep = stop - start
    area = radius**2 * sweep / 2.0
    chord = np.array([math.sin(stop) - math.sin(start), math.cos(start) - math.cos(stop)])
    s0 = radius**3 / 3.0 * chord
    j0 = radius**4 * sweep / 4.0
    v = np.asarray(apex, float)
    return MassIntegrals(area, s0 + area * v, j0 + 2.0 * float(v @ s0) + area * float(v @ v))


def rounded_polygon_integrals(corners: FloatArray, radius: float) -> MassIntegrals:
    """Exact integrals of a rounded convex polygon about the origin of its frame.

    The region splits without overlap into the core polygon, one ``|edge| x radius`` rectangle
    outside each edge and one circular sector at each corner, the sectors' angles summing to
    2 pi. One corner is a disk, two a capsule (two rectangles back to back and two half disks).

    Parameters
    ----------
    corners : (k, 2) float64
        The core's corners, counter-clockwise, k >= 1 [m].
    radius : float
        [m], >= 0; must be positive when k < 3.

    Returns
    -------
    MassIntegrals
    """
    k = corners.shape[0]
    total = polygon_integrals(corners) if k >= 3 else MassIntegrals(0.0, np.zeros(2), 0.0)
    if radius == 0.0:
        return total
    if k == 1:
        return sector_integrals(corners[0], radius, 0.0, 2.0 * math.pi)
    normals = outward_normals(corners)
    for i in range(k):
        p, q = corners[i], corners[(i + 1) % k]
        n = normals[i]
        total = total + polygon_integrals(np.array([p, p + radius * n, q + radius * n, q]))
        # the corner q, between edge i's normal and the next edge's normal
        a = math.atan2(n[1], n[0])
        b = math.atan2(normals[(i + 1) % k][1], normals[(i + 1) % k][0])
        if b <= a:
            b += 2.0 * math.pi
        total = total + sector_integrals(q, radius, a, b)
    return total


def outward_normals(corners: FloatArray) -> FloatArray:
    """Unit outward normal of each edge ``i -> i+1`` of a counter-clockwise outline, (k, 2).

    Two corners (a segment) give the two sides: edge 0 -> 1 and edge 1 -> 0.
    """
    edges = np.roll(corners, -1, axis=0) - corners
    normals = np.stack([edges[:, 1], -edges[:, 0]], axis=1)
    unit: FloatArray = normals / np.linalg.norm(normals, axis=1)[:, None]
    return unit
