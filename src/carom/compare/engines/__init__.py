"""The engines ``carom compare`` runs: carom itself and its peers.

Each engine module has a ``start(scene) -> Simulation`` that sets the engine up for a
:class:`~carom.compare.spec.PeerScene` as its own documentation recommends, and records every
setting it chose. A peer's module imports the peer, so it is imported only when that engine
runs; :func:`missing` tells whether a peer is installed without importing it.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import importlib.util
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from carom.compare.rigid import RigidScene
from carom.compare.rigid3d import RigidScene3D
from carom.compare.spec import PeerScene
from carom.errors import CaromError

__all__ = ["ENGINES", "EngineEntry", "Simulation", "engine"]

FloatArray = NDArray[np.float64]


class Simulation(Protocol):
    """One engine set up for one scene."""

    #: the fixed step [s] (carom: its frame interval; it has no step)
    dt: float
    #: every setting the engine was given or keeps at its default, by its own names
    settings: dict[str, Any]
    #: why each setting was chosen, citing the engine's documentation
    notes: list[str]

    def step(self) -> None:
        """Advance by ``dt``."""

    def state(self) -> tuple[FloatArray, FloatArray]:
        """Centres (N, d) [m] and velocities (N, d) [m/s], in the scene's body order."""
        ...

    def close(self) -> None:
        """Release the engine's resources."""


@dataclass(frozen=True)
class EngineEntry:
    """An engine ``carom compare`` can run.

    Attributes
    ----------
    name : str
        Its name on the command line.
    distribution : str
        Its package on PyPI (the ``compare`` extra installs the peers).
    dims : tuple of int
        Dimensions it simulates (a 2D scene runs in 3D engines in the plane z = 0).
    module : str
        The carom module that sets it up: ``start(scene)`` for spheres, ``start_rigid``
        for rigid bodies.
    kinds : tuple of str
        The scenes it takes: ``"spheres"`` (a :class:`PeerScene`), ``"rigid"`` (a
        :class:`~carom.compare.rigid.RigidScene` in 2D, a
        :class:`~carom.compare.rigid3d.RigidScene3D` in 3D).
    import_name : str
        Its module's name, when not the distribution's.
    rigid_dims : tuple of int
        Dimensions of the rigid scenes it takes (default: ``dims``).
    joints : bool
        Whether it is given a rigid scene's joints (:mod:`carom.compare.jointed`).
    jointed_dims : tuple of int
        Dimensions of the rigid scenes with joints it takes (default: ``rigid_dims``).
    own_env : bool
        Installed in its own environment, not carom's (pooltool): its module's ``missing()``
        and ``version()`` say whether it is there and which.
    """

    name: str
    distribution: str
    dims: tuple[int, ...]
    module: str
    kinds: tuple[str, ...] = ("spheres",)
    import_name: str = ""
    rigid_dims: tuple[int, ...] = ()
    joints: bool = False
    jointed_dims: tuple[int, ...] = ()
    own_env: bool = False

    def missing(self) -> str | None:
        """None when installed, else why not and how to install it."""
        if self.own_env:
            said: str | None = importlib.import_module(self.module).missing()
            return said
        if importlib.util.find_spec(self.import_name or self.distribution) is None:
            return f"{self.name} is not installed; pip install 'carom[compare]'"
        return None

    def unable(self, dim: int, kind: str = "spheres", joints: bool = False) -> str | None:
        """None when installed and able to simulate ``dim`` dimensions of ``kind`` bodies
        (``"spheres"`` or ``"rigid"``), with ``joints`` if asked, else why not."""
        problem = self.missing()
        if problem is None and dim not in self.dims:
            problem = f"{self.name} simulates {' and '.join(f'{d}D' for d in self.dims)} only"
        if problem is None and kind not in self.kinds:
            what = {"spheres": "spheres and disks", "rigid": "rigid bodies of any shape"}
            problem = f"{self.name} is compared on {what[self.kinds[0]]} only"
        rigid_dims = self.rigid_dims or self.dims
        if joints and self.jointed_dims:
            rigid_dims = self.jointed_dims
        if problem is None and kind == "rigid" and dim not in rigid_dims:
            dims = " and ".join(f"{d}D" for d in rigid_dims)
            bodies = "rigid bodies with joints" if joints and self.jointed_dims else "rigid bodies"
            problem = f"{self.name} is compared on {bodies} in {dims} only"
        if problem is None and joints and not self.joints:
            takers = ", ".join(e.name for e in ENGINES.values() if e.joints)
            problem = f"{self.name} is not given carom's joints in a comparison ({takers} are)"
        return problem

    def takes(self, dim: int, kind: str = "spheres", joints: bool = False) -> bool:
        """Whether the engine simulates ``dim`` dimensions of ``kind`` bodies, with ``joints``
        if asked (installed or not)."""
        dims = self.dims
        if kind == "rigid":
            dims = self.rigid_dims or self.dims
            if joints:
                dims = self.jointed_dims or dims if self.joints else ()
        return dim in dims and kind in self.kinds

    def rigid_dt(self, scene: RigidScene | RigidScene3D) -> float:
        """The step [s] the engine takes on a rigid scene: its module's ``RIGID_DT`` (its
        documentation's advice) or the scene's rate."""
        module = importlib.import_module(self.module)
        return float(getattr(module, "RIGID_DT", scene.dt))

    def version(self) -> str:
        if self.own_env:
            return str(importlib.import_module(self.module).version())
        return importlib.metadata.version(self.distribution)

    def start(self, scene: PeerScene | RigidScene | RigidScene3D) -> Any:
        """Set the engine up for ``scene`` (a :class:`Simulation`; for a rigid scene its
        ``state()`` also gives angles (3D: quaternions ``(w, x, y, z)``) and angular
        velocities)."""
        rigid = isinstance(scene, RigidScene | RigidScene3D)
        kind = "rigid" if rigid else "spheres"
        jointed = rigid and scene.joint_ints.shape[0] > 0  # type: ignore[union-attr]
        problem = self.unable(scene.dim, kind, jointed)
        if problem is not None:
            raise CaromError(f"{problem}; scene {scene.name!r} is {scene.dim}D {kind}")
        module = importlib.import_module(self.module)
        starter: Callable[[Any], Any] = module.start_rigid if kind == "rigid" else module.start
        return starter(scene)


