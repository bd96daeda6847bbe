"""Materials: how a surface responds to impacts, and how two surfaces' coefficients combine.

Bodies, walls and planes all take a :class:`Material`. A material names its impulse law
explicitly (``law``) or by the coefficients it is given: ``beta`` makes it rough (constant
tangential restitution), ``friction`` makes it Coulomb (Walton's model), neither smooth
(PHYSICS.md sections 1 and 3). Two materials in contact combine by one :data:`CombineRule`
unless the pair is given its own restitution; :func:`pair_table` makes the (M, M) tables the
engines read.

>>> steel, rubber = Material(0.9), Material(0.5, friction=0.8)
>>> rubber.law
'coulomb'
>>> table = pair_table([steel, rubber], "mean")
>>> float(table.e[0, 1]), int(table.law[0, 1]) == LAW_CODES["coulomb"]
(0.7, True)
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Literal, NamedTuple, cast, get_args

import numpy as np
from numpy.typing import NDArray

from carom.errors import CaromError
from carom.laws.kernels import LAW_ROUGH, LAW_SMOOTH, LAW_WALTON

__all__ = [
    "COMBINE_RULES",
    "LAWS",
    "LAW_CODES",
    "CombineRule",
    "Law",
    "Material",
    "PairTable",
    "combine",
    "pair_table",
]

CombineRule = Literal["mean", "min", "max", "geometric", "product"]
#: the ways two materials' coefficients combine, ``a`` and ``b`` into one
COMBINE_RULES: tuple[CombineRule, ...] = get_args(CombineRule)
Law = Literal["smooth", "rough", "coulomb"]
LAWS: tuple[Law, ...] = get_args(Law)
#: each law's code in the kernels (:mod:`carom.laws.kernels`); a pair takes the larger code
LAW_CODES: dict[Law, int] = {"smooth": LAW_SMOOTH, "rough": LAW_ROUGH, "coulomb": LAW_WALTON}


def combine(rule: CombineRule, a: float, b: float) -> float:
    """Two coefficients combined by ``rule`` [-]."""
    if rule == "mean":
        return 0.5 * (a + b)
    if rule == "min":
        return min(a, b)
    if rule == "max":
        return max(a, b)
    if rule == "geometric":
        return math.sqrt(a * b)
    if rule == "product":
        return a * b
    raise CaromError(f"combine must be one of {COMBINE_RULES}; got {rule!r}")


@dataclass(frozen=True)
class Material:
    """How a surface responds to impacts.

    Parameters
    ----------
    restitution : float
        Normal coefficient of restitution ``e`` in [0, 1] [-].
    beta : float, optional
        Constant tangential restitution in [-1, 1] [-] (law ``"rough"``; spins change).
    friction : float, optional
        Coulomb coefficient ``mu_f >= 0`` [-] (law ``"coulomb"``, Walton's model).
    beta0 : float, optional
        Walton's sticking restitution in [-1, 1] [-], default 0 (law ``"coulomb"`` only).
    law : {"smooth", "rough", "coulomb"}, optional
        The impulse law. By default it follows from the coefficients given: ``friction``
        means ``"coulomb"``, ``beta`` means ``"rough"``, neither means ``"smooth"``. Given,
        it must agree with them.
    rolling : float, default 0
        Rolling resistance [m] (the 3D rigid-body engine): rolling a body over a surface
        takes a torque of ``rolling`` times the load, so a rolling ball slows at
        ``rolling g / (R (1 + I/(m R^2)))`` on a level floor. Billiard cloth is about 1e-4 m
        for a 57 mm ball; two materials combine as the World's ``combine`` rule says.
    """

    restitution: float = 1.0
    beta: float | None = None
    friction: float | None = None
    beta0: float | None = None
    law: Law = None  # type: ignore[assignment]  # set in __post_init__
    rolling: float = 0.0

    def __post_init__(self) -> None:
        _check_range("restitution", self.restitution, 0.0, 1.0)
        if self.beta is not None and self.friction is not None:
            raise CaromError("a material takes beta (constant) or friction (Walton), not both")
        if self.beta is not None:
            _check_range("beta", self.beta, -1.0, 1.0)
        if self.friction is not None and not (
            self.friction >= 0.0 and math.isfinite(self.friction)
        ):
            raise CaromError(f"friction must be >= 0 and finite; got {self.friction!r}")
        if (
            isinstance(self.rolling, bool)
            or not isinstance(self.rolling, int | float)
            or not (self.rolling >= 0.0 and math.isfinite(self.rolling))
        ):
            raise CaromError(f"rolling must be a length >= 0 [m]; got {self.rolling!r}")
        if self.beta0 is not None:
            _check_range("beta0", self.beta0, -1.0, 1.0)
            if self.friction is None:
                raise CaromError("beta0 is Walton's sticking restitution: give friction too")
        implied: Law = (
            "coulomb"
            if self.friction is not None
            else "rough"
            if self.beta is not None
            else "smooth"
        )
        if cast("Law | None", self.law) is None:
            object.__setattr__(self, "law", implied)
        elif self.law not in LAWS:
            raise CaromError(f"law must be one of {LAWS}; got {self.law!r}")
        elif self.law != implied:
            needs = {"smooth": "neither beta nor friction", "rough": "beta", "coulomb": "friction"}
            raise CaromError(
                f"law {self.law!r} needs {needs[self.law]}; this material has "
                f"beta={self.beta!r}, friction={self.friction!r}"
            )


def _check_range(name: str, value: float, low: float, high: float) -> None:
    if isinstance(value, bool) or not isinstance(value, int | float) or not low <= value <= high:
        raise CaromError(f"{name} must lie in [{low:g}, {high:g}]; got {value!r}")


class PairTable(NamedTuple):
    """What every pair of M materials does on impact, as (M, M) arrays the kernels read.

    Attributes
    ----------
    law : (M, M) int64
        Impulse law code (:data:`LAW_CODES`): the rougher of the two materials' laws.
    e : (M, M) float64
        Normal restitution [-].
    beta : (M, M) float64
        Constant tangential restitution (law rough) or Walton's ``beta0`` (coulomb) [-].
    friction : (M, M) float64
        Coulomb coefficient [-].
    """

    law: NDArray[np.int64]
    e: NDArray[np.float64]
    beta: NDArray[np.float64]
    friction: NDArray[np.float64]


def pair_table(
    materials: Sequence[Material],
    rule: CombineRule,
    overrides: Mapping[tuple[int, int], float] | None = None,
) -> PairTable:
    """The combined coefficients of every pair of ``materials`` (one default material if none).

    ``overrides`` maps a pair of material indices to its own restitution, in place of the
    combined one (both orders should be given).
    """
    mats = list(materials) or [Material()]
    n = len(mats)
    law = np.zeros((n, n), np.int64)
    e = np.zeros((n, n))
    beta = np.full((n, n), -1.0)
    friction = np.zeros((n, n))
    overrides = overrides or {}
    for i, a in enumerate(mats):
        for j, b in enumerate(mats):
            e[i, j] = overrides.get((i, j), combine(rule, a.restitution, b.restitution))
            law[i, j] = max(LAW_CODES[a.law], LAW_CODES[b.law])
            if law[i, j] == LAW_WALTON:
                mu_a = a.friction if a.friction is not None else 0.0
                mu_b = b.friction if b.friction is not None else 0.0
                friction[i, j] = combine(rule, mu_a, mu_b)
                beta[i, j] = combine(rule, a.beta0 or 0.0, b.beta0 or 0.0)
            elif law[i, j] == LAW_ROUGH:
                beta[i, j] = combine(
                    rule,
                    a.beta if a.beta is not None else -1.0,
                    b.beta if b.beta is not None else -1.0,
                )
    return PairTable(law, e, beta, friction)
