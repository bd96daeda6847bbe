"""Sensors: bodies that feel what overlaps them and push nothing (issue 43, item 3).

:class:`Sensing` is the part of :class:`carom.World` that marks bodies as sensors
(``world.set_sensor``) and reports, after each step, the bodies that began or stopped
overlapping one (``world.sensor_events()``), as Box2D's sensor events do: a goal area, a
trigger zone, a pickup. A sensor is any body, of any shape and kind: it touches nothing
(no contact, no impact, no ray sees it; a dynamic sensor falls freely through the floor)
and sees the bodies its collision filter would let it touch (:meth:`set_filter`), other
sensors and the world's walls excepted. Some pieces of a body can be sensors, the body solid
in the others (``world.set_sensor(i, pieces=[k])``: a foot sensor). The rigid engines.

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

    def set_sensor(
        self: _Running,
        ids: int | ArrayLike,
        sensor: bool = True,
        *,
        pieces: ArrayLike | None = None,
    ) -> None:
        """Make bodies ``ids`` sensors (or, ``sensor=False``, solid again); or, with
        ``pieces``, some pieces of one body.

        Parameters
        ----------
        ids : int or (k,) array_like of int
            Body indices (any kind); one body with ``pieces``.
        sensor : bool, default True
            A sensor touches nothing and reports the bodies overlapping it
            (:meth:`sensor_events`); a solid body touches as its filter says.
        pieces : (m,) array_like of int, optional
            Only these pieces of body ``ids`` (its convex pieces in order, as
            ``world.bodies.pieces[ids]`` holds them: a Compound's parts, each convex part one
            piece; a circle or sphere is one): a character's foot sensor, a car's pickup
            zone. The body moves and weighs as a whole, and touches with its other pieces;
            a sensor piece reports, as a sensor body does, the body index of its own. (A
            body that is a sensor whole stays one whatever its pieces say.)

        Notes
        -----
        Holds from the next step, through rebuilds, runs and checkpoints; set before the
        engine is built, from its start (a body may start inside a sensor). A body made
        solid inside another is pushed out by the next step's contacts. The rigid engines.

        Raises
        ------
        CaromError
            An index out of range or of a removed body; ``pieces`` of more than one body,
            or not pieces of it; the event-driven engine. Nothing has changed then.
        """
        rows = _rows(self, np.atleast_1d(np.asarray(ids)))
        marked = _pieces_of(self, rows, pieces)
        engine = rigid_if_built(self)
        mask = sensors_of(self)
        kept = getattr(self, _PIECES, _NO_PIECES)
        if marked is None:
            mask[rows] = bool(sensor)
            kept = kept[~np.isin(kept[:, 0], rows)]  # (whole now, or solid whole)
        else:
            kept = kept[~(np.isin(kept[:, 0], rows) & np.isin(kept[:, 1], marked[:, 1]))]
            if sensor:
                kept = np.unique(np.concatenate((kept, marked)), axis=0)
        setattr(self, _PIECES, kept)
        if engine is not None:
            engine.use_sensors(mask, rows, kept)

    @property
    def sensors(self: _Running) -> NDArray[np.bool_]:
        """Which bodies are sensors (n,) bool, whole (:meth:`set_sensor`). A copy."""
        return sensors_of(self).copy()

    @property
    def sensor_pieces(self: _Running) -> NDArray[np.int64]:
        """The pieces made sensors of bodies otherwise solid (:meth:`set_sensor` with
        ``pieces``): rows (body, piece) (k, 2) int64, sorted. A copy."""
        return np.array(getattr(self, _PIECES, _NO_PIECES))

    def restore_sensors(
        self: _Running, sensor: NDArray[np.bool_], pieces: NDArray[np.int64] | None = None
    ) -> None:
        """Take which bodies are sensors from ``sensor`` (n,), as :attr:`sensors` gave it,
        and which pieces from ``pieces`` (k, 2), as :attr:`sensor_pieces` (a checkpoint's);
        the engine, if built, takes them too."""
        mask = np.array(sensor, dtype=np.bool_)
        self._sensors = mask
        kept = _NO_PIECES if pieces is None else np.array(pieces, np.int64).reshape(-1, 2)
        setattr(self, _PIECES, kept)
        engine = self.engine
        if engine is not None and isinstance(engine, SteppedEngine):
            engine.use_sensors(mask, np.zeros(0, np.int64), kept)

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
        if not sensors_of(self)[i] and i not in getattr(self, _PIECES, _NO_PIECES)[:, 0]:
            raise CaromError(f"body {i} is not a sensor: world.set_sensor({i}) makes it one")
        return engine.sensors.visitors(i)


#: no sensor pieces: (0, 2) rows (body, piece); the attribute in which a world keeps its own
_NO_PIECES = np.zeros((0, 2), np.int64)
_PIECES = "_sensor_pieces"


def _pieces_of(
    world: Any, rows: NDArray[np.int64], pieces: ArrayLike | None
) -> NDArray[np.int64] | None:
    """``pieces`` of the one body ``rows`` as rows (body, piece) (m, 2), each checked to be
    one of its pieces; None without ``pieces``; else a CaromError naming what is wrong."""
    if pieces is None:
        return None
    if rows.shape[0] != 1:
        raise CaromError(
            f"pieces= names pieces of one body; got {rows.shape[0]} bodies: call set_sensor "
            "once a body"
        )
    body = int(rows[0])
    count = max(1, len(world.bodies.pieces[body]))  # (a sphere: one piece, its own)
    raw = np.atleast_1d(np.asarray(pieces))
    if raw.ndim != 1 or raw.size == 0 or raw.dtype.kind not in "iu":
        raise CaromError(f"pieces must be piece indices (whole numbers); got {pieces!r}")
    bad = (raw < 0) | (raw >= count)
    if bad.any():
        raise CaromError(
            f"body {body} has pieces 0 to {count - 1} (world.bodies.pieces[{body}]); got "
            f"piece {int(raw[bad][0])}"
        )
    picked = np.unique(raw.astype(np.int64))
    return np.column_stack((np.full(picked.size, body, np.int64), picked))


def sensors_of(world: Any) -> NDArray[np.bool_]:
    """The world's sensor mask (n,), grown with False to its bodies."""
    return per_body(world, "_sensors", lambda k: np.zeros(k, np.bool_))
