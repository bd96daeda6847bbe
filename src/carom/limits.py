"""The numbers carom accepts, and why: one place for every limit on an input.

float64 holds magnitudes from 2.2e-308 to 1.8e308. The engines multiply up to three inputs
together (``v . v t``, ``m v^2``, ``g^2 t^4 / 4``), so every dimensioned input is kept within
``[SMALLEST, LARGEST] = [1e-100, 1e100]`` in SI units: any product of three stays finite and
normal. Outside that range arithmetic overflows to inf or underflows to zero, and what
follows (a sphere that passes through a wall, a NaN energy, a cell grid of 1e300 cells) is
not physics; such inputs are refused with a message that names them.

A sphere must also be larger than ``RESOLUTION`` times the box: positions carry a relative
round-off of 1.1e-16, so a sphere a trillion times smaller than its box is within four
digits of that round-off and its contacts are noise.

Sizes (bodies, frames, bytes) are checked before a run starts (docs/scenes.md, Limits).
"""

from __future__ import annotations

import os
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from carom.errors import CaromError

__all__ = [
    "LARGEST",
    "MAX_BODIES",
    "MAX_FRAMES",
    "MAX_STEPS",
    "RESOLUTION",
    "SMALLEST",
    "check_body_count",
    "check_magnitude",
    "check_size",
    "memory_bytes",
]

#: the largest magnitude of any dimensioned input (length, speed, mass, time, ...) [SI]
LARGEST = 1e100
#: the smallest positive size (radius, mass, box side, spacing, time step) [SI]
SMALLEST = 1e-100
#: the smallest sphere radius, relative to the largest side of the box
RESOLUTION = 1e-12
#: bodies in one scene or world: the engines index bodies with 32-bit integers, and at about
#: 1 kB of engine state per body 1e8 bodies already need 100 GB
MAX_BODIES = 100_000_000
#: frames in one trajectory (each at least a few hundred bytes, with its energies)
MAX_FRAMES = 10_000_000
#: steps of a time-stepped engine in one run (a billion: days of computing for a small world)
MAX_STEPS = 1_000_000_000
#: memory one body needs, an upper estimate: the event-driven engine's state measured 480 to
#: 820 B per body (2D at packing 0.5, 3D at 0.3 and 0.01), the body table about 200 B, and
#: building it briefly holds copies
BYTES_PER_BODY = 2048


def memory_bytes() -> int | None:
    """This machine's physical memory [bytes], or None where the system does not say."""
    try:
        return int(os.sysconf("SC_PHYS_PAGES")) * int(os.sysconf("SC_PAGE_SIZE"))
    except (AttributeError, OSError, ValueError):
        return None


def check_body_count(n: int, what: str = "the scene") -> None:
    """Refuse ``n`` bodies if they are more than :data:`MAX_BODIES` or cannot fit in memory
    (at :data:`BYTES_PER_BODY` each), before anything is allocated for them.

    Parameters
    ----------
    n : int
        Number of bodies.
    what : str
        What places them, for the message.
    """
    if n > MAX_BODIES:
        raise CaromError(
            f"{what} places {n:,} bodies, more than the {MAX_BODIES:,} carom takes "
            f"(docs/scenes.md, Limits); use fewer"
        )
    need, have = n * BYTES_PER_BODY, memory_bytes()
    if have is not None and need > have:
        raise CaromError(
            f"{what} places {n:,} bodies, which need about {need / 2**30:.3g} GiB of memory "
            f"({BYTES_PER_BODY} bytes each); this machine has {have / 2**30:.3g} GiB; use "
            f"at most {have // BYTES_PER_BODY:,} bodies here"
        )


def _first(bad: NDArray[np.bool_]) -> tuple[int, ...]:
    return tuple(int(i) for i in np.unravel_index(int(np.argmax(bad)), bad.shape))


def _at(name: str, arr: NDArray[Any], index: tuple[int, ...]) -> str:
    if arr.ndim == 0:
        return f"{name} = {float(arr)!r}"
    return f"{name}[{', '.join(map(str, index))}] = {float(arr[index])!r}"


def check_magnitude(name: str, value: ArrayLike, unit: str) -> NDArray[np.float64]:
    """``value`` as float64, refused unless every element is finite and at most
    :data:`LARGEST` in magnitude.

    Parameters
    ----------
    name : str
        The input's name in the message (``velocities``, ``gravity``).
    value : array_like
        Any shape.
    unit : str
        Its unit, for the message.

    Returns
    -------
    ndarray of float64
        ``value``, same shape.
    """
    arr = np.asarray(value, dtype=np.float64)
    bad = ~(np.abs(arr) <= LARGEST)  # NaN fails the comparison too
    if bad.any():
        at = _first(bad)
        what = "is not a number" if np.isnan(arr[at]) else f"exceeds {LARGEST:g} {unit}"
        raise CaromError(
            f"{_at(name, arr, at)} {what}; carom accepts magnitudes up to {LARGEST:g} in SI "
            f"units, so that products of three stay finite (docs/scenes.md, Limits)"
        )
    return arr


def check_size(name: str, value: ArrayLike, unit: str) -> NDArray[np.float64]:
    """``value`` as float64, refused unless every element lies in
    ``[SMALLEST, LARGEST]`` (a positive size: radius, mass, box side).

    Parameters
    ----------
    name : str
        The input's name in the message.
    value : array_like
        Any shape.
    unit : str
        Its unit, for the message.

    Returns
    -------
    ndarray of float64
        ``value``, same shape.
    """
    arr = np.asarray(value, dtype=np.float64)
    bad = ~((arr >= SMALLEST) & (arr <= LARGEST))
    if bad.any():
        at = _first(bad)
        x = arr[at]
        if np.isnan(x):
            why = "is not a number"
        elif x <= 0:
            why = f"must be positive [{unit}]"
        elif x < SMALLEST:
            why = f"is below {SMALLEST:g} {unit}, where float64 arithmetic underflows"
        else:
            why = f"exceeds {LARGEST:g} {unit}, where float64 arithmetic overflows"
        raise CaromError(
            f"{_at(name, arr, at)} {why}; carom accepts sizes from {SMALLEST:g} to "
            f"{LARGEST:g} in SI units (docs/scenes.md, Limits)"
        )
    return arr
