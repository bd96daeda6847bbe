"""What both dimensions' soft step shares: contacts coloured into groups of :data:`LANES`
that share no moving body, solved lane by lane (:data:`LANE_MATH`); the soft contact's spring
(:func:`softness`, :func:`substep_softness`), bias (:func:`soft_bias`) and normal impulse
(:func:`normal_impulse`), Box2D v3's soft step; packing a group's lanes (:func:`groups_of`,
:func:`pad_lane`, :func:`pack_pair`, :func:`absent_point`); and the restitution pass's
points and impulse (:func:`bouncing`, :func:`restitution_impulse`); copying the groups back to
the contact rows (:func:`unpack`).

Each dimension's group has its own rows; these kernels are told the rows they touch."""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.stepped.rows import FLAG_EXACT, FLAG_STRUCK, I_BODY_A, I_BODY_B, I_COUNT
from carom.jit import leaf

__all__ = [
    "ABSENT_BASE",
    "COLORS",
    "LANES",
    "LANE_MATH",
    "absent_point",
    "bouncing",
    "color_groups",
    "groups_of",
    "normal_impulse",
    "pack_pair",
    "pad_lane",
    "restitution_impulse",
    "soft_bias",
    "softness",
    "substep_softness",
    "unpack",
]

#: contacts solved together in one group
LANES = 16
#: colours a body can take (the bits of one mask); a contact finding none free is solved alone
COLORS = 64

#: what the lane loops let the compiler assume: no NaN or infinity, and the sign of a zero
#: does not matter. This lets it use vector min and max; nothing is reordered or fused, so
#: every lane does the arithmetic as written.
LANE_MATH = {"nnan", "ninf", "nsz"}
#: a point that is not there: never touching, never pushed
ABSENT_BASE = 1e30


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
    of contacts with the ground share a colour. As in Box2D v3, colour 0 is kept for contacts
    between two moving bodies: one with a static or kinematic body starts at colour 1, so a
    pass solves a stack's contacts with the ground after those within it (solved first, the
    ground's made a stack of boxes sway more and gain more energy as it settled). A contact
    whose bodies have used all :data:`COLORS` colours gets a group to itself.

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
        c = 0 if inv_mass[a] > 0.0 and inv_mass[b] > 0.0 else 1
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


@njit(cache=True)
def substep_softness(
    dt: float, substeps: int, contact_hertz: float, damping_ratio: float
) -> tuple[float, tuple[float, float, float], tuple[float, float, float]]:
    """The substep ``h = dt / substeps`` [s] and the softness (:func:`softness`) of contacts
    between two moving bodies and of those with a body of infinite mass (twice as stiff), at
    ``contact_hertz`` [Hz] but no stiffer than a quarter of the substep rate."""
    h = dt / substeps
    hertz = min(contact_hertz, 0.25 / h)
    return h, softness(hertz, damping_ratio, h), softness(2.0 * hertz, damping_ratio, h)


