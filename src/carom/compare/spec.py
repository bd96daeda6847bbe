"""What a peer engine needs to know about a scene, as plain arrays.

A :class:`PeerScene` is read off a built :class:`carom.World`: bodies, the box, gravity and the
restitution of every pair and every wall. It refuses what the peers cannot represent the same
way (periodic boxes, static bodies, extra planes, rough or frictional materials), naming the
feature and what to do instead.

Each peer combines two surfaces' restitutions by its own rule (pymunk and Bullet multiply
them, MuJoCo averages contact parameters or lets the higher-priority surface decide).
:func:`factor_restitution` finds per-body coefficients that reproduce carom's pair table under
a product rule, or says which pair makes that impossible.
"""

from __future__ import annotations

import copy
import functools
import math
from collections.abc import Callable
from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from carom.errors import CaromError
from carom.materials import LAW_CODES, pair_table
from carom.world import World

__all__ = ["PeerScene", "factor_restitution", "steps_to"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class PeerScene:
    """A scene of smooth spheres (3D) or disks (2D) in a walled box, as plain data.

    Attributes
    ----------
    name : str
        The scene's name (built-in name or file stem).
    dim : {2, 3}
        Dimension.
    box : (d,) float64
        Box sides [m]; the walls are the faces of ``[0, box]``.
    gravity : (d,) float64
        [m/s^2].
    positions, velocities : (N, d) float64
        Initial centres [m] and velocities [m/s].
    radius, mass : (N,) float64
        [m], [kg].
    pair_restitution : (N, N) float64
        Restitution of each pair of bodies [-] (carom's combine rule already applied).
    wall_restitution : (N, 2 d) float64
        Restitution of each body against each wall [-], walls ordered x_lower, x_upper,
        y_lower, ... (carom's wall coefficient is the wall's alone).
    until : float
        Simulated time [s].
    frame_interval : float
        The scene's frame interval [s] (carom's sampling interval).
    title : str
        The scene's title (its name when it has none).
    world : callable
        A fresh copy of the scene's :class:`carom.World`, not yet run (carom runs the
        scene itself, with its own combine rule and t_c).
    """

    name: str
    dim: int
    box: FloatArray
    gravity: FloatArray
    positions: FloatArray
    velocities: FloatArray
    radius: FloatArray
    mass: FloatArray
    pair_restitution: FloatArray
    wall_restitution: FloatArray
    until: float
    frame_interval: float
    world: Callable[[], World] = field(compare=False, repr=False)
    title: str = ""

    @classmethod
    def from_world(
        cls,
        build: Callable[[], World],
        name: str,
        until: float,
        frame_interval: float | None,
        title: str = "",
    ) -> PeerScene:
        """Read the world ``build()`` makes; refuse what pymunk, Bullet and MuJoCo lack."""
        world = build()
        if world.boundary == "periodic":
            raise CaromError(
                f"scene {name!r} has a periodic box; pymunk, pybullet and MuJoCo have no "
                f"periodic boundary. Compare a walled scene instead (gas-2d, gas-3d)"
            )
        if not np.all(world.bodies.mobile):
            raise CaromError(
                f"scene {name!r} has static bodies (pegs); carom compare handles moving "
                f"spheres and walls only"
            )
        if world.planes:
            raise CaromError(
                f"scene {name!r} has extra planes; carom compare handles the box walls only"
            )
        table = pair_table(world.materials, world.combine, world.pair_overrides)
        if np.any(table.law != LAW_CODES["smooth"]):
            raise CaromError(
                f"scene {name!r} has rough or frictional materials (beta, friction); carom "
                f"compare handles smooth spheres, the case every peer can be set up for"
            )
        n = world.n_bodies
        material = world.bodies.material
        pair = table.e[material[:, None], material[None, :]]
        wall_e = np.array([m.restitution for m in world.walls])
        walls = np.broadcast_to(wall_e, (n, 2 * world.dim)).copy()
        dt = frame_interval if frame_interval is not None else until / 100.0
        return cls(
            name=name,
            dim=world.dim,
            box=world.box.copy(),
            gravity=world.gravity.copy(),
            positions=world.positions.copy(),
            velocities=world.velocities.copy(),
            radius=world.radii.copy(),
            mass=world.masses.copy(),
            pair_restitution=pair,
            wall_restitution=walls,
            until=float(until),
            frame_interval=float(dt),
            world=functools.partial(copy.deepcopy, world),  # the bodies as placed, unrun
            title=title or name,
        )

    def steps(self, dt: float) -> int:
        """Steps of ``dt`` [s] that reach ``until`` (the last may pass it by < dt)."""
        return steps_to(self.until, dt)

    def duration(self, dt: float) -> float:
        """The simulated time [s] of :meth:`steps` steps of ``dt``."""
        return self.steps(dt) * dt

    @property
    def n(self) -> int:
        """Number of bodies."""
        return int(self.radius.shape[0])

    @property
    def elastic(self) -> bool:
        """Whether every pair and wall restitution is 1 (kinetic energy conserved)."""
        return bool(np.all(self.pair_restitution == 1.0) and np.all(self.wall_restitution == 1.0))

    def energy(self, positions: FloatArray, velocities: FloatArray) -> float:
        """Kinetic plus potential energy [J] of a state (positions (N, d) [m], velocities
        (N, d) [m/s]); the potential is ``-m g . x``."""
        kinetic = 0.5 * float(np.sum(self.mass * np.sum(velocities * velocities, axis=1)))
        return kinetic - float(np.sum(self.mass * (positions @ self.gravity)))


def steps_to(until: float, dt: float) -> int:
    """Steps of ``dt`` [s] that reach ``until`` [s]: the nearest whole number when ``until``
    is one to 1e-9, else enough that the last passes it by less than ``dt``."""
    ratio = until / dt
    nearest = round(ratio)
    return int(nearest) if abs(ratio - nearest) < 1e-9 * max(1.0, ratio) else math.ceil(ratio)


def factor_restitution(
    scene: PeerScene, engine: str
) -> tuple[FloatArray, FloatArray, list[str], bool]:
    """Per-body and per-wall coefficients whose products are the scene's restitutions.

    pymunk (``Shape.elasticity``) and Bullet (``restitution``) give a contact the product of
    its two surfaces' coefficients. With one restitution ``e`` between all bodies, each body
    gets ``sqrt(e)`` and wall ``k`` gets ``e_wall_k / sqrt(e)``.

    Returns
    -------
    body : (N,) float64
        Coefficient of each body [-].
    wall : (2 d,) float64
        Coefficient of each wall [-] (may exceed 1 when walls are bouncier than bodies).
    notes : list of str
        How the coefficients were chosen.
    walls_exact : bool
        False when no wall coefficients give every body-wall restitution (plastic bodies
        against bouncy walls): an engine that can should then set body-wall contacts itself.

    Raises
    ------
    CaromError
        When the body-body restitutions are not products of per-body coefficients.
    """
    pair = scene.pair_restitution
    n = scene.n
    if n > 1:
        # e_ij = c_i c_j: c_i^2 = e_ii, and every other pair must agree
        body = np.sqrt(np.diag(pair).copy())
        expected = body[:, None] * body[None, :]
        off = ~np.eye(n, dtype=bool)
        bad = np.abs(expected - pair) > 1e-12
        if np.any(bad & off):
            i, j = (int(k) for k in np.argwhere(bad & off)[0])
            raise CaromError(
                f"{engine} multiplies the two surfaces' restitutions, and scene "
                f"{scene.name!r} has pair ({i}, {j}) at e = {pair[i, j]:g}, not the product "
                f"{expected[i, j]:g} of the two bodies' own; give the bodies one restitution "
                f"or use combine = 'product'"
            )
    else:
        body = np.ones(1)
    wall_e = scene.wall_restitution
    with np.errstate(divide="ignore", invalid="ignore"):
        per_wall = np.where(body[:, None] > 0.0, wall_e / body[:, None], np.nan)
    wall = np.nanmax(per_wall, axis=0, initial=0.0)
    unequal = np.abs(per_wall - wall[None, :]) > 1e-12 * np.maximum(1.0, wall)
    walls_exact = not (np.any(np.isnan(per_wall) & (wall_e > 0.0)) or np.any(unequal))
    if not walls_exact:
        wall = np.where(np.isnan(per_wall).all(axis=0), 1.0, wall)
    notes = [
        f"{engine} multiplies the two surfaces' restitutions: bodies get sqrt(e_pair) "
        f"= {', '.join(f'{c:.6g}' for c in sorted(set(body.tolist())))}, walls e_wall / "
        f"sqrt(e_pair) = {', '.join(f'{c:.6g}' for c in wall.tolist())}"
    ]
    if np.any(wall > 1.0):
        notes.append("a wall coefficient above 1 is how a product rule gives bouncy walls")
    if not walls_exact:
        notes.append(
            "no wall coefficients reproduce every body-wall restitution under the product "
            "rule (plastic bodies, bouncy walls)"
        )
    return body, wall, notes, walls_exact
