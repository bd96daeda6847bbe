"""Frames and recordings: every body's state at output times, and the checks on those times.

:meth:`carom.World.frames` yields a :class:`Frame` at a time; :meth:`carom.World.record`
returns a :class:`Recording` of many, written by the engine in one call.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, NoReturn

import numpy as np
from numpy.typing import NDArray

from carom.engines.base import Engine, FrameArrays, Sink
from carom.errors import CaromError
from carom.limits import LARGEST, MAX_FRAMES, MAX_STEPS

__all__ = [
    "RECORD_BYTES",
    "Frame",
    "Recording",
    "advance_frame_by_frame",
    "alive_of",
    "check_interval",
    "check_span",
    "check_steps",
    "check_times",
    "check_until",
    "frame_grid",
]

FloatArray = NDArray[np.float64]

#: the most memory [bytes] one :meth:`carom.World.record` call may fill with frames
RECORD_BYTES = 2_000_000_000


@dataclass(frozen=True)
class Frame:
    """The state of every body at one output time.

    Attributes
    ----------
    time : float
        [s].
    positions, velocities : (N, d) float64
        [m], [m/s]; periodic boxes wrap positions into the box.
    orientations : (N,) float64 in 2D, (N, 4) float64 in 3D
        Angle about z [rad]; unit quaternion ``w, x, y, z`` (body to world).
    angular_velocities : (N, 3) float64
        [rad/s], world frame (2D: about z, column 2).
    alive : (N,) bool or None
        Which bodies are in the world (False: removed, :meth:`carom.World.remove_body`; their
        rows hold where they stopped); None: every body.
    """

    time: float
    positions: FloatArray
    velocities: FloatArray
    orientations: FloatArray
    angular_velocities: FloatArray
    alive: NDArray[np.bool_] | None = None

    @classmethod
    def of(cls, out: FrameArrays, f: int, dim: int, alive: NDArray[np.bool_] | None) -> Frame:
        """Frame ``f`` of what an engine wrote into ``out`` (views of its arrays); ``alive``
        (N,) as :attr:`alive`."""
        orient = out.orientations[f]
        return cls(
            float(out.times[f]),
            out.positions[f],
            out.velocities[f],
            orient[:, 0] if dim == 2 else orient,
            out.angular_velocities[f],
            alive,
        )


@dataclass(frozen=True)
class Recording:
    """Every body's state at each of ``F`` frame times (:meth:`carom.World.record`).

    Attributes
    ----------
    times : (F,) float64
        [s].
    positions, velocities : (F, N, d) float64
        [m], [m/s]; periodic boxes wrap positions into the box.
    orientations : (F, N) float64 in 2D, (F, N, 4) float64 in 3D
        Angle about z [rad]; unit quaternion ``w, x, y, z`` (body to world).
    angular_velocities : (F, N, 3) float64
        [rad/s], world frame (2D: about z, column 2).
    alive : (N,) bool or None
        Which bodies are in the world through the frames (False: removed before them, their
        rows frozen where they stopped); None: every body.
    """

    times: FloatArray
    positions: FloatArray
    velocities: FloatArray
    orientations: FloatArray
    angular_velocities: FloatArray
    alive: NDArray[np.bool_] | None = None

    def __len__(self) -> int:
        return len(self.times)

    def frame(self, f: int) -> Frame:
        """Frame ``f`` as a :class:`Frame` (views of the recording's arrays)."""
        return Frame(
            float(self.times[f]),
            self.positions[f],
            self.velocities[f],
            self.orientations[f],
            self.angular_velocities[f],
            self.alive,
        )

    @classmethod
    def of(
        cls, out: FrameArrays, done: int, dim: int, alive: NDArray[np.bool_] | None
    ) -> Recording:
        """The first ``done`` frames an engine wrote into ``out``; ``alive`` (N,) as
        :attr:`alive`."""
        orientations = out.orientations[:done]
        return cls(
            times=out.times[:done],
            positions=out.positions[:done],
            velocities=out.velocities[:done],
            orientations=orientations[..., 0] if dim == 2 else orientations,
            angular_velocities=out.angular_velocities[:done],
            alive=alive,
        )


def check_interval(frame_interval: float) -> None:
    """Refuse a frame interval that is not a positive, finite time."""
    if not (frame_interval > 0.0 and math.isfinite(frame_interval)):
        raise CaromError(f"frame_interval must be a positive time [s]; got {frame_interval!r}")


def check_until(until: float, now: float) -> float:
    """``until`` as a float at or after ``now`` [s], or a CaromError naming it."""
    wrong = CaromError(f"until must be a finite time >= the current time {now} s; got {until!r}")
    if isinstance(until, str | bytes | bool):
        raise wrong
    try:
        until = float(until)
    except (TypeError, ValueError):
        raise wrong from None
    if not math.isfinite(until) or until < now:
        raise wrong
    if until > LARGEST:
        raise CaromError(
            f"until = {until:g} s exceeds {LARGEST:g} s; carom accepts magnitudes up to "
            f"{LARGEST:g} in SI units (docs/scenes.md, Limits)"
        )
    return until


def check_span(
    now: float, until: float, step: float | None, frame_interval: float | None = None
) -> None:
    """Refuse, before anything runs, a stretch from ``now`` to ``until`` [s] that would take
    more than :data:`MAX_STEPS` steps of ``step`` [s] (None: an engine without steps) or
    more than :data:`MAX_FRAMES` frames ``frame_interval`` [s] apart, with the numbers."""
    span = until - now
    if step is not None and span / step > MAX_STEPS:
        raise CaromError(
            f"reaching until = {until:g} s from {now:g} s takes {span / step:.3g} steps of "
            f"{step:.3g} s, more than the {MAX_STEPS:.0e} carom takes in one run; run to an "
            f"earlier time (and on from there), or take a lower rate"
        )
    if frame_interval is not None and span / frame_interval > MAX_FRAMES:
        raise CaromError(
            f"frames every {frame_interval:g} s up to until = {until:g} s are "
            f"{span / frame_interval:.3g} frames, more than the {MAX_FRAMES:,} carom keeps; "
            f"take a longer frame_interval"
        )


def check_times(grid: FloatArray, now: float, n_bodies: int, dim: int) -> None:
    """Refuse frame times (F,) [s] that are not finite, decrease or start before ``now``, or
    whose frames of ``n_bodies`` bodies would take more than :data:`RECORD_BYTES`."""
    if grid.ndim != 1:
        raise CaromError(f"times must be a 1-D array of frame times [s]; got {grid.shape}")
    # one pass when all is well (ascending between finite ends is finite throughout)
    if grid.size and not (
        math.isfinite(grid[0])
        and math.isfinite(grid[-1])
        and grid[0] >= now
        and bool((grid[1:] >= grid[:-1]).all())
    ):
        _refuse_times(grid, now)
    per_frame = FrameArrays.frame_bytes(n_bodies, dim)
    if grid.size * per_frame > RECORD_BYTES:
        raise CaromError(
            f"{grid.size:,} frames of {n_bodies:,} bodies take "
            f"{grid.size * per_frame / 1e9:.1f} GB, more than the {RECORD_BYTES / 1e9:g} GB "
            f"a recording may; record fewer times at once, or stream them with frames()"
        )


def _refuse_times(grid: FloatArray, now: float) -> NoReturn:
    """Name the first frame time :meth:`carom.World.record` cannot take."""
    bad = ~np.isfinite(grid)
    if bad.any():
        i = int(np.argmax(bad))
        raise CaromError(f"times must be finite [s]; got times[{i}] = {float(grid[i])!r}")
    if grid[0] < now:
        raise CaromError(
            f"times must not start before the current time {now} s; "
            f"got times[0] = {float(grid[0])!r}"
        )
    i = int(np.argmax(np.diff(grid) < 0.0))
    raise CaromError(
        f"times must not decrease; got times[{i}] = {float(grid[i])!r} then "
        f"times[{i + 1}] = {float(grid[i + 1])!r}"
    )


def frame_grid(now: float, until: float, frame_interval: float) -> FloatArray:
    """The times [s] at which :meth:`carom.World.frames` yields, (F,):
    ``now + k frame_interval`` for k = 1, 2, ... while before ``until``, then ``until``."""
    until = check_until(until, now)
    check_interval(frame_interval)
    count = int(min((until - now) / frame_interval + 2.0, MAX_FRAMES + 2.0))
    grid = now + np.arange(1, count + 1, dtype=np.float64) * frame_interval
    grid = grid[grid < until]
    if grid.size >= MAX_FRAMES:
        raise CaromError(
            f"{grid.size:,} frames or more: more than the {MAX_FRAMES:,} carom writes; "
            f"take a longer frame_interval"
        )
    return np.append(grid, until)


def advance_frame_by_frame(
    engine: Engine,
    until: float,
    frame_interval: float | None,
    sink: Sink | None,
    stop: Callable[[], bool] | None,
    reached: Callable[[bool], None],
    world: Any,
) -> Iterator[Frame]:
    """Advance ``engine`` to ``until`` [s], yielding a :class:`Frame` of ``world``'s bodies
    (its ``n_bodies``, ``dim`` and ``alive``) at each ``start + k frame_interval`` (None:
    none) and at ``until``; ``reached`` is told after each stretch whether the engine got
    there (False: ``stop`` ended it, and no frame follows)."""
    n, dim = world.n_bodies, world.dim
    alive = alive_of(world)
    start = engine.time
    k = 1
    while True:
        target = until if frame_interval is None else min(until, start + k * frame_interval)
        if frame_interval is None:
            done = engine.advance(target, np.iinfo(np.int64).max, sink, stop)
        else:  # one compiled call advances and samples (event-driven engine)
            out = FrameArrays.empty(1, n, dim)
            done = engine.advance_frames(np.array([target]), sink, stop, out) == 1
        reached(done)
        if not done:
            return
        if frame_interval is not None:
            yield Frame.of(out, 0, dim, alive)
        if target >= until:
            return
        k += 1


def alive_of(world: Any) -> NDArray[np.bool_] | None:
    """``world``'s mask of bodies in it (N,), None when every body is."""
    alive: NDArray[np.bool_] | None = getattr(world, "alive", None)
    return None if alive is None or alive.all() else alive


def check_steps(dt: float | None, engine: str, **times: float | None) -> None:
    """The frames and the end of a recorded run fall on a time-stepped engine's steps
    (``dt`` [s]; None: an engine that stops at any time), so that what is recorded never
    changes the steps taken (the engine can end on any time with a shorter step, which a
    frame between two steps would insert): refuse a time (``until``, ``frame_interval``,
    ``warmup``: given by name, in seconds) that is not a whole number of them, naming the
    nearest that is and the ``engine``'s table."""
    if dt is None:
        return
    for name, value in times.items():
        if value is None:
            continue
        steps = value / dt
        if abs(steps - round(steps)) > 1e-6 * max(1.0, steps) or round(steps) < 1:
            near = max(1, round(steps)) * dt
            raise CaromError(
                f"{name} = {value:g} s is not a whole number of the {engine} engine's steps "
                f"(1/{1.0 / dt:g} s): frames and the end fall on steps; use "
                f"{near:.6g} s ({max(1, round(steps))} steps), or change [{engine}] rate"
            )
