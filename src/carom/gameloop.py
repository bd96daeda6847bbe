"""A world a game drives, frame by frame: :meth:`GameLoop.step` (issue 43).

A game loop advances the world by one frame at a time and reaches into it between frames.
:class:`GameLoop` is the part of :class:`carom.World` that does that: ``world.step()`` takes
one step of the engine's own length (the rigid engines' ``1 / rate``), ``world.step(dt)`` one
of any length, and :attr:`GameLoop.steps` counts them. Stepping by hand and ``run`` take the
same steps, so they give the same bits at the same times.

>>> import carom
>>> from carom.shapes import Box
>>> world = carom.World(2, [10.0, 10.0], gravity=[0.0, -9.81], boundary="open")
>>> _ = world.add_body(Box(1.0, 1.0), [5.0, 5.0])
>>> for frame in range(60):
...     world.step()
>>> world.steps, round(world.time, 12)
(60, 1.0)
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from carom.engines.base import Engine
from carom.engines.stepped.driver import SteppedEngine
from carom.errors import CaromError
from carom.limits import LARGEST

__all__ = ["GameLoop"]


class _Running(Protocol):
    """What :class:`GameLoop` takes from the World it is part of."""

    reached: bool

    @property
    def time(self) -> float: ...

    @property
    def engine(self) -> Engine | None: ...

    def build(self) -> Engine: ...

    def _sink(
        self, log: bool | Any, stream: Callable[[NDArray[Any]], object] | None
    ) -> Callable[[NDArray[Any]], None] | None: ...


#: the attribute in which a world keeps its event-driven engine and the steps taken on it
_HAND = "_hand_steps"


class GameLoop:
    """Stepping a :class:`carom.World` by hand, one frame at a time."""

    def step(self: _Running, dt: float | None = None) -> None:
        """Advance the world by one step.

        Parameters
        ----------
        dt : float, optional
            The step [s]. By default the engine's own: the rigid engines' ``1 / rate``; the
            event-driven engine has none and needs one. The rigid engines take another
            ``dt`` as one step of that length in every stage (as Box2D's ``b2World_Step``
            takes the frame's time); the clock's origin moves to where it ends, and later
            steps are whole steps from there. The event-driven engine advances exactly
            ``dt``, every impact on the way at its own time.

        Raises
        ------
        CaromError
            ``dt`` not a positive finite time, shorter than a millionth of the engine's step,
            or reaching past carom's largest time; no ``dt`` for the event-driven engine.
            Nothing has moved then.
        """
        engine = self.build()
        sink = self._sink(False, None)
        if isinstance(engine, SteppedEngine):
            step = engine.dt if dt is None else _positive_time(dt)
            if step < 1e-6 * engine.dt:
                raise CaromError(
                    f"dt = {step:g} s is under a millionth of the engine's step "
                    f"({engine.dt:g} s); take dt >= {1e-6 * engine.dt:g} s"
                )
            _within_limits(step, self.time)
            engine.step_of(step, sink)
            self.reached = True
            return
        if dt is None:
            raise CaromError(
                "the event-driven engine has no step of its own: give the time to advance, "
                "e.g. world.step(1 / 60) [s]"
            )
        step = _positive_time(dt)
        _within_limits(step, self.time)
        self.reached = engine.advance(self.time + step, np.iinfo(np.int64).max, sink)
        kept, count = getattr(self, _HAND, (None, 0))
        setattr(self, _HAND, (engine, (count if kept is engine else 0) + 1))

    @property
    def steps(self: _Running) -> int:
        """Steps taken since the engine was built: every step of the rigid engines (by
        :meth:`step`, ``run``, ``frames`` or ``record``); the calls of :meth:`step` for the
        event-driven engine, whose runs take no steps. 0 before the engine is built."""
        engine = self.engine
        if engine is None:
            return 0
        if isinstance(engine, SteppedEngine):
            return engine.steps
        kept, count = getattr(self, _HAND, (None, 0))
        return int(count) if kept is engine else 0


def _positive_time(dt: object) -> float:
    """``dt`` as a positive finite float [s], or a CaromError naming it."""
    wrong = CaromError(f"dt must be a positive finite time [s]; got {dt!r}")
    if isinstance(dt, str | bytes | bool):
        raise wrong
    try:
        value = float(dt)  # type: ignore[arg-type]
    except (TypeError, ValueError):
        raise wrong from None
    if not (math.isfinite(value) and value > 0.0):
        raise wrong
    return value


def _within_limits(dt: float, now: float) -> None:
    """Refuse a step that would take the clock past carom's largest time."""
    if now + dt > LARGEST:
        raise CaromError(
            f"dt = {dt:g} s takes the clock from {now:g} s past {LARGEST:g} s; carom accepts "
            f"magnitudes up to {LARGEST:g} in SI units (docs/scenes.md, Limits)"
        )
