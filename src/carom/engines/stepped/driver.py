"""What the 2D and 3D rigid engines share of a step's driver: the clock in whole steps,
advancing to a time or through frames, warming up, and the running totals (collisions with
bodies and with walls or planes, the energy ledger) that ``counters`` reports and a
checkpoint keeps."""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom.engines.base import KIND_PAIR, Counters, FrameArrays, Partners, Sink
from carom.engines.stepped.broadphase import KeptPairs
from carom.engines.stepped.settings import RigidSettings
from carom.laws.kinds import KIND_DYNAMIC, KIND_KINEMATIC

__all__ = ["STOP_CHECK_STEPS", "SteppedEngine"]

FloatArray = NDArray[np.float64]

#: steps between looks at a run's stop request
STOP_CHECK_STEPS = 64


class SteppedEngine:
    """What the 2D and 3D rigid engines share: the clock in whole steps, advancing to a time,
    and the running totals (collisions with bodies and with walls or planes, the energy
    ledger) that :meth:`counters` reports and a checkpoint keeps. A subclass sets itself up
    with :meth:`_begin` and defines ``step``, ``sample`` and ``_warm_kernels``."""

    start: float
    steps: int
    dt: float
    n_bodies: int
    partners: Partners

    def _begin(
        self,
        model: Any,
        state: Any,
        settings: RigidSettings,
        time: float,
        partners: Partners | None,
        shape: tuple[int, int, int],
        cell: float,
        find_pairs: Callable[..., int],
    ) -> None:
        """What both dimensions' engines set up alike: the constants, the state advanced in
        place, the settings, the clock and totals from ``time`` [s], what each body is to a
        collision record (default: every body the caller's), room for contact rows of
        ``shape`` = (dimensions, floats, ints), the kept pairs that the dimension's
        ``find_pairs`` finds in a grid of ``cell`` [m], and the bodies' roles."""
        self.model = model
        self.state = state
        self.settings = settings
        self._start_totals(time)
        self.dt = settings.dt
        n = model.kind.shape[0]
        if partners is None:
            partners = Partners(np.zeros(n, np.int8), np.arange(n, dtype=np.int64))
        self.partners = partners
        #: the caller's bodies: the first ``n_bodies``
        self.n_bodies = int(np.count_nonzero(partners.kind == KIND_PAIR))
        self.cell = cell
        dims, floats, ints = shape
        self._cf = np.zeros((max(64, 2 * n), floats))
        self._ci = np.zeros((max(64, 2 * n), ints), np.int64)
        pieces = model.piece_body.shape[0]
        self._boxes = np.zeros((pieces, 2 * dims))
        self._kept = KeptPairs(
            pieces,
            dims,
            n,
            lambda boxes, active, out: find_pairs(
                boxes, self.model.piece_body, active, self._dynamic, self.cell, out
            ),
        )
        self._parent = np.zeros(n, np.int64)
        self._role = np.zeros(n, np.int64)
        self._dynamic = model.kind == KIND_DYNAMIC
        self._kinematic = model.kind == KIND_KINEMATIC
        self._accel = np.zeros((n, dims))
        self._accel[self._dynamic] = model.gravity
        self.n_contacts = 0

    def arrays(self) -> dict[str, NDArray[Any]]:
        """The state's arrays and the clock and totals, for a checkpoint."""
        s = self.state
        return {name: np.array(value) for name, value in s._asdict().items()} | self._totals()

    def _start_totals(self, time: float) -> None:
        self.start = float(time)
        self.steps = 0
        self._collisions = 0
        self._wall_collisions = 0
        self._energy_lost = 0.0
        self._energy_given = 0.0
        self._work_done = 0.0

    def step(self, sink: Sink | None = None) -> None:
        raise NotImplementedError

    @staticmethod
    def _warm_kernels() -> None:
        """Load every kernel a step of this engine's dimension can call (a module's
        ``warm_up``)."""
        raise NotImplementedError

    def warm_up(self) -> None:
        """Load (or compile) every kernel a run may call: a step's, including those called
        only on a first impact or sleep, and the sampler's. Changes nothing."""
        self.advance(self.time, 0, None)  # no step is taken
        self._warm_kernels()
        self.sample()

    @property
    def time(self) -> float:
        """The clock [s]: the start plus whole steps."""
        return self.start + self.steps * self.dt

    def advance(
        self,
        until: float,
        max_events: int,
        sink: Sink | None,
        stop: Callable[[], bool] | None = None,
    ) -> bool:
        """Step until the clock reaches ``until`` [s] (to within a millionth of a step);
        ``max_events`` bounds the steps. Impacts solved exactly go to ``sink``."""
        target = math.floor((until - self.start) / self.dt + 1e-6)
        todo = min(max(target - self.steps, 0), max_events)
        for k in range(todo):
            self.step(sink)
            if stop is not None and (k + 1) % STOP_CHECK_STEPS == 0 and stop():
                return False
        return True

    def sample(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        raise NotImplementedError

    def sample_motion(self) -> tuple[FloatArray, FloatArray]:
        """:meth:`sample`'s positions and velocities (a stepped engine's bodies are few)."""
        x, v, _, _ = self.sample()
        return x, v

    def advance_frames(
        self,
        times: FloatArray,
        sink: Sink | None,
        stop: Callable[[], bool] | None,
        out: FrameArrays,
    ) -> int:
        """Step to each of ``times`` and sample there: a call from Python a frame, which
        costs little beside a step. Returns the frames written (fewer if ``stop`` said so)."""
        for f in range(len(times)):
            if not self.advance(float(times[f]), np.iinfo(np.int64).max, sink, stop):
                return f
            x, v, orient, w = self.sample()
            out.times[f] = self.time
            out.positions[f] = x
            out.velocities[f] = v
            out.orientations[f] = orient.reshape(len(orient), -1)
            out.angular_velocities[f] = w
        return len(times)

    def counters(self) -> Counters:
        return Counters(
            self.steps,
            self._collisions,
            self._wall_collisions,
            0,
            0,
            0.0,
            self._energy_lost,
            0,
            self._energy_given,
            self._work_done,
        )

    def resting(self) -> NDArray[np.int64]:
        return np.full(self.n_bodies, -1, np.int64)

    def _totals(self) -> dict[str, NDArray[Any]]:
        """The clock and the running totals, for :meth:`arrays`."""
        return {
            "steps": np.array([self.steps]),
            "start": np.array([self.start]),
            "totals": np.array(
                [
                    self._collisions,
                    self._wall_collisions,
                    self._energy_lost,
                    self._energy_given,
                    self._work_done,
                ]
            ),
        }

    def _restore_totals(self, arrays: Mapping[str, NDArray[Any]]) -> None:
        """Take the clock and totals back from :meth:`_totals`' arrays."""
        self.steps = int(arrays["steps"][0])
        collisions, walls, lost, given, work = (float(t) for t in arrays["totals"])
        self._collisions, self._wall_collisions = int(collisions), int(walls)
        self._energy_lost, self._energy_given, self._work_done = lost, given, work

    def _count(self, partner: NDArray[np.int64], lost: float, work: float) -> NDArray[np.int8]:
        """Count exact impacts against ``partner`` rows and add their ledger; return what
        each partner is (KIND_PAIR, KIND_WALL, KIND_PLANE)."""
        against = self.partners.kind[partner]
        self._wall_collisions += int(np.count_nonzero(against != KIND_PAIR))
        self._collisions += int(np.count_nonzero(against == KIND_PAIR))
        self._energy_lost += lost
        self._work_done += work
        return against
