"""Worlds the tests share."""

from __future__ import annotations

import carom
from carom.scene.layouts import lattice_gas


def gas(
    dim: int, n_side: int, phi: float, seed: int, boundary: str = "periodic", e: float = 1.0
) -> carom.World:
    """``n_side ** dim`` spheres of unit diameter on a lattice at packing ``phi``, with
    Gaussian velocities (zero momentum) and restitution ``e``."""
    return lattice_gas(
        dim,
        n_side,
        phi,
        seed=seed,
        boundary=boundary,  # type: ignore[arg-type]
        restitution=e,
    )
