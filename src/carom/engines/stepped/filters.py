"""Collision filters: which pairs of bodies may touch (Box2D's ``b2Filter``).

Each body has a ``category`` (the bits it is), a ``mask`` (the bits it touches) and a
``group``. Two bodies of the same nonzero group always touch when it is positive and never
when it is negative (a ragdoll's limbs, a car's wheels and body); otherwise they touch when
each one's mask holds a bit of the other's category. By default a body is category 1 and
touches every category, group 0: everything touches.

Joined bodies do not touch either, unless their joint says so (Box2D's ``collideConnected``).
A filter removes the pair from the step altogether: the broad phase's pairs are filtered
before the narrow phase (so no contact, no exact impact), and the static geometry an exact
impact or a sweep looks through skips the pieces its body does not touch. The engines step
with a filter row per piece (:func:`piece_filters`): its body's, or none for a sensor's piece
(:mod:`.sensors`), so that a body may be solid in some pieces and a sensor in others.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from carom.engines.stepped.joints import joined
from carom.errors import CaromError
from carom.jit import leaf

__all__ = [
    "ALL",
    "F_CATEGORY",
    "F_GROUP",
    "F_MASK",
    "bits64",
    "collides",
    "default_filters",
    "filter_pairs",
    "piece_filters",
    "whole_number",
]

#: the columns of a filter row: category bits, mask bits, group
F_CATEGORY, F_MASK, F_GROUP = 0, 1, 2
#: every bit (as a signed 64-bit integer)
ALL = -1


def whole_number(name: str, value: object, low: int, high: int) -> int:
    """``value`` as a whole number in ``[low, high]``, or a CaromError naming it."""
    if isinstance(value, bool) or not isinstance(value, int | np.integer):
        raise CaromError(f"{name} must be a whole number; got {value!r}")
    if not low <= int(value) <= high:
        raise CaromError(f"{name} must lie in [{low}, {high}]; got {value}")
    return int(value)


def bits64(name: str, value: object) -> int:
    """Bits as a Python int, 0 to 2**64 - 1 or as a signed 64-bit integer (-2**63 to -1:
    two's complement, so -1 is every bit and ``~0b10`` all but bit 1), as a signed 64-bit
    integer; or a CaromError."""
    bits = whole_number(name, value, -(2**63), 2**64 - 1)
    return bits - 2**64 if bits >= 2**63 else bits


def default_filters(n: int) -> np.ndarray:
    """``n`` bodies' filter rows (n, 3) int64: category 1, every mask bit, group 0."""
    rows = np.zeros((n, 3), np.int64)
    rows[:, F_CATEGORY] = 1
    rows[:, F_MASK] = ALL
    return rows


def piece_filters(filters: np.ndarray, piece_body: np.ndarray, sensing: np.ndarray) -> np.ndarray:
    """The filter row (P, 3) each piece steps with: its body's of ``filters`` (N, 3), zeroed
    (no category, no mask, no group: it touches nothing and no ray sees it) where ``sensing``
    (P,) marks a sensor's piece."""
    rows: np.ndarray = filters[piece_body]
    rows[sensing] = 0
    return rows


@njit(cache=True, inline="always")
def collides(filters: np.ndarray, a: int, b: int) -> bool:
    """Whether rows ``a`` and ``b`` of ``filters`` may touch: two bodies' (N, 3), or two
    pieces' (P, 3) (:func:`piece_filters`)."""
    ga = filters[a, F_GROUP]
    if ga != 0 and ga == filters[b, F_GROUP]:
        grouped: bool = ga > 0
        return grouped
    touch: bool = (filters[a, F_MASK] & filters[b, F_CATEGORY]) != 0 and (
        filters[a, F_CATEGORY] & filters[b, F_MASK]
    ) != 0
    return touch


@leaf
def filter_pairs(
    pairs: np.ndarray, n_pairs: int, piece_body: np.ndarray, piece_filters: np.ndarray,
    joints: np.ndarray, n_bodies: int, out: np.ndarray,
) -> int:  # fmt: skip
    """The first ``n_pairs`` rows of ``pairs`` (pieces) that may touch under
    ``piece_filters`` (P, 3) (each piece's body's filter, zeroed for a sensor's pieces:
    :func:`piece_filters`), into ``out`` in order; returns how many. Bodies that a joint
    keeps apart (``joints``, sorted keys of :func:`carom.engines.stepped.joints.joined_keys`,
    of ``n_bodies``) do not touch either."""
    m = 0
    for k in range(n_pairs):
        pa, pb = pairs[k, 0], pairs[k, 1]
        a = piece_body[pa]
        b = piece_body[pb]
        if collides(piece_filters, pa, pb) and not joined(joints, a, b, n_bodies):
            out[m, 0] = pa
            out[m, 1] = pb
            m += 1
    return m
