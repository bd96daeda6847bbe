"""The rigid-body engine's settings: what a user may choose, checked, with its defaults.

The defaults are Box2D v3's, which its authors tuned on the benchmark scenes carom also runs
(``b2DefaultWorldDef``): 60 Hz, 4 substeps, contacts as 30 Hz springs with damping ratio 10
(twice as stiff against static bodies), pushed apart at 3 m/s at most, a linear slop of
5 mm, restitution above 1 m/s, sleep after 0.5 s below 5 cm/s.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from carom.errors import CaromError

__all__ = ["RigidSettings"]


@dataclass(frozen=True)
class RigidSettings:
    """Settings of the time-stepped rigid-body engine (docs/rigid.md).

    Parameters
    ----------
    rate : float, default 60
        Steps per second [Hz]; the step is ``1/rate`` [s].
    substeps : int, default 4
        Solver substeps per step (Box2D v3's soft step).
    contact_hertz : float, default 30
        Stiffness of a contact as a spring frequency [Hz]; capped at a quarter of the
        substep rate (a stiffer spring than the substep can follow would ring).
    damping_ratio : float, default 10
        Damping of the contact spring [-] (over-damped: no bounce from the spring itself).
    push_speed : float, default 3
        Largest speed at which overlapping bodies are pushed apart [m/s].
    restitution_threshold : float, default 1
        Normal approach speed below which the solver's restitution pass leaves a contact
        plastic [m/s] (resting contacts must not bounce). Isolated impacts, solved exactly,
        obey Newton's restitution at every speed.
    linear_slop : float, default 0.005
        Length below which contact is considered made [m]; speculative contacts reach
        ``4 linear_slop`` ahead.
    manifold_reuse : float, default 0.1
        How far two bodies in contact may move relative to each other, as a fraction of
        ``linear_slop``, before their contact manifold is made again (3D; 0.5 mm by default):
        below it the manifold is kept and only its separations are measured anew, as Rapier
        and Bullet do (:mod:`carom.engines.rigid3d.contacts`). 0 makes every manifold anew
        every step.
    exact_impacts : bool, default True
        Split a step at the time of impact of an isolated pair (found by conservative
        advancement) and apply Newton's restitution there exactly (docs/rigid.md).
    sleep : bool, default True
        Let islands of bodies at rest sleep (skipped until something touches them).
    sleep_speed : float, default 0.05
        Speed below which a body may sleep [m/s] (a spin counts by the speed it gives the
        body's farthest point).
    sleep_time : float, default 0.5
        How long an island must stay below ``sleep_speed`` to sleep [s].
    """

    rate: float = 60.0
    substeps: int = 4
    contact_hertz: float = 30.0
    damping_ratio: float = 10.0
    push_speed: float = 3.0
    restitution_threshold: float = 1.0
    linear_slop: float = 0.005
    manifold_reuse: float = 0.1
    exact_impacts: bool = True
    sleep: bool = True
    sleep_speed: float = 0.05
    sleep_time: float = 0.5

    def __post_init__(self) -> None:
        for name, low, unit in (
            ("rate", 0.0, "Hz"),
            ("contact_hertz", 0.0, "Hz"),
            ("damping_ratio", 0.0, "-"),
            ("push_speed", 0.0, "m/s"),
            ("linear_slop", 0.0, "m"),
            ("sleep_time", 0.0, "s"),
        ):
            value = getattr(self, name)
            if not (_real(value) and math.isfinite(value) and value > low):
                raise CaromError(f"{name} must be a positive number [{unit}]; got {value!r}")
        for name, unit in (
            ("restitution_threshold", "m/s"),
            ("sleep_speed", "m/s"),
            ("manifold_reuse", "-"),
        ):
            value = getattr(self, name)
            if not (_real(value) and math.isfinite(value) and value >= 0.0):
                raise CaromError(f"{name} must be a number >= 0 [{unit}]; got {value!r}")
        s = self.substeps
        if isinstance(s, bool) or not isinstance(s, int | np.integer) or not 1 <= s <= 64:
            raise CaromError(f"substeps must be a whole number from 1 to 64; got {s!r}")
        for name in ("exact_impacts", "sleep"):
            if not isinstance(getattr(self, name), bool | np.bool_):
                raise CaromError(f"{name} must be true or false; got {getattr(self, name)!r}")

    @property
    def dt(self) -> float:
        """The step [s]."""
        return 1.0 / self.rate


def _real(x: object) -> bool:
    return isinstance(x, int | float | np.integer | np.floating) and not isinstance(x, bool)
