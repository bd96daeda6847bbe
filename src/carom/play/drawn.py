"""The shapes the page draws, as flat arrays in the bodies' frames (sent once a scene, and
again when bodies are added): the same arrays for a live world and for a replay.

2D: every piece's outline as a ring of points (a circle as a 32-gon, rounded corners as arcs:
:class:`carom.viz.animate.Outlines`); 3D: every piece's triangles
(:class:`carom.viz.animate.Facets`). Spheres and disks of the event-driven engine have no
pieces: the page draws them from their radii.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom.bodies import Pieces
from carom.viz.animate import Facets, Outlines

__all__ = ["shape_arrays"]


def shape_arrays(
    dim: int,
    pieces: Sequence[Pieces],
    radius: NDArray[np.float64],
    mass: NDArray[np.float64],
    still: NDArray[np.bool_],
) -> dict[str, NDArray[Any]]:
    """The arrays of a geometry message (module docstring) for N bodies.

    Parameters
    ----------
    dim : int
        2 or 3.
    pieces : sequence of N tuples
        Each body's convex pieces in its frame (empty: a sphere or disk).
    radius : (N,) float64
        Each sphere's radius [m] (the rigid bodies': their reach; unused for those with pieces).
    mass : (N,) float64
        [kg]; infinite for still bodies.
    still : (N,) bool
        Static or kinematic: drawn grey.

    Returns
    -------
    dict
        ``radius`` (N,) float32, ``mass`` (N,) float32 (0 for infinite), ``still`` (N,) uint8,
        ``round`` (N,) uint8 (drawn from its radius); 2D: ``ring`` (M, 2) float32 points,
        ``ring_start`` (K + 1,) int32 (ring k is ``ring[ring_start[k]:ring_start[k + 1]]``),
        ``ring_body`` (K,) int32, ``ring_spoke`` (K,) uint8 (a circle: drawn with a spoke so
        that its turn shows); 3D: ``tri`` (T, 3, 3) float32 corners, ``tri_body`` (T,) int32.
    """
    n = len(pieces)
    every = list(pieces)
    finite = np.where(np.isfinite(mass), mass, 0.0)
    out: dict[str, NDArray[Any]] = {
        "radius": np.asarray(radius, np.float32),
        "mass": finite.astype(np.float32),
        "still": np.asarray(still, np.uint8),
        "round": np.array([not p for p in every], np.uint8).reshape(n),
    }
    if dim == 2:
        outlines = Outlines(every)  # type: ignore[arg-type]
        sizes = np.diff(np.concatenate(([0], outlines.splits, [len(outlines.points)])))
        start = np.concatenate(([0], np.cumsum(sizes))) if len(outlines.body) else np.zeros(1)
        out["ring"] = outlines.points.astype(np.float32).reshape(-1, 2)
        out["ring_start"] = start.astype(np.int32)
        out["ring_body"] = outlines.body.astype(np.int32)
        out["ring_spoke"] = outlines.circle.astype(np.uint8)
    else:
        facets = Facets(every)  # type: ignore[arg-type]
        out["tri"] = facets.corners.astype(np.float32).reshape(-1, 3, 3)
        out["tri_body"] = facets.body.astype(np.int32)
    return out
