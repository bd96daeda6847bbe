"""The collisions a World keeps in memory, and where an engine's collisions go during a run.

An engine hands its collisions over in blocks (structured arrays of
:data:`carom.engines.base.COLLISION_DTYPE`); :meth:`CollisionLog.sink` makes the function that
receives them: it streams each block to the caller's function, keeps it (all, or the
collisions of some bodies) up to :data:`LOG_LIMIT`, or both.
"""

from __future__ import annotations

import warnings
from collections.abc import Callable
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from carom.engines.base import COLLISION_DTYPE, PARTNER_BODY
from carom.errors import CaromError, CaromWarning

__all__ = ["LOG_LIMIT", "CollisionLog"]

#: collisions a World keeps in memory with ``log=True`` (64 bytes each: 64 MB); more are
#: counted in ``World.collisions_dropped``: stream them with ``on_collisions`` instead
LOG_LIMIT = 1_000_000


class CollisionLog:
    """The collisions kept so far, and how many the full log dropped."""

    def __init__(self, kept: NDArray[Any] | None = None, dropped: int = 0) -> None:
        self._blocks: list[NDArray[Any]] = [kept] if kept is not None and kept.size else []
        self._kept = 0 if kept is None else int(kept.size)
        self.dropped = dropped

    @property
    def collisions(self) -> NDArray[Any]:
        """Every collision kept, in the order they came (one array of ``COLLISION_DTYPE``)."""
        if not self._blocks:
            return np.empty(0, dtype=COLLISION_DTYPE)
        if len(self._blocks) > 1:
            self._blocks = [np.concatenate(self._blocks)]
        return self._blocks[0]

    def sink(
        self,
        log: bool | ArrayLike,
        stream: Callable[[NDArray[Any]], object] | None,
        n_bodies: int,
    ) -> Callable[[NDArray[Any]], None] | None:
        """Where an engine's collisions go: kept (``log`` True, or the body indices whose
        collisions to keep), streamed to ``stream``, both, or nowhere (None: the engine then
        logs nothing)."""
        if isinstance(log, bool | np.bool_):
            keep_all, bodies = bool(log), None
        else:
            bodies = np.asarray(log).reshape(-1)
            if bodies.size and (
                not np.issubdtype(bodies.dtype, np.integer)
                or np.any((bodies < 0) | (bodies >= n_bodies))
            ):
                raise CaromError(
                    f"log must be True, False or body indices in [0, {n_bodies}); got {log!r}"
                )
            keep_all = False
        keep = keep_all or (bodies is not None and bodies.size > 0)
        if not keep and stream is None:
            return None

        def sink(block: NDArray[Any]) -> None:
            if stream is not None:
                stream(block)
            if not keep:
                return
            if bodies is not None:
                mine = np.isin(block["body"], bodies)
                mine |= (block["kind"] == PARTNER_BODY) & np.isin(block["partner"], bodies)
                block = block[mine]
            self._keep(block)

        return sink

    def _keep(self, block: NDArray[Any]) -> None:
        room = LOG_LIMIT - self._kept
        if block.size > room:
            if self.dropped == 0:
                warnings.warn(
                    f"the in-memory collision log is full ({LOG_LIMIT} collisions, "
                    f"{LOG_LIMIT * COLLISION_DTYPE.itemsize / 1e6:.0f} MB); later ones are "
                    f"counted in World.collisions_dropped but not kept: stream them with "
                    f"on_collisions=... instead",
                    CaromWarning,
                    stacklevel=5,
                )
            self.dropped += block.size - room
            block = block[:room]
        if block.size:
            self._blocks.append(block)
            self._kept += block.size
