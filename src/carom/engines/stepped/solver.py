"""What both dimensions' soft step shares: contacts coloured into groups of :data:`LANES`
that share no moving body, solved lane by lane (:data:`LANE_MATH`), and the soft contact's
spring (:func:`softness`) and bias (:func:`soft_bias`), Box2D v3's soft step."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.stepped.rows import FLAG_EXACT, I_BODY_A, I_BODY_B

__all__ = ["COLORS", "LANES", "LANE_MATH", "color_groups", "soft_bias", "softness"]

#: contacts solved together in one group
LANES = 16
#: colours a body can take (the bits of one mask); a contact finding none free is solved alone
COLORS = 64

#: what the lane loops let the compiler assume: no NaN or infinity, and the sign of a zero
#: does not matter. This lets it use vector min and max; nothing is reordered or fused, so
#: every lane does the arithmetic as written.
LANE_MATH = {"nnan", "ninf", "nsz"}


@njit(cache=True)
def softness(hertz: float, zeta: float, h: float) -> tuple[float, float, float]:
    """Bias rate [1/s], mass scale and impulse scale [-] of a soft contact over substep h."""
    omega = 2.0 * math.pi * hertz
    a1 = 2.0 * zeta + h * omega
    a2 = h * omega * a1
    a3 = 1.0 / (1.0 + a2)
    return omega / a1, a2 * a3, a3


@njit(cache=True, inline="always")
def soft_bias(
    s: float, use_bias: bool, inv_h: float, push_speed: float, rate: float, mass_scale: float,
    impulse_scale: float,
) -> tuple[float, float, float]:  # fmt: skip
    """The mass scale, impulse scale [-] and bias [m/s] of a contact point at separation ``s``
    [m] in a pass (both engines' lanes): a point apart is speculative and may close the gap
    in the substep, no more (rigid, bias ``s / h``); one that overlaps is the soft spring
    (``rate``, ``mass_scale``, ``impulse_scale`` from :func:`softness`) pushing out at
    ``push_speed`` [m/s] at most in a pass ``use_bias``, and rigid in a relax pass."""
    spec = s > 0.0  # speculative: close the gap, no more
    soft = use_bias and not spec
    scale_m = mass_scale if soft else 1.0
    scale_i = impulse_scale if soft else 0.0
    if spec:
        bias = s * inv_h
    elif use_bias:
        bias = max(scale_m * rate * s, -push_speed)
    else:
        bias = 0.0
    return scale_m, scale_i, bias


@njit(cache=True)
def color_groups(ci: np.ndarray, nc: int, inv_mass: np.ndarray, flags: int) -> np.ndarray:
    """The contacts in groups of :data:`LANES`, no two of a group sharing a body that moves.

    Greedy colouring in row order: a contact takes the lowest colour that neither of its
    bodies has used; a body of zero inverse mass (static, kinematic) takes none, so any number
    of contacts with the ground share a colour. A contact whose bodies have used all
    :data:`COLORS` colours gets a group to itself.

    Parameters
    ----------
    ci : (M, CONTACT_INTS) int64
        Contact rows (the declared columns of :mod:`.rows`); rows flagged exact are left
        out.
    nc : int
        Rows in use.
    inv_mass : (N,) float64
        Inverse masses [1/kg].
    flags : int
        The column of the rows' flags (:func:`.rows.flags_column`).

    Returns
    -------
    (G, LANES) int64
        Contact rows, group by group: the colours in order, each cut into groups in row
        order, then the contacts that found no colour one per group; -1 in a padding lane.
    """
    one = np.uint64(1)
    used = np.zeros(inv_mass.shape[0], np.uint64)
    color = np.full(nc, -1, np.int64)
    counts = np.zeros(COLORS + 1, np.int64)
    for m in range(nc):
        if ci[m, flags] & FLAG_EXACT:
            continue
        a = ci[m, I_BODY_A]
        b = ci[m, I_BODY_B]
        taken = np.uint64(0)
        if inv_mass[a] > 0.0:
            taken |= used[a]
        if inv_mass[b] > 0.0:
            taken |= used[b]
        c = 0
        while c < COLORS and (taken >> np.uint64(c)) & one:
            c += 1
        color[m] = c
        counts[c] += 1
        if c < COLORS:
            bit = one << np.uint64(c)
            if inv_mass[a] > 0.0:
                used[a] |= bit
            if inv_mass[b] > 0.0:
                used[b] |= bit
    first = np.zeros(COLORS + 2, np.int64)  # each colour's first group
    for c in range(COLORS):
        first[c + 1] = first[c] + (counts[c] + LANES - 1) // LANES
    first[COLORS + 1] = first[COLORS] + counts[COLORS]
    lanes = np.full((first[COLORS + 1], LANES), -1, np.int64)
    filled = np.zeros(COLORS + 1, np.int64)
    for m in range(nc):
        c = color[m]
        if c < 0:
            continue
        k = filled[c]
        filled[c] += 1
        if c < COLORS:
            lanes[first[c] + k // LANES, k % LANES] = m
        else:
            lanes[first[c] + k, 0] = m
    return lanes
