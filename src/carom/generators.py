"""Ready-made initial conditions: worlds built from a few physical parameters."""

from __future__ import annotations

import math
from typing import Literal

import numpy as np

from carom.errors import CaromError
from carom.world import World

__all__ = ["lattice_gas"]


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
    v = rng.normal(scale=math.sqrt(temperature), size=(count, dim))
    v -= v.mean(axis=0)
    world = World(dim, [side] * dim, boundary)
    world.add_spheres(x, v, radius=0.5, restitution=restitution)
    return world