@njit(cache=True)
def groups_of(
    ci: np.ndarray, nc: int, inv_mass: np.ndarray, flags: int, width: int
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The contacts coloured into groups (:func:`color_groups`) and room for the groups:
    ``lanes`` (G, LANES) rows, ``group`` (G, width * LANES) floats, ``pair`` (G, 2 LANES)
    bodies and ``kinematic`` (G,) flags."""
    lanes = color_groups(ci, nc, inv_mass, flags)
    groups = lanes.shape[0]
    group = np.empty((groups, width * LANES))
    pair = np.empty((groups, 2 * LANES), np.int64)
    kinematic = np.empty(groups, np.bool_)
    return lanes, group, pair, kinematic


@njit(cache=True, inline="always")
def pad_lane(
    group: np.ndarray, pair: np.ndarray, g: int, lane: int, dummy: int, group_rows: int,
    first_point: int, point_rows: int, points: int, base: int,
) -> None:  # fmt: skip
    """An empty lane of group g: both bodies the dummy, every row zero, every point absent
    (its ``base`` row, from a point's first row, :data:`ABSENT_BASE`)."""
    pair[g, lane] = dummy
    pair[g, LANES + lane] = dummy
    for r in range(group_rows):
        group[g, r * LANES + lane] = 0.0
    for p in range(points):
        group[g, (first_point + p * point_rows + base) * LANES + lane] = ABSENT_BASE


@njit(cache=True, inline="always")
def absent_point(group: np.ndarray, g: int, lane: int, q: int, point_rows: int, base: int) -> None:
    """The point whose rows start at ``q`` in a lane of group g is not there: zero rows, an
    absent base."""
    for r in range(point_rows):
        group[g, (q + r) * LANES + lane] = 0.0
    group[g, (q + base) * LANES + lane] = ABSENT_BASE


@njit(cache=True, inline="always")
def pack_pair(
    ci: np.ndarray, m: int, group: np.ndarray, pair: np.ndarray, g: int, lane: int,
    inv_mass: np.ndarray, soft_moving: tuple[float, float, float],
    soft_fixed: tuple[float, float, float], mu: float, rows: tuple[int, int, int, int, int, int],
) -> tuple[int, int]:  # fmt: skip
    """Contact row ``m``'s bodies into ``pair`` and, into its lane of group g, the rows
    ``rows`` = (friction ``mu``, bias rate, mass scale, impulse scale, A's and B's inverse
    masses): the softness of a contact with a body of infinite mass when it has one. Return
    the bodies (A, B)."""
    r_mu, r_rate, r_mscale, r_iscale, r_ima, r_imb = rows
    a = ci[m, I_BODY_A]
    b = ci[m, I_BODY_B]
    pair[g, lane] = a
    pair[g, LANES + lane] = b
    fixed = inv_mass[a] == 0.0 or inv_mass[b] == 0.0
    rate, mass_scale, impulse_scale = soft_fixed if fixed else soft_moving
    group[g, r_mu * LANES + lane] = mu
    group[g, r_rate * LANES + lane] = rate
    group[g, r_mscale * LANES + lane] = mass_scale
    group[g, r_iscale * LANES + lane] = impulse_scale
    group[g, r_ima * LANES + lane] = inv_mass[a]
    group[g, r_imb * LANES + lane] = inv_mass[b]
    return a, b


@njit(cache=True, inline="always")
def normal_impulse(
    buf: np.ndarray, lane: int, jn_row: int, mass_row: int, total_row: int, un: float,
    mass_scale: float, impulse_scale: float, bias: float,
) -> tuple[float, float]:  # fmt: skip
    """One soft normal impulse of a lane's point (Catto 2024): the new accumulated impulse,
    kept >= 0, into row ``jn_row`` and its increment added to ``total_row``, for a normal
    relative speed ``un`` [m/s] and the point's effective mass in ``mass_row``. Return the new
    impulse and the increment [N s]."""
    jn = buf[jn_row * LANES + lane]
    dj = -buf[mass_row * LANES + lane] * (mass_scale * un + bias) - impulse_scale * jn
    new = max(jn + dj, 0.0)
    dj = new - jn
    buf[jn_row * LANES + lane] = new
    buf[total_row * LANES + lane] += dj
    return new, dj


@njit(cache=True, inline="always")
def restitution_impulse(
    cf: np.ndarray, m: int, o: int, un: float, e: float, jn: int, mass: int, vrel: int,
    total: int,
) -> float:  # fmt: skip
    """The impulse [N s] that makes the point at offset ``o`` of row ``m`` leave at ``-e``
    times its approach speed (column ``vrel``) from its normal relative speed ``un`` now,
    with its accumulated impulse (column ``jn``) kept >= 0; added to the point's
    accumulated and total impulses (columns ``jn``, ``total``; ``mass``: effective mass)."""
    j = cf[m, o + jn]
    dj = -cf[m, o + mass] * (un + e * cf[m, o + vrel])
    new = max(j + dj, 0.0)
    dj = new - j
    cf[m, o + jn] = new
    cf[m, o + total] += dj
    change: float = dj
    return change


@leaf
def unpack(
    group: np.ndarray, lanes: np.ndarray, ci: np.ndarray, cf: np.ndarray,
    layout: tuple[int, int, int, int, int], columns: tuple[int, ...], rows: tuple[int, ...],
    every_point: bool,
) -> None:  # fmt: skip
    """Copy each point's rows ``rows`` of the groups (its impulses, total, masses) back to the
    columns ``columns`` of its contact row. ``layout``: a group's first point row and rows per
    point, a contact row's first point column and columns per point, and the points a row
    holds; ``every_point``: copy the absent points too (else only the row's count)."""
    first_row, point_rows, point0, point_floats, points = layout
    for g in range(lanes.shape[0]):
        for lane in range(LANES):
            m = lanes[g, lane]
            if m < 0:
                continue
            for p in range(points if every_point else ci[m, I_COUNT]):
                q = first_row + p * point_rows
                o = point0 + p * point_floats
                for k in range(len(columns)):
                    cf[m, o + columns[k]] = group[g, (q + rows[k]) * LANES + lane]


@njit(cache=True)
def bouncing(
    cf: np.ndarray, ci: np.ndarray, nc: int, threshold: float, flags: int, restitution: int,
    layout: tuple[int, int, int, int],
) -> np.ndarray:  # fmt: skip
    """The points the restitution pass bounces, in order, as rows (contact, point offset),
    (K, 2) int64: those of contacts not solved exactly, not struck before the soft step and
    not plastic (column
    ``restitution``) that approached faster than ``threshold`` [m/s] and were pushed.
    ``layout``: a row's first point column, columns per point, and a point's normal relative
    speed and total impulse columns."""
    point0, point_floats, vrel, total = layout
    count = 0
    for m in range(nc):
        count += ci[m, I_COUNT]
    todo = np.empty((count, 2), np.int64)
    k = 0
    for m in range(nc):
        if ci[m, flags] & (FLAG_EXACT | FLAG_STRUCK) or cf[m, restitution] == 0.0:
            continue
        for j in range(ci[m, I_COUNT]):
            o = point0 + point_floats * j
            if cf[m, o + vrel] > -threshold or cf[m, o + total] == 0.0:
                continue
            todo[k, 0] = m
            todo[k, 1] = o
            k += 1
    return todo[:k]
