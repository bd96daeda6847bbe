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
        The carom module that sets it up.
    """

    name: str
    distribution: str
    dims: tuple[int, ...]
    module: str

    def missing(self) -> str | None:
        """None when installed, else why not and how to install it."""
        if importlib.util.find_spec(self.distribution) is None:
            return f"{self.name} is not installed; pip install 'carom[compare]'"
        return None

    def unable(self, dim: int) -> str | None:
        """None when installed and able to simulate ``dim`` dimensions, else why not."""
        problem = self.missing()
        if problem is None and dim not in self.dims:
            problem = f"{self.name} simulates {' and '.join(f'{d}D' for d in self.dims)} only"
        return problem

    def version(self) -> str:
        return importlib.metadata.version(self.distribution)

    def start(self, scene: PeerScene) -> Simulation:
        """Set the engine up for ``scene``."""
        problem = self.unable(scene.dim)
        if problem is not None:
            raise CaromError(f"{problem}; scene {scene.name!r} is {scene.dim}D")
        starter: Callable[[PeerScene], Simulation] = importlib.import_module(self.module).start
        return starter(scene)


ENGINES: dict[str, EngineEntry] = {
    e.name: e
    for e in (
        EngineEntry("carom", "carom", (2, 3), "carom.compare.engines.carom_engine"),
        EngineEntry("pymunk", "pymunk", (2,), "carom.compare.engines.pymunk_engine"),
        EngineEntry("pybullet", "pybullet", (2, 3), "carom.compare.engines.pybullet_engine"),
        EngineEntry("mujoco", "mujoco", (2, 3), "carom.compare.engines.mujoco_engine"),
    )
}


def engine(name: str) -> EngineEntry:
    """The engine called ``name``; a CaromError lists the known ones otherwise."""
    try:
        return ENGINES[name]
    except KeyError:
        raise CaromError(f"unknown engine {name!r}; choose from {', '.join(ENGINES)}") from None
