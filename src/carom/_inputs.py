"""Input checking and broadcasting shared by the two-body laws.

Every public law accepts a single pair (vectors of shape ``(d,)``, scalars) or a batch
(vectors ``(n, d)``, scalars ``(n,)`` or scalar). :class:`PairInputs` turns the arguments into
float64 arrays of one common batch length ``n`` (a single pair is ``n = 1``) and remembers
whether the caller gave a single pair, so results can be returned in the caller's shape.
Each check names the argument, the offending value (and its index in a batch) and the fix.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from carom.errors import CaromError
from carom.limits import check_magnitude, check_size

FloatArray = NDArray[np.float64]


def _where(name: str, arr: NDArray[Any], bad: NDArray[np.bool_], item_ndim: int) -> str:
    """Describe the first offending item as ``name = value`` or, in a batch, ``name[i] = value``.

    ``item_ndim`` is the number of dimensions of one item: 1 for a vector, 0 for a scalar.
    """
    if arr.ndim == item_ndim:
        shown = str(arr.tolist()) if item_ndim else repr(arr.item())
        return f"{name} = {shown}"
    rows = bad.reshape(arr.shape[0], -1).any(axis=1)
    row = int(np.argmax(rows))
    value = arr[row]
    shown = str(value.tolist()) if item_ndim else repr(float(value))
    return f"{name}[{row}] = {shown}"


def _check_finite(name: str, arr: FloatArray, item_ndim: int, unit: str) -> None:
    """Refuse non-finite or overflowing items of a vector or spin argument, by name."""
    bad = ~np.isfinite(arr)
    if bad.any():
        raise CaromError(f"{name} must be finite [{unit}]; got {_where(name, arr, bad, item_ndim)}")
    check_magnitude(name, arr, unit)


def as_float_array(name: str, value: ArrayLike) -> FloatArray:
    """Convert to a float64 array, refusing anything that is not numeric."""
    try:
        arr = np.asarray(value, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise CaromError(f"{name} must be numeric; got {value!r} ({exc})") from None
    return arr


@dataclass
class PairInputs:
    """Collects the arguments of one call, checks them and broadcasts them to a batch.

    Use :meth:`vector`, :meth:`scalar` to register arguments, then :meth:`broadcast`.
    Shapes are checked as each argument is registered. Values are checked then too, unless
    ``defer_values`` is set: a caller that checks values in its own pass (a Numba kernel) runs
    :meth:`check_values` only when that pass finds a bad pair, to name it.
    """

    dim: int | None = None
    single: bool = True
    defer_values: bool = False
    _vectors: dict[str, FloatArray] = field(default_factory=dict)
    _scalars: dict[str, FloatArray] = field(default_factory=dict)
    _spins: dict[str, FloatArray] = field(default_factory=dict)
    _value_checks: list[Callable[[], None]] = field(default_factory=list)

    def _values(self, check: Callable[[], None]) -> None:
        if self.defer_values:
            self._value_checks.append(check)
        else:
            check()

    def check_values(self) -> None:
        """Run the value checks deferred so far, in the order the arguments were registered."""
        for check in self._value_checks:
            check()

    def vector(self, name: str, value: ArrayLike, *, unit: str) -> None:
        """Register a position or velocity: shape (d,) or (n, d), d in {2, 3}, finite."""
        arr = as_float_array(name, value)
        if arr.ndim not in (1, 2):
            raise CaromError(
                f"{name} must have shape (d,) for one pair or (n, d) for a batch, d = 2 or 3; "
                f"got shape {arr.shape}"
            )
        d = arr.shape[-1]
        if d not in (2, 3):
            raise CaromError(
                f"{name} has {d} components; carom works in 2 or 3 dimensions: give vectors of "
                f"shape (2,) or (3,) (or (n, 2), (n, 3) for a batch)"
            )
        if self.dim is None:
            self.dim = d
        elif d != self.dim:
            first = next(iter(self._vectors))
            raise CaromError(
                f"{name} is {d}-dimensional but {first} is {self.dim}-dimensional; "
                f"give every vector the same number of components"
            )
        self._values(lambda: _check_finite(name, arr, 1, unit))
        if arr.ndim == 2:
            self.single = False
        self._vectors[name] = arr

    def spin(self, name: str, value: ArrayLike) -> None:
        """Register an angular velocity [rad/s]: a scalar per body in 2D, a 3-vector in 3D."""
        if self.dim is None:
            raise RuntimeError("register the vectors before the spins")
        arr = as_float_array(name, value)
        per_body_ndim = 0 if self.dim == 2 else 1
        if arr.ndim not in (per_body_ndim, per_body_ndim + 1) or (
            self.dim == 3 and arr.shape[-1] != 3
        ):
            want = "a scalar (or shape (n,))" if self.dim == 2 else "shape (3,) (or (n, 3))"
            raise CaromError(
                f"{name} is the spin [rad/s] and in {self.dim}D must be {want}; "
                f"got shape {arr.shape}"
            )
        self._values(lambda: _check_finite(name, arr, per_body_ndim, "rad/s"))
        if arr.ndim == per_body_ndim + 1:
            self.single = False
        self._spins[name] = arr

    def scalar(
        self,
        name: str,
        value: ArrayLike,
        *,
        low: float,
        high: float,
        unit: str,
        low_open: bool = False,
        allow_inf: bool = False,
        hint: str = "",
    ) -> None:
        """Register a per-pair scalar in [low, high] (or (low, high] if ``low_open``)."""
        arr = as_float_array(name, value)
        if arr.ndim > 1:
            raise CaromError(
                f"{name} must be a scalar or have shape (n,) for a batch; got shape {arr.shape}"
            )

        def check() -> None:
            ok = (arr > low) if low_open else (arr >= low)
            ok &= arr <= high
            if not allow_inf:
                ok &= np.isfinite(arr)
            bad = ~ok  # NaN fails every comparison, so it lands here too
            if bad.any():
                bracket = "(" if low_open else "["
                top = "inf" if math.isinf(high) else f"{high:g}"
                rng = f"{bracket}{low:g}, {top}]"
                extra = f" ({hint})" if hint else ""
                raise CaromError(
                    f"{name} must lie in {rng} [{unit}]{extra}; got {_where(name, arr, bad, 0)}"
                )
            finite = np.where(np.isfinite(arr), arr, 1.0)  # inf, where allowed, is not overflow
            check_magnitude(name, finite, unit)
            if low_open and low == 0.0:  # a positive size: not so small that it underflows
                check_size(name, finite, unit)

        self._values(check)
        if arr.ndim == 1:
            self.single = False
        self._scalars[name] = arr

    def length(self) -> int:
        """The common batch length ``n`` (1 for a single pair); refuse lengths that differ."""
        assert self.dim is not None
        lengths: dict[str, int] = {}
        for name, arr in self._vectors.items():
            if arr.ndim == 2:
                lengths[name] = arr.shape[0]
        for name, arr in self._spins.items():
            if arr.ndim == (1 if self.dim == 2 else 2):
                lengths[name] = arr.shape[0]
        for name, arr in self._scalars.items():
            if arr.ndim == 1:
                lengths[name] = arr.shape[0]
        sizes = set(lengths.values()) - {1}
        if len(sizes) > 1:
            listed = ", ".join(f"{k}: {v}" for k, v in lengths.items())
            raise CaromError(
                f"the batch arguments do not broadcast: their lengths differ ({listed}); "
                f"give every batched argument the same length n, or a single value"
            )
        return sizes.pop() if sizes else 1

    def rows(self, name: str) -> FloatArray:
        """A registered argument as C-contiguous rows, without broadcasting: vectors and
        spins ``(k, c)`` (a 2D spin has ``c = 1``), scalars ``(k,)``, with ``k`` 1 or ``n``."""
        if name in self._vectors:
            arr = self._vectors[name]
            return np.ascontiguousarray(arr.reshape(-1, arr.shape[-1]))
        if name in self._spins:
            arr = self._spins[name]
            return np.ascontiguousarray(arr.reshape(-1, 1 if self.dim == 2 else 3))
        return np.ascontiguousarray(self._scalars[name].reshape(-1))

    def broadcast(self) -> tuple[int, dict[str, FloatArray]]:
        """Broadcast everything to one batch length ``n``; return ``n`` and the arrays.

        Vectors come back as (n, d), spins as (n,) in 2D or (n, 3) in 3D, scalars as (n,).
        Every array is a fresh contiguous copy, so callers may modify it.
        """
        assert self.dim is not None
        n = self.length()
        out: dict[str, FloatArray] = {}
        for name, arr in self._vectors.items():
            out[name] = np.array(np.broadcast_to(arr, (n, self.dim)))
        for name, arr in self._spins.items():
            shape = (n,) if self.dim == 2 else (n, 3)
            out[name] = np.array(np.broadcast_to(arr, shape))
        for name, arr in self._scalars.items():
            out[name] = np.array(np.broadcast_to(arr, (n,)))
        return n, out


def dot(a: FloatArray, b: FloatArray) -> FloatArray:
    """Row-wise dot product of (n, d) arrays, summed in a fixed order.

    Written out component by component so that a pair gives bit-identical results
    whether it is computed alone or inside a batch.
    """
    total = a[:, 0] * b[:, 0] + a[:, 1] * b[:, 1]
    if a.shape[1] == 3:
        total = total + a[:, 2] * b[:, 2]
    return total


def cross_scalar_vector(w: FloatArray, n: FloatArray) -> FloatArray:
    """``w x n`` for spins ``w``: (n,) scalars in 2D (about z), (n, 3) vectors in 3D."""
    if n.shape[1] == 2:
        # w z x (nx, ny, 0) = w (-ny, nx)
        return np.stack((-w * n[:, 1], w * n[:, 0]), axis=1)
    return np.cross(w, n)


def cross_vector_vector(a: FloatArray, b: FloatArray) -> FloatArray:
    """``a x b`` row-wise: the z component (n,) in 2D, the (n, 3) vector in 3D."""
    if a.shape[1] == 2:
        return a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]
    return np.cross(a, b)


def inverse_mass(m: FloatArray) -> FloatArray:
    """1/m with 1/inf = 0 (a static body)."""
    with np.errstate(divide="ignore"):
        return np.where(np.isinf(m), 0.0, 1.0 / m)


def check_not_both_static(m1: FloatArray, m2: FloatArray) -> None:
    """Refuse pairs whose two masses are both infinite (no impulse can be shared)."""
    both = np.isinf(m1) & np.isinf(m2)
    if both.any():
        where = "" if both.size == 1 else f" at index {int(np.argmax(both))}"
        raise CaromError(
            f"m1 and m2 are both infinite{where}: two static bodies cannot exchange an impulse; "
            "give at least one body a finite mass"
        )


def finite_positive(name: str, value: object, unit: str, *, zero: bool = False) -> float:
    """``value`` as a float if it is finite and positive (or zero when allowed); a CaromError
    naming it, its unit and what it got otherwise (a shape's sizes, a density, a mass)."""
    ok = (
        not isinstance(value, bool)
        and isinstance(value, int | float | np.floating | np.integer)
        and math.isfinite(float(value))
        and (float(value) >= 0.0 if zero else float(value) > 0.0)
    )
    if not ok:
        what = "zero or positive" if zero else "positive"
        raise CaromError(f"{name} must be {what} and finite [{unit}]; got {value!r}")
    return float(value)  # type: ignore[arg-type]
