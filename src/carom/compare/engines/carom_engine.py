"""carom in a comparison: the exact event-driven engine, sampled at the scene's frames."""

from __future__ import annotations

from typing import Any

import numpy as np

from carom.compare.spec import PeerScene
from carom.world import Frame, World

__all__ = ["start"]


class CaromSimulation:
    """carom advancing frame by frame; it has no time step, so ``dt`` is the frame interval.

    Between frames it jumps from collision to collision; the frames only tell the monitor
    where the bodies are.
    """

    def __init__(self, scene: PeerScene) -> None:
        _warm_up(scene.dim)
        world = scene.world()  # the scene's own world: its combine rule, t_c and all
        self.dt = scene.frame_interval
        world._ensure_built()  # the set-up (neighbour grid, first predictions) is not timed
        self._frame: Frame = world.frame()
        self._frames = world.frames(scene.duration(self.dt), self.dt, log=False)
        self.settings: dict[str, Any] = {
            "method": "event-driven: exact times of impact, one impulse per collision",
            "frame_interval_s": self.dt,
            "tc_s": world.t_c,
            "combine": world.combine,
        }
        self.notes = [
            "no time step: collisions are found and resolved at their exact instants; the "
            "frame interval only sets when the monitor looks",
        ]

    def step(self) -> None:
        self._frame = next(self._frames)

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        return self._frame.positions, self._frame.velocities

    def close(self) -> None:
        pass


def _warm_up(dim: int) -> None:
    """Load the compiled kernels (from Numba's cache, or compile them) before timing."""
    world = World(dim, [1.0] * dim)
    world.add_spheres([[0.25] * dim, [0.75] * dim], [[1.0] * dim, [-1.0] * dim], radius=0.1)
    world.run(1.0, frame_dt=0.5, log=False)


def start(scene: PeerScene) -> CaromSimulation:
    return CaromSimulation(scene)
