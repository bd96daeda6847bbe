"""carom in a comparison: the exact event-driven engine, sampled at the scene's frames."""

from __future__ import annotations

from typing import Any

import numpy as np

from carom.compare.spec import PeerScene
from carom.world import Frame

__all__ = ["start"]


class CaromSimulation:
    """carom advancing frame by frame; it has no time step, so ``dt`` is the frame interval.

    Between frames it jumps from collision to collision; the frames only tell the monitor
    where the bodies are.
    """

    def __init__(self, scene: PeerScene) -> None:
        world = scene.world()  # the scene's own world: its combine rule, t_c and all
        self.dt = scene.frame_interval
        world.prepare()  # the set-up (neighbour grid, first predictions, kernels) is not timed
        self._frame: Frame = world.frame()
        self._frames = world.frames(scene.duration(self.dt), self.dt)
        self.settings: dict[str, Any] = {
            "method": "event-driven: exact times of impact, one impulse per collision",
            "frame_interval_s": self.dt,
            "t_c_s": world.settings.t_c,
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


def start(scene: PeerScene) -> CaromSimulation:
    return CaromSimulation(scene)
