"""An obvious O(N^2) event-driven loop in pure NumPy: the oracle for the fast engine.

Every step computes the time of impact of every pair and every body with every wall, from a
state in which all bodies share one clock; takes the earliest; moves every body to it; and
applies :func:`carom.collide` (pairs) or Newton's law against the wall. No neighbour lists,
no lazy clocks, no heap: nothing that could hide a mistake in the fast engine. Covers moving
smooth spheres in a box with walls or periodic boundaries, with gravity, the TC model and
bodies coming to rest on a wall (not static bodies, planes or rough laws). Use it for a few
hundred events of a few dozen bodies.
"""

from __future__ import annotations

import itertools
import math
from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from carom.laws.spheres import collide

__all__ = ["ReferenceEvent", "reference_events"]


@dataclass(frozen=True)
class ReferenceEvent:
    """One collision: time [s] and the bodies (``b < 0``: wall face ``-1 - b``)."""

    time: float
    a: int
    b: int


def _pair_toi(r: NDArray[np.float64], v: NDArray[np.float64], reach: float) -> float:
    # PHYSICS.md section 4: b = r.v, a = v.v, c = r.r - R^2, t = c / (-b + sqrt(b^2 - a c))
    b = float(r @ v)
    c = float(r @ r) - reach * reach
    if b >= 0.0:
        return math.inf
    if c <= 0.0:
        return 0.0
    disc = b * b - float(v @ v) * c
    return math.inf if disc < 0.0 else c / (-b + math.sqrt(disc))


def _pair_toi_accelerated(
    r: NDArray[np.float64], v: NDArray[np.float64], da: NDArray[np.float64], reach: float
) -> float:
    # |r + v t + da t^2/2|^2 = R^2, a quartic: numpy.roots, then the first real root > 0 at
    # which the distance is falling (or now, if touching and approaching)
    c0 = float(r @ r) - reach * reach
    c1 = 2.0 * float(r @ v)
    if c0 <= 0.0:
        return 0.0 if c1 < 0.0 else math.inf
    coeffs = [0.25 * float(da @ da), float(v @ da), float(v @ v) + float(r @ da), c1, c0]
    roots = np.roots(coeffs)
    real = sorted(z.real for z in roots if abs(z.imag) <= 1e-9 * max(1.0, abs(z)) and z.real > 0)
    return real[0] if real else math.inf


def _gap_toi(d0: float, u: float, acc: float) -> float:
    # first t > 0 with d0 + u t + acc t^2/2 = 0 while closing, by the quadratic formula
    if d0 <= 0.0:
        if u < 0.0 or (u == 0.0 and acc < 0.0):
            return 0.0
        if u == 0.0 or acc >= 0.0:
            return math.inf
    if acc == 0.0:
        return -d0 / u if u < 0.0 else math.inf
    disc = u * u - 2.0 * acc * d0
    if disc < 0.0:
        return math.inf
    roots = sorted([(-u - math.sqrt(disc)) / acc, (-u + math.sqrt(disc)) / acc])
    if d0 <= 0.0:
        return roots[1] if roots[1] > 0.0 else math.inf
    positive = [t for t in roots if t > 0.0]
    return positive[0] if positive else math.inf


