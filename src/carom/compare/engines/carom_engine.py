"""carom in a comparison: the exact event-driven engine sampled at the scene's frames, or the
rigid-body engine stepping at the scene's rate."""

from __future__ import annotations

from typing import Any

import numpy as np

from carom.compare.rigid import RigidScene
from carom.compare.rigid3d import RigidScene3D
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


class CaromRigidSimulation:
    """carom's rigid-body engine stepping at the scene's rate (its settings as the scene
    gives them; exact isolated impacts on)."""

    def __init__(self, scene: RigidScene | RigidScene3D) -> None:
        world = scene.world()
        self.dim = scene.dim
        self.dt = scene.dt
        world.prepare()  # the kernels compile (or load from the cache) outside the timing
        self._frame: Frame = world.frame()
        self._frames = world.frames(scene.steps(self.dt) * self.dt, self.dt)
        s = world.rigid_settings
        self.settings = {
            "dt_s": self.dt,
            "substeps": s.substeps,
            "contact_hertz": s.contact_hertz,
            "damping_ratio": s.damping_ratio,
            "push_speed_m_s": s.push_speed,
            "restitution_threshold_m_s": s.restitution_threshold,
            "linear_slop_m": s.linear_slop,
            "exact_impacts": s.exact_impacts,
            "sleep": s.sleep,
        }
        self.notes = [
            "soft-step solver with the scene's settings (docs/rigid.md); an isolated pair's "
            "impact is found by conservative advancement and solved exactly",
        ]

    def step(self) -> None:
        self._frame = next(self._frames)

    def state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Centres, velocities, angles (2D) or quaternions ``(w, x, y, z)`` (3D), and
        angular velocities (2D: about z; 3D: vectors in the world frame)."""
        f = self._frame
        spin = f.angular_velocities if self.dim == 3 else f.angular_velocities[:, 2]
        return f.positions, f.velocities, np.asarray(f.orientations), spin

    def close(self) -> None:
        pass


def start_rigid(scene: RigidScene | RigidScene3D) -> CaromRigidSimulation:
    return CaromRigidSimulation(scene)
