"""The same yardstick for every engine: fed each engine's state after every step.

:class:`Monitor` measures, from positions and velocities alone, what a user of any engine would
see: overlap of two bodies and of a body with a wall, bodies that went through a wall or
through each other (tunnelling), the energy, and the state at the closed form's check times.
Nothing here asks an engine about itself, so no engine is measured more kindly than another.
"""

from __future__ import annotations

import math
from typing import Any

import numba
import numpy as np
from numpy.typing import NDArray

from carom.compare.closed_form import Expectation
from carom.compare.spec import PeerScene

__all__ = ["Monitor", "pair_check"]

FloatArray = NDArray[np.float64]

#: at most this many points of the energy and penetration series are kept per engine
SERIES_POINTS = 1500


@numba.njit(cache=True)
def pair_check(
    before: FloatArray, after: FloatArray, radius: FloatArray, box: FloatArray, size: float
) -> tuple[float, int]:
    """Deepest overlap of two bodies after a step, and how many pairs passed through each
    other during it.

    A pair passed through when its separation turned by more than 90 degrees in one step
    while the straight path between the two separations came closer than the sum of the
    radii: the bodies swapped sides without being stopped.

    Parameters
    ----------
    before, after : (N, d) float64
        Centres at the start and end of the step [m].
    radius : (N,) float64
        [m].
    box : (d,) float64
        Box sides [m] (bodies outside are binned at its edge).
    size : float
        Grid cell side [m]: at least the largest contact distance plus twice the largest
        displacement in the step, so that every pair that can touch lies in adjacent cells.

    Returns
    -------
    overlap : float
        ``max(r_i + r_j - |x_i - x_j|)`` over pairs, or ``-inf`` [m].
    crossings : int
        Pairs that passed through each other.
    """
    n, dim = after.shape
    ncell = np.ones(3, np.int64)
    for k in range(dim):
        ncell[k] = max(1, min(int(box[k] / size), 1 << 20))
    while ncell[0] * ncell[1] * ncell[2] > 8 * n + 64:  # bound memory for sparse scenes
        for k in range(dim):
            ncell[k] = max(1, ncell[k] // 2)
    cell = np.empty(n, np.int64)
    coord = np.zeros((n, 3), np.int64)
    for i in range(n):
        for k in range(dim):
            q = math.floor(after[i, k] / box[k] * ncell[k])
            q = min(max(q, 0), ncell[k] - 1)
            coord[i, k] = q
        cell[i] = (coord[i, 0] * ncell[1] + coord[i, 1]) * ncell[2] + coord[i, 2]
    order = np.argsort(cell, kind="mergesort")
    total = ncell[0] * ncell[1] * ncell[2]
    start = np.zeros(total + 1, np.int64)
    for i in range(n):
        start[cell[i] + 1] += 1
    for c in range(total):
        start[c + 1] += start[c]
    overlap = -np.inf
    crossings = 0
    reach_z = 1 if dim == 3 else 0
    for i in range(n):
        for dx in range(-1, 2):
            cx = coord[i, 0] + dx
            if cx < 0 or cx >= ncell[0]:
                continue
            for dy in range(-1, 2):
                cy = coord[i, 1] + dy
                if cy < 0 or cy >= ncell[1]:
                    continue
                for dz in range(-reach_z, reach_z + 1):
                    cz = coord[i, 2] + dz
                    if cz < 0 or cz >= ncell[2]:
                        continue
                    c = (cx * ncell[1] + cy) * ncell[2] + cz
                    for slot in range(start[c], start[c + 1]):
                        j = order[slot]
                        if j <= i:
                            continue
                        s = radius[i] + radius[j]
                        d1 = 0.0
                        d0d1 = 0.0
                        d0d0 = 0.0
                        for k in range(dim):
                            a = after[j, k] - after[i, k]
                            b = before[j, k] - before[i, k]
                            d1 += a * a
                            d0d1 += a * b
                            d0d0 += b * b
                        overlap = max(overlap, s - math.sqrt(d1))
                        if d0d1 < 0.0:
                            # closest approach of the segment from d0 to d1 to the origin
                            span = d0d0 - 2.0 * d0d1 + d1
                            f = min(max((d0d0 - d0d1) / span, 0.0), 1.0) if span > 0 else 0.0
                            closest = (1 - f) * (1 - f) * d0d0 + 2 * f * (1 - f) * d0d1 + f * f * d1
                            if closest < s * s:
                                crossings += 1
    return overlap, crossings


class Monitor:
    """Running measurements of one engine's run of one scene.

    Parameters
    ----------
    scene : PeerScene
        The scene (radii, box, gravity, masses).
    expected : Expectation or None
        The closed form's checks.
    dt : float
        The engine's step [s] (sizes the kept series).
    """

    def __init__(self, scene: PeerScene, expected: Expectation | None, dt: float) -> None:
        self.scene = scene
        self.expected = expected
        self.checks = [] if expected is None else expected.checks
        self._best: list[tuple[float, FloatArray, float]] = [
            (math.inf, np.zeros(0), math.nan) for _ in self.checks
        ]
        self.energy0 = scene.energy(scene.positions, scene.velocities)
        self.steps = 0
        self.max_overlap = 0.0  # [m], pairs
        self.max_wall = 0.0  # [m], walls
        self.crossings = 0
        self.outside: set[int] = set()
        self.max_displacement = 0.0  # [m] per step, largest of any body
        self._previous: FloatArray | None = None
        self._every = max(1, math.ceil(scene.until / dt / SERIES_POINTS))
        self.series: dict[str, list[float]] = {"time": [], "energy": [], "penetration": []}

    def observe(self, time: float, positions: FloatArray, velocities: FloatArray) -> None:
        """Take the state after a step: time [s], positions and velocities (N, d)."""
        scene = self.scene
        r = scene.radius
        wall = float(np.max(np.maximum(r[:, None] - positions, positions + r[:, None] - scene.box)))
        self.max_wall = max(self.max_wall, wall)
        out = np.nonzero(np.any((positions < 0.0) | (positions > scene.box), axis=1))[0]
        self.outside.update(int(i) for i in out)
        overlap = -math.inf
        previous = positions if self._previous is None else self._previous
        step = float(np.max(np.linalg.norm(positions - previous, axis=1)))
        self.max_displacement = max(self.max_displacement, step)
        if scene.n > 1:
            size = 2.0 * float(r.max()) + 2.0 * step
            overlap, crossings = pair_check(previous, positions, r, scene.box, size)
            self.crossings += crossings
            self.max_overlap = max(self.max_overlap, overlap)
        self._previous = positions.copy()
        energy = scene.energy(positions, velocities)
        for k, check in enumerate(self.checks):
            if abs(time - check.time) < self._best[k][0]:
                # free flight from the sample to the check time: v(t) = v + g (t - t_s)
                moved = velocities + scene.gravity * (check.time - time)
                self._best[k] = (abs(time - check.time), moved, energy)
        if self.steps % self._every == 0:
            self.series["time"].append(time)
            self.series["energy"].append(energy)
            self.series["penetration"].append(max(0.0, overlap, wall))
        self.steps += 1

    def result(self) -> dict[str, Any]:
        """The measurements, as JSON-ready numbers (see docs/compare.md for each)."""
        scale = self.expected.speed if self.expected is not None else 1.0
        velocity_error = None
        worst_energy: float | None = None
        final_energy: float | None = None
        for check, (_, v, energy) in zip(self.checks, self._best, strict=True):
            if check.velocities is not None:
                err = float(np.max(np.linalg.norm(v - check.velocities, axis=1))) / scale
                velocity_error = err if velocity_error is None else max(velocity_error, err)
            drift = (energy - check.energy) / abs(self.energy0)
            if worst_energy is None or abs(drift) > abs(worst_energy):
                worst_energy = drift
            final_energy = drift
        smallest = float(self.scene.radius.min())
        penetration = max(self.max_overlap, self.max_wall, 0.0)
        return {
            "velocity_error": velocity_error,
            "energy_error": worst_energy,
            "energy_error_last_check": final_energy,
            "max_penetration": penetration,
            "max_penetration_per_radius": penetration / smallest,
            "max_overlap_pairs": max(self.max_overlap, 0.0),
            "max_overlap_walls": max(self.max_wall, 0.0),
            "tunnelled": bool(self.crossings or self.outside),
            "pairs_passed_through": self.crossings,
            "bodies_through_walls": len(self.outside),
            "max_step_per_radius": self.max_displacement / smallest,
            "samples": self.steps,
        }