def reference_events(
    x: NDArray[np.float64],
    v: NDArray[np.float64],
    radius: NDArray[np.float64],
    mass: NDArray[np.float64],
    box: NDArray[np.float64],
    *,
    periodic: bool = False,
    gravity: NDArray[np.float64] | None = None,
    e: float = 1.0,
    wall_e: float = 1.0,
    t_c: float = 0.0,
    n_events: int = 100,
    resting: NDArray[np.int64] | None = None,
) -> list[ReferenceEvent]:
    """The first ``n_events`` collisions of moving smooth spheres, computed the slow way.

    Parameters
    ----------
    x, v : (N, d) array_like
        Positions [m] and velocities [m/s] at time 0.
    radius, mass : (N,) array_like
        [m], [kg].
    box : (d,) array_like
        Box sides [m].
    periodic, gravity, e, wall_e, t_c
        As for :class:`carom.World` (one restitution for all pairs, one for all walls).
    n_events : int
        How many collisions to compute.
    resting : (N,) array_like of int, optional
        Wall face each body rests on at the start (-1: none), as :class:`carom.World` keeps it.
    """
    x = np.array(x, dtype=float)
    v = np.array(v, dtype=float)
    n, dim = x.shape
    g = np.zeros(dim) if gravity is None else np.asarray(gravity, dtype=float)
    last = np.full(n, -np.inf)
    support = np.full(n, -1) if resting is None else np.array(resting)
    time = 0.0

    def accel(i: int) -> NDArray[np.float64]:
        a = g.copy()
        if support[i] >= 0:
            a[support[i] // 2] = 0.0  # the wall bears the normal part of gravity
        return a

    events: list[ReferenceEvent] = []
    # periodic: every neighbouring image of a pair is tried, and a step never exceeds the
    # time in which a pair could close half a box, so no image can be skipped
    shifts = [np.array(s) * box for s in itertools.product((-1, 0, 1), repeat=dim)]
    if not periodic:
        shifts = [np.zeros(dim)]
    while len(events) < n_events:
        best, a, b = math.inf, -1, -1
        if periodic:
            speed = float(np.max(np.sqrt(np.sum(v * v, axis=1))))
            room = 0.5 * float(np.min(box)) - 2.0 * float(np.max(radius))
            best = room / (2.0 * speed) if speed > 0 else math.inf
        for i in range(n):
            for j in range(i + 1, n):
                r0 = x[i] - x[j]
                if periodic:
                    r0 = r0 - box * np.floor(r0 / box + 0.5)
                da = accel(i) - accel(j)
                for shift in shifts:
                    if np.any(da != 0.0):
                        t = _pair_toi_accelerated(
                            r0 + shift, v[i] - v[j], da, radius[i] + radius[j]
                        )
                    else:
                        t = _pair_toi(r0 + shift, v[i] - v[j], radius[i] + radius[j])
                    if t < best:
                        best, a, b = t, i, j
            if not periodic:
                gi = accel(i)
                for k in range(dim):
                    for face, d0, u, acc in (
                        (2 * k, x[i, k] - radius[i], v[i, k], gi[k]),
                        (2 * k + 1, box[k] - x[i, k] - radius[i], -v[i, k], -gi[k]),
                    ):
                        if face == support[i]:
                            continue
                        t = _gap_toi(d0, u, acc)
                        if t < best:
                            best, a, b = t, i, -1 - face
        if not math.isfinite(best):
            break
        acc_all = np.array([accel(i) for i in range(n)])
        x += (v + 0.5 * acc_all * best) * best
        v += acc_all * best
        time += best
        if a < 0:
            continue  # a periodic step with no event: look again from here
        if b >= 0:
            pair_e = 1.0 if time - last[a] < t_c or time - last[b] < t_c else e
            r = x[a] - x[b]
            if periodic:
                r = r - box * np.floor(r / box + 0.5)
            out = collide(r, v[a], mass[a], np.zeros(dim), v[b], mass[b], e=pair_e)
            v[a], v[b] = out.v1, out.v2
            last[a] = last[b] = time
            for body in (a, b):  # a resting body pushed into its wall bounces off it
                face = support[body]
                if face >= 0:
                    k, sign = face // 2, (1.0 if face % 2 == 0 else -1.0)
                    un = sign * v[body, k]
                    if un < 0.0:
                        v[body, k] = -wall_e * v[body, k]
                    if un != 0.0:
                        support[body] = -1
        else:
            face = -1 - b
            k, sign = face // 2, (1.0 if face % 2 == 0 else -1.0)
            tc = time - last[a] < t_c
            g_n = sign * g[k]
            this_e = 1.0 if tc and g_n >= 0.0 else wall_e
            u_out = this_e * abs(v[a, k])
            if g_n < 0.0 and (tc or 2.0 * u_out < -g_n * t_c):
                v[a, k] = 0.0  # comes to rest on the wall
                support[a] = face
            else:
                v[a, k] = -this_e * v[a, k]
            last[a] = time
        events.append(ReferenceEvent(time, a, b))
    return events
