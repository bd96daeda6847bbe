"""What a stepped engine keeps from step to step beside its bodies' motion, the same in 2D and
3D: which bodies sleep and for how long they have been still (Box2D's islands and sleep), and
the last step's contact impulses, which warm-start the next (Box2D's and Rapier's warm start).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from carom.laws.kinds import KIND_DYNAMIC

__all__ = ["StepMemory", "new_memory"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


class StepMemory(NamedTuple):
    """Sleep and the warm-start cache of N bodies (a checkpoint keeps them by these names).

    Attributes
    ----------
    awake : (N,) bool
        Dynamic bodies being simulated (false: asleep).
    clock : (N,) float64
        How long each body has been slow enough to sleep [s].
    island : (N,) int64
        The island a sleeping body sleeps in (its root body).
    cache_keys : (K,) int64
        Contacts of the last step (``a * P + b`` for pieces ``a < b`` of P), sorted.
    cache_ids : (K, points) int64
        Their points' feature ids (-1: no point).
    cache_impulses : float64
        Each point's normal impulse and its tangent impulse [N s]: (K, 4) in 2D (normal and
        tangent of each of two points), (K, 4, 4) in 3D (the tangent as a world vector).
    cache_count : (1,) int64
        How many rows of the cache are used.
    """

    awake: NDArray[np.bool_]
    clock: FloatArray
    island: IntArray
    cache_keys: IntArray
    cache_ids: IntArray
    cache_impulses: FloatArray
    cache_count: IntArray


def new_memory(kind: NDArray[np.int8], points: int, impulse_shape: tuple[int, ...]) -> StepMemory:
    """The memory at the start: every dynamic body awake, no contact cached; a cached
    contact has up to ``points`` points and impulses of ``impulse_shape`` per row."""
    n = kind.shape[0]
    return StepMemory(
        awake=kind == KIND_DYNAMIC,
        clock=np.zeros(n),
        island=np.arange(n, dtype=np.int64),
        cache_keys=np.zeros(0, np.int64),
        cache_ids=np.zeros((0, points), np.int64),
        cache_impulses=np.zeros((0, *impulse_shape)),
        cache_count=np.zeros(1, np.int64),
    )
