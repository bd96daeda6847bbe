"""Closed-form answers a comparison holds every engine to.

Three kinds of scene have one, recognised from their content, not their name:

* **two spheres, no gravity** (the seven cases): free flight to contact, then the smooth
  impulse law in rational arithmetic (:func:`carom.reference.exact.smooth_exact`);
* **bodies on one line, no gravity** (Newton's cradle): sequential collisions in rational
  arithmetic, ``v1' = v1 - (1 + e) m2 / (m1 + m2) (v1 - v2)`` and its mirror;
* **one body dropped along gravity onto a wall** (the bouncing ball): impact speed
  ``V1 = sqrt(w0^2 + 2 g z0)``, rebound speeds ``e^k V1``, flights of ``2 e^k V1 / g``.

Each gives velocity checks at instants in free flight, and the total energy there. Any other
elastic scene still has one exact answer: its energy is conserved.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from fractions import Fraction

import numpy as np
from numpy.typing import NDArray

from carom.compare.spec import PeerScene
from carom.reference.exact import smooth_exact

__all__ = ["Check", "Expectation", "expectation"]

FloatArray = NDArray[np.float64]


@dataclass(frozen=True)
class Check:
    """The exact state at one instant of free flight.

    Attributes
    ----------
    time : float
        [s].
    velocities : (N, d) float64 or None
        Exact velocities [m/s], None when only the energy is known.
    energy : float
        Exact kinetic plus potential energy [J] (potential ``-m g . x``).
    """

    time: float
    velocities: FloatArray | None
    energy: float


@dataclass(frozen=True)
class Expectation:
    """What the closed form says about a scene.

    Attributes
    ----------
    source : str
        Which closed form, in words.
    checks : list of Check
        Instants at which the answer is known, in time order.
    speed : float
        Speed scale for relative velocity errors [m/s] (approach or impact speed).
    """

    source: str
    checks: list[Check]
    speed: float


def expectation(scene: PeerScene) -> Expectation | None:
    """The closed form for ``scene``, or None when there is none (not even energy)."""
    still = not np.any(scene.gravity)
    if still and scene.n == 2:
        return _two_spheres(scene)
    if still and _collinear(scene) is not None:
        return _line(scene)
    if not still and scene.n == 1:
        found = _bouncing(scene)
        if found is not None:
            return found
    if scene.elastic:
        e0 = scene.energy(scene.positions, scene.velocities)
        speed = float(np.max(np.linalg.norm(scene.velocities, axis=1), initial=0.0))
        return Expectation(
            "energy conservation (every restitution is 1)",
            [Check(scene.until, None, e0)],
            speed or 1.0,
        )
    return None


def _first_wall_time(scene: PeerScene, x: FloatArray, v: FloatArray) -> float:
    """When the first body, flying straight from ``x`` with ``v``, touches a wall [s]."""
    r = scene.radius[:, None]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(v > 0, (scene.box - r - x) / v, np.where(v < 0, (r - x) / v, math.inf))
    return float(np.min(t, initial=math.inf))


def _check_after(scene: PeerScene, start: float, end: float) -> float:
    """The middle of the free flight from ``start`` to ``end`` (or ``until``)."""
    return 0.5 * (start + min(end, scene.until))


def _two_spheres(scene: PeerScene) -> Expectation | None:
    x, v, m, r = scene.positions, scene.velocities, scene.mass, scene.radius
    d0, u = x[1] - x[0], v[1] - v[0]
    s = float(r[0] + r[1])
    a, b, c = float(u @ u), float(2.0 * d0 @ u), float(d0 @ d0) - s * s
    disc = b * b - 4.0 * a * c
    speed = math.sqrt(a)
    e0 = scene.energy(x, v)
    if a == 0.0 or b >= 0.0 or disc < 0.0:
        end = _first_wall_time(scene, x, v)
        return Expectation(
            "two spheres that never meet: free flight",
            [Check(_check_after(scene, 0.0, end), v.copy(), e0)],
            speed or 1.0,
        )
    t_hit = (2.0 * c) / (-b + math.sqrt(disc))  # the smaller root, without cancellation
    if _first_wall_time(scene, x, v) < t_hit or t_hit > scene.until:
        return None
    x_hit = x + v * t_hit
    e = float(scene.pair_restitution[0, 1])
    v1, v2, lost = smooth_exact(x_hit[0], v[0], m[0], x_hit[1], v[1], m[1], e)
    after = np.array([v1, v2])
    end = _first_wall_time(scene, x_hit, after) + t_hit
    return Expectation(
        "two smooth spheres: impact at the contact instant, impulse law in rational "
        "arithmetic (PHYSICS.md section 1)",
        [Check(_check_after(scene, t_hit, end), after, e0 - lost)],
        speed,
    )


def _collinear(scene: PeerScene) -> FloatArray | None:
    """The unit direction of the line every centre lies on and every velocity runs along,
    or None."""
    v = scene.velocities
    moving = np.linalg.norm(v, axis=1) > 0.0
    if not moving.any():
        return None
    line = v[int(np.argmax(moving))]
    line = line / np.linalg.norm(line)
    across = (scene.positions - scene.positions[0]) - np.outer(
        (scene.positions - scene.positions[0]) @ line, line
    )
    sideways = v - np.outer(v @ line, line)
    if np.all(across == 0.0) and np.all(sideways == 0.0):
        return np.asarray(line, dtype=np.float64)
    return None


def _line(scene: PeerScene) -> Expectation | None:
    """Sequential collisions along one line, in exact rational arithmetic."""
    line = _collinear(scene)
    assert line is not None
    s0 = scene.positions @ line
    base = scene.positions[0] - s0[0] * line  # the line's point nearest the origin
    order = np.argsort(s0, kind="stable")
    rank = np.argsort(order)  # scene body i is the rank[i]-th along the line
    pos = [Fraction(float(s0[i])) for i in order]
    vel = [Fraction(float(scene.velocities[i] @ line)) for i in order]
    mass = [Fraction(float(scene.mass[i])) for i in order]
    rad = [Fraction(float(scene.radius[i])) for i in order]
    e_pair = [
        Fraction(float(scene.pair_restitution[order[k], order[k + 1]]))
        for k in range(len(order) - 1)
    ]
    now, lost = Fraction(0), Fraction(0)  # time of the last collision [s], energy lost [J]
    for _ in range(100 * scene.n + 100):
        # the next collision of neighbours k, k + 1 (1D order never changes)
        best: tuple[Fraction, int] | None = None
        for k in range(len(pos) - 1):
            closing = vel[k] - vel[k + 1]
            if closing > 0:
                gap = pos[k + 1] - pos[k] - rad[k] - rad[k + 1]
                t = now + max(gap, Fraction(0)) / closing
                if best is None or t < best[0]:
                    best = (t, k)
        x_now = base + np.outer([float(p) for p in pos], line)[rank]
        v_now = np.outer([float(w) for w in vel], line)[rank]
        wall = float(now) + _first_wall_time(scene, x_now, v_now)
        if best is None or float(best[0]) >= min(wall, scene.until):
            # free flight from the last collision to the next event (or the end)
            end = wall if best is None else min(wall, float(best[0]))
            energy = scene.energy(scene.positions, scene.velocities) - float(lost)
            return Expectation(
                "bodies on one line: sequential collisions, 1D impulse law in rational arithmetic",
                [Check(_check_after(scene, float(now), end), v_now, energy)],
                float(max(abs(w) for w in vel)) or 1.0,
            )
        t, k = best
        pos = [p + w * (t - now) for p, w in zip(pos, vel, strict=True)]
        now = t
        m1, m2, w1, w2, e = mass[k], mass[k + 1], vel[k], vel[k + 1], e_pair[k]
        mu = m1 * m2 / (m1 + m2)
        lost += mu * (1 - e * e) * (w1 - w2) ** 2 / 2
        vel[k] = w1 - (1 + e) * m2 / (m1 + m2) * (w1 - w2)
        vel[k + 1] = w2 + (1 + e) * m1 / (m1 + m2) * (w1 - w2)
    return None


def _bouncing(scene: PeerScene) -> Expectation | None:
    """One body dropped (or thrown) along gravity onto the wall gravity points at."""
    g_vec = scene.gravity
    axis = int(np.argmax(np.abs(g_vec)))
    sideways = scene.velocities[0][np.arange(scene.dim) != axis]
    if np.count_nonzero(g_vec) != 1 or np.count_nonzero(sideways):
        return None
    g = abs(float(g_vec[axis]))
    down = g_vec[axis] < 0
    r = float(scene.radius[0])
    y = float(scene.positions[0, axis])
    z0 = (y - r) if down else (scene.box[axis] - r - y)  # height above the floor surface
    w0 = float(scene.velocities[0, axis]) * (1.0 if down else -1.0)  # upward speed
    e = float(scene.wall_restitution[0, 2 * axis + (0 if down else 1)])
    v1 = math.sqrt(w0 * w0 + 2.0 * g * z0)
    t = (w0 + v1) / g  # first impact
    ceiling = float(scene.box[axis]) - 2.0 * r
    if max(z0, v1 * v1 / (2.0 * g)) >= ceiling:
        return None  # it would reach the opposite wall
    m = float(scene.mass[0])
    checks = []
    speed = v1
    for _ in range(3):  # the first three bounces
        speed *= e
        apex = t + speed / g
        if apex >= scene.until or speed == 0.0:
            break
        height = speed * speed / (2.0 * g)
        top = r + height if down else float(scene.box[axis]) - r - height
        checks.append(Check(apex, np.zeros((1, scene.dim)), -m * float(g_vec[axis]) * top))
        t += 2.0 * speed / g
    if not checks:
        return None
    return Expectation(
        f"a ball dropped on a wall of restitution {e:g}: rebound speeds e^k V1, apex heights "
        f"e^(2k) V1^2 / (2 g)",
        checks,
        v1,
    )
