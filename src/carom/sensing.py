"""Sensors: bodies that feel what overlaps them and push nothing (issue 43, item 3).

:class:`Sensing` is the part of :class:`carom.World` that marks bodies as sensors
(``world.set_sensor``) and reports, after each step, the bodies that began or stopped
overlapping one (``world.sensor_events()``), as Box2D's sensor events do: a goal area, a
trigger zone, a pickup. A sensor is any body, of any shape and kind: it touches nothing
(no contact, no impact, no ray sees it; a dynamic sensor falls freely through the floor)
and sees the bodies its collision filter would let it touch (:meth:`set_filter`), other
sensors and the world's walls excepted. The rigid engines.

>>> import carom
>>> from carom.shapes import Box, Circle
>>> world = carom.World(2, [10.0, 10.0], gravity=[0.0, -9.81], boundary="open")
>>> goal = world.add_body(Box(2.0, 1.0), [5.0, 2.0], kind="static")
>>> world.set_sensor(goal)
>>> ball = world.add_body(Circle(0.25), [5.0, 4.0])
>>> began = []
>>> for _ in range(60):
...     world.step()
...     began += world.sensor_events().begin.tolist()
>>> began
[(0, 1)]
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from carom.engines.stepped.driver import SteppedEngine
from carom.engines.stepped.sensors import SensorArrays
from carom.errors import CaromError
from carom.gameloop import _index, _rows, _Running, per_body, rigid_if_built

__all__ = ["Sensing", "SensorArrays", "sensors_of"]

_NOT_YET = (
    "sensors are the rigid engines' (the event-driven engine has no sensors yet): use "
    'engine="rigid"'
)


class Sensing:
    """Sensors and their events: mixed into :class:`carom.World`."""

    def set_sensor(self: _Running, ids: int | ArrayLike, sensor: bool = True) -> None:
        """Make bodies ``ids`` sensors (or, ``sensor=False``, solid again).

        Parameters
        ----------
        ids : int or (k,) array_like of int
            Body indices (any kind).
        sensor : bool, default True
            A sensor touches nothing and reports the bodies overlapping it
            (:meth:`sensor_events`); a solid body touches as its filter says.

        Notes
        -----
        Holds from the next step, through rebuilds, runs and checkpoints; set before the
        engine is built, from its start (a body may start inside a sensor). A body made
        solid inside another is pushed out by the next step's contacts. The rigid engines.

        Raises
        ------
        CaromError
            An index out of range or of a removed body; the event-driven engine. Nothing
            has changed then.
        """
        rows = _rows(self, np.atleast_1d(np.asarray(ids)))
        engine = rigid_if_built(self)
        mask = sensors_of(self)
        mask[rows] = bool(sensor)
        if engine is not None:
            engine.use_sensors(mask, rows)

    @property
    def sensors(self: _Running) -> NDArray[np.bool_]:
        """Which bodies are sensors (n,) bool (:meth:`set_sensor`). A copy."""
        return sensors_of(self).copy()

    def restore_sensors(self: _Running, sensor: NDArray[np.bool_]) -> None:
        """Take which bodies are sensors from ``sensor`` (n,), as :attr:`sensors` gave it (a
        checkpoint's); the engine, if built, takes them too."""
        mask = np.array(sensor, dtype=np.bool_)
        self._sensors = mask
        engine = self.engine
        if engine is not None and isinstance(engine, SteppedEngine):
            engine.use_sensors(mask, np.zeros(0, np.int64))

    def sensor_events(self: _Running) -> SensorArrays:
        """The sensor events of the last step, as NumPy structured arrays.

        Returns
        -------
        SensorArrays
            ``begin``: bodies that began to overlap a sensor; ``end``: bodies that stopped
            (or were removed); each a structured array of ``sensor`` and ``visitor``, the
            world's body indices, sorted by sensor then visitor.

        Notes
        -----
        A body overlaps a sensor when their shapes overlap or touch at the step's end (the
        exact test of the narrow phase, among the pairs the broad phase found for the
        step). A sleeping body in a sensor that does not move stays in it. Gathered by
        :meth:`step` (a game loop's steps) and, once this has been called, by every step.
        Empty before the first step gathered; that step's ``begin`` holds every body in a
        sensor then.
        """
        engine = self.build()
        if not isinstance(engine, SteppedEngine):
            raise CaromError(_NOT_YET)
        engine.events.on = True
        return engine.sensors.last

    def sensor_overlaps(self: _Running, index: int) -> NDArray[np.int64]:
        """The bodies overlapping sensor ``index`` at the last step that gathered events
        (:meth:`sensor_events`), sorted (k,) int64."""
        i = _index(self, index)
        engine = self.build()
        if not isinstance(engine, SteppedEngine):
            raise CaromError(_NOT_YET)
        if not sensors_of(self)[i]:
            raise CaromError(f"body {i} is not a sensor: world.set_sensor({i}) makes it one")
        return engine.sensors.visitors(i)


def sensors_of(world: Any) -> NDArray[np.bool_]:
    """The world's sensor mask (n,), grown with False to its bodies."""
    return per_body(world, "_sensors", lambda k: np.zeros(k, np.bool_))
