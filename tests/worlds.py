"""Worlds the tests share."""

from __future__ import annotations

import textwrap
import tomllib

import numpy as np

import carom
from carom.scene import Scene
from carom.scene.layouts import lattice_gas

#: a scene's [world] and [run] tables: a 10 m square 2D world, open, under gravity, run 1 s
OPEN_2D = """
[world]
dimension = 2
box = [10.0, 10.0]
boundary = "open"
gravity = [0.0, -9.81]

[run]
until = 1.0
"""


def scene_world(tables: str) -> carom.World:
    """The world of the scene :data:`OPEN_2D` followed by ``tables`` (TOML: its bodies,
    joints), built as ``carom run`` builds it."""
    text = OPEN_2D + textwrap.dedent(tables)
    world: carom.World = Scene.from_dict(tomllib.loads(text), "scene.toml", text).build()
    return world


def rotation(q: np.ndarray) -> np.ndarray:
    """The rotation matrix (3, 3) of the unit quaternion ``q`` = (w, x, y, z), written out
    (not carom's), for tests that check a 3D body's orientation."""
    w, x, y, z = q
    return np.array([
        [1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
        [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
        [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)],
    ])  # fmt: skip


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


def rough_disks(side: int) -> carom.World:
    """A walled 2D gas of ``side``^2 rough disks with spins, under gravity: its spins, turns
    and supports exercise every array of the event-driven engine's state."""
    world = carom.World(dim=2, box=(float(side), float(side)), gravity=(0.0, -1.0))
    rough = world.add_material(carom.Material(restitution=0.9, beta=0.4))
    rng = np.random.default_rng(4)
    grid = (np.arange(side) + 0.5) * 1.0
    x = np.stack(np.meshgrid(grid, grid, indexing="ij"), -1).reshape(-1, 2)
    v, spins = rng.normal(size=(side * side, 2)), rng.normal(size=side * side)
    world.add_spheres(x, v, angular_velocities=spins, radius=0.3, material=rough)
    return world
