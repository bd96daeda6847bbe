"""A toy engine, plugged in through the table of engines as any engine would be: bodies in
free flight under gravity, passing through each other and the walls (no collisions). Its
positions are the closed form ``x(t) = x0 + v0 (t - t0) + g (t - t0)^2 / 2``, so a run, a
checkpoint and a trajectory can be checked against it exactly."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom.engines.base import Counters, FrameArrays, Sink, WorldView

NAME = "toy"


def refuses(world: WorldView) -> str | None:
    return None if world.bodies.spheres_only else "the toy engine flies spheres only"


def build(world: WorldView) -> Flight:
    b = world.bodies
    return Flight(b.position.copy(), b.velocity.copy(), world.gravity.copy(), world.time)


def restore(world: WorldView, arrays: Mapping[str, NDArray[Any]]) -> Flight:
    start, now = arrays["clock"]
    return Flight(arrays["x0"], arrays["v0"], world.gravity.copy(), float(start), float(now))


class Flight:
    name = NAME

    def __init__(self, x0: NDArray[Any], v0: NDArray[Any], g: NDArray[Any], t0: float,
                 now: float | None = None) -> None:  # fmt: skip
        self.x0, self.v0, self.g, self.t0 = x0, v0, g, t0
        self.time = t0 if now is None else now

    def warm_up(self) -> None:
        pass

    def advance(self, until: float, max_events: int, sink: Sink | None,
                stop: Callable[[], bool] | None = None) -> bool:  # fmt: skip
        self.time = max(self.time, until)
        return True

    def advance_frames(self, times: NDArray[np.float64], sink: Sink | None,
                       stop: Callable[[], bool] | None, out: FrameArrays) -> int:  # fmt: skip
        for f, t in enumerate(times):
            self.advance(float(t), 0, sink)
            out.times[f] = self.time
            out.positions[f], out.velocities[f], orient, out.angular_velocities[f] = self.sample()
            out.orientations[f] = orient.reshape(len(orient), -1)
        return len(times)

    def sample_motion(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        t = self.time - self.t0
        return self.x0 + self.v0 * t + 0.5 * self.g * t * t, self.v0 + self.g * t

    def sample(self) -> tuple[NDArray[np.float64], ...]:  # type: ignore[override]
        x, v = self.sample_motion()
        n, dim = x.shape
        turn = np.zeros((n, 1)) if dim == 2 else np.tile([1.0, 0.0, 0.0, 0.0], (n, 1))
        return x, v, turn, np.zeros((n, 3))

    def counters(self) -> Counters:
        return Counters(0, 0, 0, 0, 0, 0.0, 0.0, 0, 0.0, 0.0)

    def resting(self) -> NDArray[np.int64]:
        return np.full(len(self.x0), -1, np.int64)

    def arrays(self) -> dict[str, NDArray[Any]]:
        return {"x0": self.x0, "v0": self.v0, "clock": np.array([self.t0, self.time])}
