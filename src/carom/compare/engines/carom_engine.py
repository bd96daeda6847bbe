"""carom in a comparison: the exact event-driven engine sampled at the scene's frames, or the
rigid-body engine stepping at the scene's rate."""

from __future__ import annotations

from typing import Any

import numpy as np

from carom.compare.rigid import RigidScene
from carom.compare.rigid3d import RigidScene3D
from carom.compare.spec import PeerScene
from carom.engines.base import FrameArrays
from carom.world import Recording

__all__ = ["start"]


#: the most memory [bytes] one stretch of recorded frames may take
CHUNK_BYTES = 8 << 20


class CaromSimulation:
    """carom advancing frame by frame; it has no time step, so ``dt`` is the frame interval.

    Between frames it jumps from collision to collision; the frames only tell the monitor
    where the bodies are. The frames are recorded a stretch at a time (``World.record``: one
    compiled call runs the events of many frames and samples each), and each step moves on to
    the next one; the stretch's call is timed in the step that makes it.
    """

    def __init__(self, scene: PeerScene) -> None:
        world = scene.world()  # the scene's own world: its combine rule, t_c and all
        self.dt = scene.frame_interval
        world.prepare()  # the set-up (neighbour grid, first predictions, kernels) is not timed
        self._world = world
        first = world.frame()
        self._first = first.positions, first.velocities
        self._times = world.frame_times(scene.duration(self.dt), self.dt)
        self._stretch = max(1, CHUNK_BYTES // FrameArrays.frame_bytes(world.n_bodies, world.dim))
        self._recording: Recording | None = None  # None: at the start, before any step
        self._next = 0  # the first frame time not yet recorded
        self._row, self._rows = -1, 0  # the row handed over, of the recording's rows
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
        self._row += 1
        if self._row == self._rows:  # the stretch is used up: record the next one
            stretch = self._times[self._next : self._next + self._stretch]
            self._recording = self._world.record(stretch)
            self._next += len(stretch)
            self._row, self._rows = 0, len(stretch)

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        if self._recording is None:
            return self._first
        return self._recording.positions[self._row], self._recording.velocities[self._row]

    def close(self) -> None:
        pass


def start(scene: PeerScene) -> CaromSimulation:
    return CaromSimulation(scene)


class CaromRigidSimulation:
    """carom's rigid-body engine stepping at the scene's rate (its settings as the scene
    gives them; impacts solved exactly on).

    A step is :meth:`carom.World.step` (the same bits as a run), as a peer's step is its own
    step call; its state is read afterwards, outside the timed step, as the peers' is."""

    def __init__(self, scene: RigidScene | RigidScene3D) -> None:
        world = scene.world()
        self.dim = scene.dim
        self.dt = scene.dt
        world.prepare()  # the kernels compile (or load from the cache) outside the timing
        world.build()
        self._world = world
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
        self._world.step()

    def state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """Centres, velocities, angles (2D) or quaternions ``(w, x, y, z)`` (3D), and
        angular velocities (2D: about z; 3D: vectors in the world frame)."""
        w = self._world
        spin = np.asarray(w.angular_velocities)
        turn = np.asarray(w.orientations)
        if self.dim == 2:  # (about z)
            spin, turn = spin[:, 2].copy(), turn.reshape(-1)
        return np.asarray(w.positions), np.asarray(w.velocities), turn, spin

    def close(self) -> None:
        pass


def start_rigid(scene: RigidScene | RigidScene3D) -> CaromRigidSimulation:
    return CaromRigidSimulation(scene)
