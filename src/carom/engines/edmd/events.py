"""The event-driven engine's contact events between two steps of a game loop: begin, end and
hit, as :class:`carom.engines.stepped.events.EventArrays`, the rigid engines' own.

Hard spheres touch for an instant: a pair that collides begins and ends touching in the same
step, and every collision at least the threshold's approach speed is a hit at its own time. A
sphere that comes to rest on a wall or plane (it slides on it) keeps touching the scenery until
it leaves: it began in the step it landed and ends in the step it lifts off. The scenery is
body -1, as in the rigid engines' events; ``a < b`` and each normal points from a to b.
"""

from __future__ import annotations

from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom.engines.stepped.events import EventArrays, event_dtypes

__all__ = ["EdmdEvents"]


class EdmdEvents:
    """The contact events of an event-driven engine of ``n`` bodies in ``d`` dimensions."""

    def __init__(self, n: int, d: int) -> None:
        self.n, self.d = n, d
        self.dtypes = event_dtypes(d)
        #: whether the engine gathers now (during a game loop's step, once events were asked
        #: for: other runs never do)
        self.gathering = False
        #: the least approach speed of a hit [m/s]
        self.threshold = 1.0
        #: the pairs touching at the end of the last step (sorted keys: resting on a face)
        self.keys = np.zeros(0, np.int64)
        self.last = EventArrays(*(np.zeros(0, t) for t in self.dtypes))
        self._met: list[tuple[NDArray[Any], ...]] = []

    def gather(
        self, time: NDArray[np.float64], a: NDArray[np.int64], b: NDArray[np.int64],
        un: NDArray[np.float64], point: NDArray[np.float64], normal: NDArray[np.float64],
    ) -> None:  # fmt: skip
        """Keep a block of collisions: times (k,) [s], bodies ``a`` (k,) and partners ``b``
        (k,) in the caller's numbering (-1: a wall or plane), normal speeds before (k,)
        [m/s], points and normals from a to b (k, d)."""
        # a < b, the scenery first: swap where b is the smaller (the normal turns round)
        swap = b < a
        first, second = np.where(swap, b, a), np.where(swap, a, b)
        sign = np.where(swap, -1.0, 1.0)[:, None]
        self._met.append((time.copy(), first, second, un.copy(), point.copy(), sign * normal))

    def close(self, resting: NDArray[np.int64]) -> None:
        """The step's events (:attr:`last`), from the collisions gathered since the last
        close and the bodies ``resting`` (k,) on a wall or plane now."""
        n = self.n + 1
        if self._met:
            time, a, b, un, point, normal = (
                np.concatenate(c) for c in zip(*self._met, strict=True)
            )
        else:
            time, a, b, un = np.zeros(0), np.zeros(0, np.int64), np.zeros(0, np.int64), np.zeros(0)
            point = normal = np.zeros((0, self.d))
        self._met = []
        keys = (a + 1) * n + (b + 1)
        now = np.unique(resting.astype(np.int64) + 1)  # the keys of (-1, body): body + 1
        met, first = np.unique(keys, return_index=True)  # (the first collision of each pair)
        began = ~np.isin(met, self.keys)
        begin = np.zeros(int(began.sum()), self.dtypes[0])
        rows = first[began]
        begin["a"], begin["b"] = a[rows], b[rows]
        begin["point"], begin["normal"] = point[rows], normal[rows]
        ended = np.setdiff1d(np.union1d(self.keys, met), now)
        end = np.zeros(ended.size, self.dtypes[1])
        end["a"], end["b"] = ended // n - 1, ended % n - 1
        hard = -un >= self.threshold
        hit = np.zeros(int(hard.sum()), self.dtypes[2])
        hit["a"], hit["b"], hit["time"] = a[hard], b[hard], time[hard]
        hit["point"], hit["normal"], hit["speed"] = point[hard], normal[hard], -un[hard]
        self.keys = now
        self.last = EventArrays(begin, end, hit)