ENGINES: dict[str, EngineEntry] = {
    e.name: e
    for e in (
        EngineEntry(
            "carom",
            "carom",
            (2, 3),
            "carom.compare.engines.carom_engine",
            ("spheres", "rigid"),
            joints=True,
        ),
        EngineEntry(
            "pymunk",
            "pymunk",
            (2,),
            "carom.compare.engines.pymunk_engine",
            ("spheres", "rigid"),
            joints=True,
        ),
        EngineEntry(
            "pybullet",
            "pybullet",
            (2, 3),
            "carom.compare.engines.pybullet_engine",
            ("spheres", "rigid"),
            rigid_dims=(3,),
        ),
        EngineEntry(
            "mujoco",
            "mujoco",
            (2, 3),
            "carom.compare.engines.mujoco_engine",
            ("spheres", "rigid"),
            rigid_dims=(3,),
            joints=True,
            jointed_dims=(2, 3),
        ),
        EngineEntry(
            "rapier3d",
            "rapier3d",
            (3,),
            "carom.compare.engines.rapier_engine",
            ("rigid",),
            joints=True,
        ),
        EngineEntry(
            "box2d",
            "box2d",
            (2,),
            "carom.compare.engines.box2d_engine",
            ("rigid",),
            "Box2D",
            joints=True,
        ),
        EngineEntry(
            "pooltool",
            "pooltool-billiards",
            (3,),
            "carom.compare.engines.pooltool_engine",
            ("rigid",),
            own_env=True,
        ),
    )
}


def engine(name: str) -> EngineEntry:
    """The engine called ``name``; a CaromError lists the known ones otherwise."""
    try:
        return ENGINES[name]
    except KeyError:
        raise CaromError(f"unknown engine {name!r}; choose from {', '.join(ENGINES)}") from None
