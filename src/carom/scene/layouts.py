"""Ready-made initial conditions: worlds built from a few physical parameters."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import Literal

import numpy as np
from numpy.typing import ArrayLike, NDArray

from carom.errors import CaromError
from carom.world import World

__all__ = [
    "cushion_rails",
    "lattice_gas",
    "lattice_positions",
    "maxwell_velocities",
    "peg_positions",
    "rack_positions",
    "row_positions",
]


def _unit(direction: ArrayLike | None, dim: int) -> NDArray[np.float64]:
    """``direction`` normalised; +x when None."""
    if direction is None:
        u = np.zeros(dim)
        u[0] = 1.0
        return u
    u = np.asarray(direction, dtype=float)
    norm = float(np.linalg.norm(u))
    if u.shape != (dim,) or not norm > 0 or not math.isfinite(norm):
        raise CaromError(f"direction must be a nonzero vector of {dim} numbers; got {direction!r}")
    return u / norm


def _in_plane_normal(u: NDArray[np.float64]) -> NDArray[np.float64]:
    """The unit vector a quarter turn anticlockwise from ``u`` in the x-y plane."""
    n = np.zeros_like(u)
    n[0], n[1] = -u[1], u[0]
    norm = float(np.linalg.norm(n))
    if not norm > 0:
        raise CaromError("direction must not be along z: racks and rows lie in the x-y plane")
    return n / norm


def row_positions(
    count: int, start: ArrayLike, spacing: float, direction: ArrayLike | None = None
) -> NDArray[np.float64]:
    """``count`` centres in a straight line: ``start + k spacing u``, ``k = 0 .. count - 1``.

    With ``spacing = 2 radius`` the spheres touch: a Newton's cradle.

    Parameters
    ----------
    count : int
        Number of spheres (>= 1).
    start : array_like, shape (d,)
        The first centre [m].
    spacing : float
        Distance between neighbouring centres [m].
    direction : array_like, shape (d,), optional
        Direction of the row (normalised here); +x by default.

    Returns
    -------
    ndarray, shape (count, d)
        Centres [m].

    Examples
    --------
    >>> row_positions(3, [0.0, 1.0], 0.5).tolist()
    [[0.0, 1.0], [0.5, 1.0], [1.0, 1.0]]
    """
    origin = np.asarray(start, dtype=float)
    u = _unit(direction, origin.size)
    k = np.arange(count, dtype=float)[:, None]
    return origin + k * spacing * u


def rack_positions(
    rows: int, apex: ArrayLike, pitch: float, direction: ArrayLike | None = None
) -> NDArray[np.float64]:
    """A triangular rack: row ``r`` (0 at the apex) holds ``r + 1`` spheres.

    Rows lie ``pitch sqrt(3) / 2`` apart along ``direction``, the spheres of a row ``pitch``
    apart across it, so that with ``pitch = 2 radius`` every sphere touches its neighbours
    (15 balls for ``rows = 5``: a pool rack). In 3D the rack lies in the x-y plane through
    the apex.

    Parameters
    ----------
    rows : int
        Number of rows (>= 1); ``rows (rows + 1) / 2`` spheres.
    apex : array_like, shape (d,)
        Centre of the front sphere [m].
    pitch : float
        Distance between touching centres: diameter plus gap [m].
    direction : array_like, shape (d,), optional
        Where the rack opens towards (normalised); +x by default.

    Returns
    -------
    ndarray, shape (rows (rows + 1) / 2, d)
        Centres [m], row by row.

    Examples
    --------
    >>> rack_positions(2, [0.0, 0.0], 2.0).round(6).tolist()
    [[0.0, 0.0], [1.732051, -1.0], [1.732051, 1.0]]
    """
    origin = np.asarray(apex, dtype=float)
    u = _unit(direction, origin.size)
    across = _in_plane_normal(u)
    centres = [
        origin + r * pitch * math.sqrt(3.0) / 2.0 * u + (j - r / 2.0) * pitch * across
        for r in range(rows)
        for j in range(r + 1)
    ]
    return np.array(centres)


def lattice_positions(
    shape: Sequence[int], origin: ArrayLike, spacing: float
) -> NDArray[np.float64]:
    """A simple cubic (square) lattice of ``prod(shape)`` centres, ``spacing`` apart.

    Parameters
    ----------
    shape : sequence of int, length d
        Sites along each axis.
    origin : array_like, shape (d,)
        The first centre (lowest corner) [m].
    spacing : float
        Lattice constant [m].

    Returns
    -------
    ndarray, shape (prod(shape), d)
        Centres [m], the last axis varying fastest.

    Examples
    --------
    >>> lattice_positions([2, 2], [1.0, 1.0], 0.5).tolist()
    [[1.0, 1.0], [1.0, 1.5], [1.5, 1.0], [1.5, 1.5]]
    """
    base = np.asarray(origin, dtype=float)
    axes = [np.arange(n, dtype=float) * spacing for n in shape]
    grid = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, len(shape))
    return base + grid


def peg_positions(
    rows: int,
    top: ArrayLike,
    spacing: Sequence[float],
    layout: Literal["triangle", "staggered"] = "triangle",
    columns: int | None = None,
) -> NDArray[np.float64]:
    """Pegs of a Galton board, row by row downwards (-y) from ``top``.

    ``"triangle"``: row ``r`` (0 at the top) holds ``r + 1`` pegs centred under ``top``, so a
    ball falling on the top peg meets one peg per row. ``"staggered"``: every row holds
    ``columns`` pegs starting at ``top``, odd rows shifted by half a spacing.

    Parameters
    ----------
    rows : int
        Number of rows (>= 1).
    top : array_like, shape (d,)
        The first peg of the top row [m] (triangle: the apex).
    spacing : sequence of 2 floats
        ``[dx, dy]``: between pegs of a row and between rows [m].
    layout : {"triangle", "staggered"}
    columns : int, optional
        Pegs per row; needed for ``"staggered"``.

    Returns
    -------
    ndarray, shape (n, d)
        Centres [m].

    Examples
    --------
    >>> peg_positions(2, [0.0, 1.0], [0.2, 0.1]).round(12).tolist()
    [[0.0, 1.0], [-0.1, 0.9], [0.1, 0.9]]
    """
    origin = np.asarray(top, dtype=float)
    dx, dy = spacing
    pegs = []
    for r in range(rows):
        if layout == "triangle":
            xs = [(j - r / 2.0) * dx for j in range(r + 1)]
        else:
            if columns is None:
                raise CaromError("a staggered peg layout needs columns (pegs per row)")
            xs = [(j + 0.5 * (r % 2)) * dx for j in range(columns)]
        for x in xs:
            p = origin.copy()
            p[0] += x
            p[1] -= r * dy
            pegs.append(p)
    return np.array(pegs)


def cushion_rails(
    low: ArrayLike, high: ArrayLike, height: float, width: float = 0.05, cloth: float = 0.0
) -> list[tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]]:
    """The four cushions of a billiards table: static rails whose noses, ``height`` [m] above
    the cloth (the plane z = ``cloth``), run along the rectangle ``low`` to ``high`` ((2,)
    [m], x and y) that bounds the playing area.

    A rail is a prism ``width`` [m] deep: its top is level with the nose, and its face below
    the nose leans back at 45 degrees (a real cushion's rubber is undercut), so that a ball
    meets the nose first wherever it comes from, as long as the nose is above the ball's
    centre by less than ``R sin 45``: the contact normal then points from the nose to the
    ball's centre, tilted down by ``asin(height / R - 1)`` (Han 2005; Mathavan et al. 2010).

    Returns
    -------
    list of (points, position, orientation)
        Each rail's convex hull points in its own frame (8, 3) [m] (its nose along +y from
        the origin at the nose's height, the rail behind it towards +x), where that origin is
        (3,) [m], and its turn about z, a unit quaternion (w, x, y, z): the right, top, left
        and bottom rails.
    """
    lo = np.asarray(low, dtype=float)
    hi = np.asarray(high, dtype=float)
    if lo.shape != (2,) or hi.shape != (2,) or not np.all(hi > lo):
        raise CaromError(
            f"a table's playing area is [[x0, y0], [x1, y1]] with x1 > x0 and y1 > y0; got "
            f"{np.asarray(low).tolist()!r} to {np.asarray(high).tolist()!r}"
        )
    if not (height > 0.0 and width > 0.0):
        raise CaromError(f"a cushion's height and width must be > 0; got {height}, {width} m")

    def rail(length: float) -> NDArray[np.float64]:
        profile = [(0.0, height), (width, height), (width, 0.0), (min(height, width), 0.0)]
        return np.array(
            [[x, y, z - height] for y in (0.0, length) for x, z in profile], dtype=float
        )

    def yaw(angle: float) -> NDArray[np.float64]:
        return np.array([math.cos(angle / 2.0), 0.0, 0.0, math.sin(angle / 2.0)])

    z = cloth + height
    (x0, y0), (x1, y1) = lo, hi
    return [
        (rail(y1 - y0), np.array([x1, y0, z]), yaw(0.0)),  # facing -x
        (rail(x1 - x0), np.array([x1, y1, z]), yaw(0.5 * math.pi)),  # facing -y
        (rail(y1 - y0), np.array([x0, y1, z]), yaw(math.pi)),  # facing +x
        (rail(x1 - x0), np.array([x0, y0, z]), yaw(-0.5 * math.pi)),  # facing +y
    ]


def maxwell_velocities(
    rng: np.random.Generator, count: int, dim: int, temperature: float, mass: float
) -> NDArray[np.float64]:
    """``count`` velocities (count, dim) [m/s] drawn from Maxwell-Boltzmann at ``temperature``
    [J] (``k_B = 1``) for bodies of ``mass`` [kg]: each component Gaussian with variance
    ``temperature / mass`` (PHYSICS.md section 6), then the mean removed so that the bodies'
    centre of mass is at rest (a drift is added apart, by whoever wants one)."""
    v: NDArray[np.float64] = rng.normal(scale=math.sqrt(temperature / mass), size=(count, dim))
    v -= v.mean(axis=0)
    return v


def lattice_gas(
    dim: int,
    n_side: int,
    packing: float,
    *,
    temperature: float = 1.0,
    seed: int = 0,
    boundary: Literal["walls", "periodic"] = "periodic",
    restitution: float = 1.0,
) -> World:
    """Spheres (disks) of unit diameter and mass on a simple lattice, with Maxwell velocities.

    ``n_side ** dim`` bodies in a cubic (square) box sized for the packing fraction
    ``phi = N pi sigma^3 / (6 V)`` (2D: ``N pi sigma^2 / (4 V)``); velocities Gaussian with
    variance ``temperature / m`` per component, total momentum removed. The lattice melts
    after a few collisions per body.

    Parameters
    ----------
    dim : {2, 3}
        Dimension.
    n_side : int
        Bodies per side of the lattice (>= 1).
    packing : float
        Packing fraction [-], below the lattice's own (pi/6 in 3D, pi/4 in 2D).
    temperature : float
        ``k_B T`` with ``k_B = 1`` [J]; unit mass.
    seed : int
        Seed of the velocities: same seed, same world.
    boundary, restitution
        As for :class:`carom.World` and :meth:`carom.World.add_spheres`.

    Examples
    --------
    >>> world = lattice_gas(3, 4, 0.3, seed=1)
    >>> world.n_bodies, round(float(world.box[0]), 4)
    (64, 4.816)
    """
    unit = math.pi / 6 if dim == 3 else math.pi / 4
    if dim not in (2, 3) or n_side < 1:
        raise CaromError(f"need dim 2 or 3 and n_side >= 1; got dim={dim!r}, n_side={n_side!r}")
    if not 0.0 < packing < unit:
        raise CaromError(
            f"packing must lie in (0, {unit:.4f}): a simple lattice of unit spheres cannot be "
            f"denser; got {packing!r}"
        )
    if not temperature > 0.0:
        raise CaromError(f"temperature must be positive; got {temperature!r}")
    count = n_side**dim
    side = (count * unit / packing) ** (1 / dim)
    grid = (np.arange(n_side) + 0.5) * side / n_side
    x = np.stack(np.meshgrid(*([grid] * dim), indexing="ij"), -1).reshape(-1, dim)
    rng = np.random.default_rng(seed)
    v = maxwell_velocities(rng, count, dim, temperature, 1.0)
    world = World(dim, [side] * dim, boundary)
    world.add_spheres(x, v, radius=0.5, restitution=restitution)
    return world
