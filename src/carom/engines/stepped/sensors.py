"""Sensors: bodies, or pieces of bodies, that overlap others and say so, and never push
(Box2D's sensor shapes).

A sensor piece touches nothing: its row in the filters the engine steps with, one a piece
(:func:`.filters.piece_filters`), is zeroed (no category, no mask, no group), so the broad
phase's pairs with it are dropped before the narrow phase, and no exact impact, sweep or ray
meets it. A sensor body is one whose pieces are all sensors (a dynamic one flies freely); a
body with some sensor pieces (a character's foot sensor) is solid in the others, and moves
and weighs as a whole. What a sensor piece sees is decided by the caller's own filters
(:mod:`.filters`): it reports a body when the two would touch were it solid. A sensor piece
sees no other sensor piece, nor the world's walls and planes.

After each step that gathers events, every broad-phase pair of a sensor and a body is
tested exactly at the step's end (the pieces placed at their poses then: overlapping or
touching, separation <= 0); against the last step's pairs this gives the sensor events:

- **begin**: a body began to overlap a sensor;
- **end**: a body stopped overlapping it (or was removed).

A pair of which neither body moves (a sleeping body in a static sensor) still overlaps, as
in Box2D, where sleep ends nothing. Keys and the begin/end comparison are those of the
contact events (:func:`carom.engines.stepped.events.compare`): pairs as ``(sensor + 1) *
(N + 1) + (visitor + 1)`` in the caller's numbers.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit
from numpy.typing import NDArray

from carom.engines.stepped.events import compare, split_off
from carom.engines.stepped.filters import collides, default_filters, piece_filters

__all__ = ["SENSOR_DTYPE", "SensorArrays", "Sensors", "sensor_pair"]

#: a sensor event: the sensor's index and the visitor's (the world's body indices)
SENSOR_DTYPE = np.dtype([("sensor", np.int64), ("visitor", np.int64)])


class SensorArrays(NamedTuple):
    """One step's sensor events: structured arrays of :data:`SENSOR_DTYPE`."""

    #: bodies that began to overlap a sensor: ``sensor``, ``visitor``
    begin: NDArray[np.void]
    #: bodies that stopped overlapping a sensor: ``sensor``, ``visitor``
    end: NDArray[np.void]


@njit(cache=True, inline="always")
def sensor_pair(
    pa: int, pb: int, piece_body: np.ndarray, sensor: np.ndarray, filters: np.ndarray,
    number: np.ndarray,
) -> tuple[int, int, int, int]:  # fmt: skip
    """Pieces ``pa`` and ``pb`` as a sensor piece and a visitor's: ``(sensor body, visitor
    body, sensor piece, visitor piece)``, or -1s when the pair is not one a sensor reports
    (neither or both sensor pieces (``sensor`` (P,)), a wall or plane, kept apart by the
    caller's body ``filters``)."""
    a = piece_body[pa]
    b = piece_body[pb]
    if sensor[pa] == sensor[pb] or number[a] < 0 or number[b] < 0:
        return -1, -1, -1, -1
    if sensor[pb]:
        a, b, pa, pb = b, a, pb, pa
    if not collides(filters, a, b):
        return -1, -1, -1, -1
    return a, b, pa, pb


class Sensors:
    """The sensors of an engine of N rows numbered ``number`` (N,) for the caller (-1: the
    world's walls and planes) and P ``pieces``, their pairs overlapping at the last step and
    its events."""

    def __init__(self, number: NDArray[np.int64], pieces: int) -> None:
        n = number.shape[0]
        self.number = number
        #: which pieces are sensors (P,), and the caller's filters (N, 3): whom each sees
        self.mask = np.zeros(pieces, np.bool_)
        self.filters = default_filters(n)
        #: the pairs overlapping at the last step (sorted keys), and its events
        self.keys = np.zeros(0, np.int64)
        self.last = SensorArrays(np.zeros(0, SENSOR_DTYPE), np.zeros(0, SENSOR_DTYPE))
        #: pairs of bodies taken out of the world since the last step: they end in the next
        self.ending = np.zeros(0, np.int64)

    def forget(self, gone: NDArray[np.int64]) -> None:
        """Bodies ``gone`` (the caller's numbers) left the world: their pairs end at the next
        step."""
        self.keys, dropped = split_off(self.keys, gone, self.number.shape[0] + 1)
        self.ending = np.concatenate((self.ending, dropped))

    @property
    def on(self) -> bool:
        """Whether any piece is a sensor."""
        return bool(self.mask.any())

    def solid(self, table: NDArray[np.int64], piece_body: NDArray[np.int64]) -> NDArray[np.int64]:
        """The filters (P, 3) the engine steps with, one a piece of body ``piece_body`` (P,):
        the caller's ``table`` (N, 3), kept as whom sensors see, with the sensor pieces' rows
        zeroed (nothing touches them)."""
        self.filters = table.copy()
        return piece_filters(table, piece_body, self.mask)

    def update(self, keys: NDArray[np.int64], moving: NDArray[np.bool_]) -> None:
        """The events of a step whose end found the pairs ``keys`` (k,) overlapping (repeats
        allowed); ``moving`` (N,) the awake dynamic bodies."""
        n = self.number.shape[0] + 1
        now, began, _, ended = compare(keys, self.keys, moving, n)
        ended = np.concatenate((self.ending, ended))
        self.ending = np.zeros(0, np.int64)
        begin = np.zeros(began.size, SENSOR_DTYPE)
        begin["sensor"], begin["visitor"] = began // n - 1, began % n - 1
        end = np.zeros(ended.size, SENSOR_DTYPE)
        end["sensor"], end["visitor"] = ended // n - 1, ended % n - 1
        self.keys = now
        self.last = SensorArrays(begin, end)

    def visitors(self, sensor: int) -> NDArray[np.int64]:
        """The bodies overlapping ``sensor`` (a row) at the last step, sorted (k,)."""
        n = self.number.shape[0] + 1
        mine = self.keys[self.keys // n - 1 == sensor]
        return np.asarray(mine % n - 1, np.int64)
