"""What both dimensions' exact impacts share: the islands solved exactly, their impacts taken in
the order they happen, and the search for a pair's time of impact by conservative advancement
(Mirtich 1996; Erin Catto's time of impact in Box2D), written once as a step function the
dimension calls with the gap it measures.

An island solved exactly (:func:`carom.engines.stepped.islands.plan`) is a small event-driven
simulation inside the step. Its candidates are the broad-phase pairs of its bodies with each
other or with static bodies (:func:`gather`), not only the contacts that joined it. Each body
keeps its own clock within the step and is flown to a time only when a pair of it is looked at;
the earliest time of impact is taken, the impulse applied, and the two bodies' candidates
searched again. A body turned by an impact may head where its broad phase did not look (a fast
ball bounced back towards the wall behind it): when what it can reach in the rest of the step
leaves its swept box, the static pieces in the new reach are found through the static tree
(and the unbounded ones, few) and join the candidates (:func:`look_around`). What it cannot
follow exactly, a body moving otherwise in its reach (another island, the solver's, a
sleeping or kinematic body), ends the island's step at that impact, as Box2D's continuous
collision does: its bodies keep their velocities and their poses, the rest of the step is
dropped for them, and nothing is run through. So does an island that has taken
:func:`impact_cap` impacts in one step (a ball at 1e100 m/s in a box).

The search starts at ``t = 0``. At each time it is given the gap ``d`` [m] and a bound on how
fast the gap can close from then to the horizon [m/s]; while the pieces are apart it moves on
by ``d`` over that bound, which cannot pass the first touch; within ``tol`` of touching it
stops; past it (a turn the bound missed, or a start already overlapping) it bisects back
between the last safe time and this one.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.stepped.filters import collides
from carom.engines.stepped.rows import FLAG_EXACT, I_BODY_A, I_BODY_B, I_PIECE_A, I_PIECE_B
from carom.geometry.bvh import STACK, overlap, query_bvh
from carom.laws.kinds import KIND_STATIC

__all__ = [
    "BISECTIONS",
    "BOUNCED",
    "HELD",
    "MAX_IMPACTS",
    "MAX_ITERATIONS",
    "NEW",
    "PAIR_LOOKS",
    "Search",
    "add_candidate",
    "advance",
    "approaching",
    "closing_bound",
    "discriminant_root",
    "earliest",
    "gather",
    "give_back",
    "impact_cap",
    "island_candidates",
    "keep_island",
    "logged_row",
    "look_around",
    "near_keys",
    "search",
    "started_sunk",
    "statics_in",
    "take_isolated",
]

#: conservative-advancement iterations in one search; then it returns the furthest time known
#: to be safe, where the caller finds no contact and searches on from there (a search never
#: gives up with the pieces run into each other)
MAX_ITERATIONS = 200
#: gaps a search waits, still touching, for a pair left :data:`HELD` to part: one that parts
#: by a turn leaves the touching distance within them, one held in contact never does (a
#: pair :data:`BOUNCED` apart waits as long as it takes: a rod struck at one end, e = 0.5,
#: parts in steps of a billionth of its reach and needs more than 16)
PARTING_GAPS = 16
#: how a search starts: at a touch that is a new impact (``NEW``); at a touch a pair was
#: left in at zero normal speed (plastic, a slow impact, or no impact: ``HELD``), waiting
#: :data:`PARTING_GAPS` gaps for it to part; at a touch a pair was hit apart from at speed
#: (``BOUNCED``), waiting until it parts
NEW = 0
HELD = 1
BOUNCED = 2
#: halvings of an overshot interval before settling on its safe end
BISECTIONS = 60
#: impacts of an island within one step: this many per candidate pair, and
#: :data:`ISLAND_IMPACTS` more
MAX_IMPACTS = 8
ISLAND_IMPACTS = 256
#: turns one pair may take as an island's next impact in one step: more is a pair held in
#: contact (plastic, or turning against each other), a sequence of ever smaller impacts
#: without end (inelastic collapse), and the island goes back to the solver
PAIR_LOOKS = 4
#: relative round-off of a normal speed: 64 ulps of the point speeds it is computed from
ROUND_OFF = 64.0 * np.finfo(np.float64).eps

#: a search's state: the last safe time, the bisected interval (lo, hi), whether it is
#: bisecting, how many gaps it has taken in its phase, and how it waits for the pair to part
#: (:data:`NEW`, :data:`HELD` or :data:`BOUNCED`; touching is an impact only once ``NEW``)
Search = tuple[float, float, float, bool, int, int]


@njit(cache=True, inline="always")
def search(parting: int) -> Search:
    """A new search from ``t = 0``; ``parting``: :data:`NEW`, :data:`HELD` or
    :data:`BOUNCED`, how the pair was left at its last meeting."""
    return 0.0, 0.0, 0.0, False, 0, parting


@njit(cache=True, inline="always")
def advance(
    state: Search, t: float, d: float, closing: float, tol: float, horizon: float
) -> tuple[bool, float, Search]:
    """One step of the search, given the gap ``d`` [m] at time ``t`` [s] and, while
    advancing, how fast it can close from ``t`` to ``horizon`` [m/s].

    Returns ``(done, time, state)``: done, the time of impact in ``[0, horizon]`` (or, after
    :data:`MAX_ITERATIONS`, the furthest time known safe) or -1 when there is none; else the
    next time to measure the gap at.
    """
    safe, lo, hi, bisecting, taken, parting = state
    if bisecting:
        if d < -tol:
            hi = t
        elif d > tol:
            lo = t
        else:
            return True, t, state
        taken += 1
        mid = 0.5 * (lo + hi)
        if taken == BISECTIONS or not lo < mid < hi:
            # (no time left between them: the halvings left would measure lo or hi again,
            # the same gap each time, and end on lo)
            return True, lo, state
        return False, mid, (safe, lo, hi, True, taken, parting)
    if d < -tol:
        # overshot: bisect back between the last safe time and t (overlapping already at
        # the search's start, t = safe: nothing between, and the safe end is t)
        mid = 0.5 * (safe + t)
        if not safe < mid < t:
            return True, safe, state
        return False, mid, (safe, safe, t, True, 0, parting)
    if d <= tol and parting == NEW:
        return True, t, state
    if d > tol:
        parting = NEW
    elif parting == HELD and taken >= PARTING_GAPS:  # still held: the caller looks again
        return True, t, state
    if closing <= 0.0:
        return True, -1.0, state
    later = t + max(d, tol) / closing
    taken += 1
    if later > horizon:
        return True, -1.0, state
    if taken == MAX_ITERATIONS:
        return True, later, state  # (safe: the pieces cannot touch before it)
    return False, later, (t, lo, hi, False, taken, parting)


@njit(cache=True, inline="always")
def discriminant_root(b: float, q: float) -> float:
    """``sqrt(b^2 + q)``, or -1 where ``b^2 + q < 0``, without squaring ``b`` (whose square
    underflows to 0 below 1e-154 and overflows above 1e154)."""
    if q >= 0.0:
        return math.hypot(b, math.sqrt(q))
    r = math.sqrt(-q)
    if abs(b) < r:
        return -1.0
    return math.sqrt(abs(b) - r) * math.sqrt(abs(b) + r)


@njit(cache=True, inline="always")
def closing_bound(gap: float, opening: float, pull: float, spin: float) -> float:
    """How fast [m/s] a gap of ``gap`` [m] > 0 can close on average until it could first be
    closed: ``gap / s`` for the least ``s`` [s] at which it can, 0 if it never can.

    The pieces' separation along the direction ``n`` they are measured in (from B to A) at
    time ``s`` from now is at least ``gap + opening s + pull s^2 / 2 - spin s``: the centres'
    relative motion along ``n`` is exact (``opening`` [m/s], ``pull`` [m/s^2]: the relative
    velocity and acceleration along ``n``), and a point turning about its centre moves at most
    its reach times the spin (``spin`` [m/s], both bodies'). That quadratic's least root is
    ``s = 2 gap / (b + sqrt(b^2 - 2 pull gap))`` with ``b = spin - opening``: a step that
    cannot pass the first touch (Mirtich's conservative advancement with the centres' motion
    taken exactly rather than bounded by the fastest speed to the horizon).
    """
    b = spin - opening
    q = -2.0 * pull * gap
    root = discriminant_root(b, q)
    if root < 0.0:
        return 0.0  # the bound stays above the gap for ever
    if b >= 0.0:
        return 0.5 * (b + root)
    # b < 0: (b + root) / 2 without the cancellation, (root^2 - b^2) / (2 (root - b))
    return max(0.5 * q / (root - b), 0.0)


@njit(cache=True, inline="always")
def take_isolated(ci: np.ndarray, m: int, flags: int) -> tuple[int, int, int, int]:
    """Contact row ``m``'s bodies and pieces ``(a, b, pa, pb)``, flagged solved exactly
    (column ``flags``)."""
    ci[m, flags] |= FLAG_EXACT
    return ci[m, I_BODY_A], ci[m, I_BODY_B], ci[m, I_PIECE_A], ci[m, I_PIECE_B]


@njit(cache=True, inline="always")
def approaching(un: np.ndarray, used: int, scale: float) -> bool:
    """Whether any of the first ``used`` normal relative speeds ``un`` [m/s] approaches by
    more than its round-off: ``un`` is a difference of the two bodies' point velocities, whose
    sizes add up to at most ``scale`` [m/s], so it carries an error of a few ulps of
    ``scale``; a slower approach is a resting touch (an impulse for it would leave it as
    slow, and the pair would be met again at the same instant, without end)."""
    floor = ROUND_OFF * scale
    for j in range(used):  # noqa: SIM110 (a loop Numba compiles, not a generator)
        if un[j] < -floor:
            return True
    return False


@njit(cache=True, inline="always")
def impact_cap(candidates: int) -> int:
    """The impacts an island of ``candidates`` pairs may take in one step."""
    cap: int = ISLAND_IMPACTS + MAX_IMPACTS * candidates
    return cap


@njit(cache=True)
def gather(
    pairs: np.ndarray,
    n_pairs: int,
    piece_body: np.ndarray,
    kind: np.ndarray,
    island_of: np.ndarray,
    n_islands: int,
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Each island's candidate pairs and watched pairs, from the broad phase's ``pairs``
    (the first ``n_pairs``): ``(cand_first, cand, watch_first, watch)``, island k's
    candidates ``cand[cand_first[k]:cand_first[k + 1]]`` (indices into ``pairs``), in the
    pairs' order, and its watched pairs likewise.

    A candidate joins two bodies of the island, or one of it and a static body; a watched
    pair joins a body of the island to one that moves otherwise (another island, the solver's,
    a free or kinematic body): the island must not reach that body's box on a path the broad
    phase did not look at.
    """
    counts = np.zeros((2, n_islands + 1), np.int64)
    which = np.full((n_pairs, 2), -1, np.int64)  # (list, island) of each pair's entries
    for k in range(n_pairs):
        ba = piece_body[pairs[k, 0]]
        bb = piece_body[pairs[k, 1]]
        ia = island_of[ba]
        ib = island_of[bb]
        for mine, other, theirs, slot in ((ia, bb, ib, 0), (ib, ba, ia, 1)):
            if mine < 0:
                continue
            if theirs == mine or kind[other] == KIND_STATIC:
                if slot == 0 or theirs != mine:  # a pair within the island, listed once
                    which[k, slot] = mine
                    counts[0, mine + 1] += 1
            else:
                which[k, slot] = n_islands + 1 + mine  # watched
                counts[1, mine + 1] += 1
    for j in range(2):
        for k in range(n_islands):
            counts[j, k + 1] += counts[j, k]
    cand_first = counts[0].copy()
    watch_first = counts[1].copy()
    cand = np.empty(cand_first[n_islands], np.int64)
    watch = np.empty(watch_first[n_islands], np.int64)
    fill = counts[:, :n_islands].copy()
    for k in range(n_pairs):
        for slot in range(2):
            i = which[k, slot]
            if i < 0:
                continue
            if i <= n_islands:
                cand[fill[0, i]] = k
                fill[0, i] += 1
            else:
                i -= n_islands + 1
                watch[fill[1, i]] = k
                fill[1, i] += 1
    return cand_first, cand, watch_first, watch


@njit(cache=True, inline="always")
def earliest(hit: np.ndarray, lo: int, hi: int) -> int:
    """The candidate in ``[lo, hi)`` with the earliest time of impact ``hit`` (inf: none),
    the first of equals; -1 when none has one."""
    best = -1
    when = np.inf
    for c in range(lo, hi):
        if hit[c] < when:
            when = hit[c]
            best = c
    return best


@njit(cache=True, inline="always")
def _contained(inner: np.ndarray, outer: np.ndarray, p: int) -> bool:
    """Whether box ``inner`` (2 d,) lies in box ``outer[p]``, up to a millionth of a
    millionth of the outer box's size (the round-off of flying there)."""
    d = inner.shape[0] // 2
    for k in range(d):
        slack = 1e-12 * (outer[p, d + k] - outer[p, k])
        if inner[k] < outer[p, k] - slack or inner[d + k] > outer[p, d + k] + slack:
            return False
    return True


@njit(cache=True)
def logged_row(log: np.ndarray, logged: int) -> np.ndarray:
    """``log`` with room for row ``logged`` (doubled when full)."""
    if logged < log.shape[0]:
        return log
    bigger = np.zeros((2 * log.shape[0], log.shape[1]))
    bigger[: log.shape[0]] = log
    return bigger


@njit(cache=True)
def island_candidates(
    cand: np.ndarray, lo: int, hi: int, pairs: np.ndarray
) -> tuple[np.ndarray, int]:
    """An island's candidates ``cand[lo:hi]`` as piece pairs (C, 2), with room for more,
    and how many there are."""
    cp = np.empty((max(8, 2 * (hi - lo)), 2), np.int64)
    for c in range(lo, hi):
        cp[c - lo, 0] = pairs[cand[c], 0]
        cp[c - lo, 1] = pairs[cand[c], 1]
    return cp, hi - lo


@njit(cache=True)
def add_candidate(cp: np.ndarray, n: int, p: int, q: int) -> tuple[np.ndarray, int]:
    """Pieces ``p`` and ``q`` among the candidates ``cp[:n]`` (lower piece first), unless
    they are there; the candidates (grown when full) and their count."""
    a, b = min(p, q), max(p, q)
    for c in range(n):
        if cp[c, 0] == a and cp[c, 1] == b:
            return cp, n
    if n == cp.shape[0]:
        bigger = np.empty((2 * n, 2), np.int64)
        bigger[:n] = cp
        cp = bigger
    cp[n, 0] = a
    cp[n, 1] = b
    return cp, n + 1


@njit(cache=True)
def look_around(
    p: int,
    k: int,
    box: np.ndarray,
    boxes: np.ndarray,
    island_of: np.ndarray,
    piece_body: np.ndarray,
    reach: tuple[
        tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        np.ndarray,
        np.ndarray,
        np.ndarray,
    ],
    watching: tuple[np.ndarray, np.ndarray, np.ndarray],
    cp: np.ndarray,
    n: int,
) -> tuple[np.ndarray, int, bool]:
    """Piece ``p`` of a body of island ``k``, turned by an impact, can now reach ``box``
    (2 d,) by the step's end. Beyond its swept box ``boxes[p]``: widen that box to hold it,
    add the static pieces in it that its body may touch (``reach``: the static tree, its
    items' boxes, the static pieces it does not hold, the pieces of bodies that are not
    static, the collision filters; :func:`statics_in`) and the island's pieces in it to the
    candidates ``cp[:n]``. Returns the candidates, their count, and whether the island must
    stop: a piece moving otherwise lies in reach (``reach``'s pieces of bodies that are not
    static, beyond the swept box; within it, the ``watching`` pairs: the broad phase's pairs
    and island k's watched ones, :func:`gather`)."""
    if not _contained(box, boxes, p):
        d = box.shape[0] // 2
        for j in range(d):
            boxes[p, j] = min(boxes[p, j], box[j])
            boxes[p, d + j] = max(boxes[p, d + j], box[d + j])
        tree, open_statics, movers, filters = reach
        found, total = statics_in(
            box, tree, open_statics, np.empty(64, np.int64), filters, p, piece_body
        )
        for j in range(total):
            cp, n = add_candidate(cp, n, p, found[j])
        body = piece_body[p]
        for q in movers:
            other = piece_body[q]
            if other == body or not overlap(boxes, q, box) or not collides(filters, p, q):
                continue
            if island_of[other] != k:
                return cp, n, True
            cp, n = add_candidate(cp, n, p, q)
    pairs, watch, watch_first = watching
    return cp, n, _watched(p, k, box, boxes, pairs, watch, watch_first)


@njit(cache=True, inline="always")
def _watched(
    p: int,
    k: int,
    box: np.ndarray,
    boxes: np.ndarray,
    pairs: np.ndarray,
    watch: np.ndarray,
    watch_first: np.ndarray,
) -> bool:
    """Whether ``box`` (2 d,), where piece ``p`` of island ``k`` can go, meets the swept box
    of a piece moving otherwise that the broad phase paired with it (island k's watched
    pairs, :func:`gather`)."""
    for w in range(watch_first[k], watch_first[k + 1]):
        qa, qb = pairs[watch[w], 0], pairs[watch[w], 1]
        if (qa == p or qb == p) and overlap(boxes, qb if qa == p else qa, box):
            return True
    return False


@njit(cache=True)
def near_keys(ci: np.ndarray, nc: int, closest: np.ndarray, near: float, pieces: int) -> np.ndarray:
    """The piece pairs (``a * pieces + b``) of the ``nc`` contacts whose least separation at
    the step's start ``closest`` is within ``near`` [m], sorted (a far contact repeats the
    key before it, so that :func:`started_sunk` finds only the near ones)."""
    keys = np.full(nc, -1, np.int64)
    for m in range(nc):
        if closest[m] <= near:
            keys[m] = ci[m, I_PIECE_A] * pieces + ci[m, I_PIECE_B]
        elif m > 0:
            keys[m] = keys[m - 1]
    return keys


@njit(cache=True, inline="always")
def started_sunk(
    keys: np.ndarray, closest: np.ndarray, p: int, q: int, pieces: int
) -> tuple[bool, float]:
    """Whether pieces ``p`` and ``q`` were a near contact at the step's start
    (:func:`near_keys`), and how deep they overlapped then [m] (0 if apart)."""
    key = min(p, q) * pieces + max(p, q)
    at = np.searchsorted(keys, key)
    near = at < keys.shape[0] and keys[at] == key
    return near, max(0.0, -closest[at]) if near else 0.0


@njit(cache=True)
def statics_in(
    box: np.ndarray, tree: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
    np.ndarray], open_statics: np.ndarray, found: np.ndarray, filters: np.ndarray, piece: int,
    piece_body: np.ndarray,
) -> tuple[np.ndarray, int]:  # fmt: skip
    """The static pieces whose boxes meet ``box`` (2 d,) and that ``piece`` may touch under
    the pieces' ``filters`` (P, 3) (:func:`.filters.piece_filters`): through the static
    ``tree`` (node boxes, left, first, count, order, its items' boxes), then the
    ``open_statics`` it does not hold. Returns ``found`` (grown if need be) and how many it
    holds."""
    node_box, left, first, count, order, items = tree
    stack = np.empty(STACK, np.int64)
    total = query_bvh(node_box, left, first, count, order, items, box, found, stack)
    if total + open_statics.shape[0] > found.shape[0]:
        found = np.empty(total + open_statics.shape[0], np.int64)
        total = query_bvh(node_box, left, first, count, order, items, box, found, stack)
    for q in open_statics:
        if overlap(items, q, box):
            found[total] = q
            total += 1
    kept = 0
    for j in range(total):
        if collides(filters, piece, found[j]):
            found[kept] = found[j]
            kept += 1
    return found, kept


@njit(cache=True)
def keep_island(
    ci: np.ndarray, isolated: np.ndarray, lo: int, hi: int, island_of: np.ndarray,
    x: np.ndarray, turn: np.ndarray, v: np.ndarray, spin: np.ndarray,
) -> tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:  # fmt: skip
    """The bodies of an island (the moving ends of its rows ``isolated[lo:hi]``, a body
    once per row it is in) and copies of their state at the start of the step (position,
    angle or orientation, velocity, angular velocity), for :func:`give_back`."""
    bodies = np.empty(2 * (hi - lo), np.int64)
    n = 0
    for r in range(lo, hi):
        for body in (ci[isolated[r], I_BODY_A], ci[isolated[r], I_BODY_B]):
            if island_of[body] >= 0:
                bodies[n] = body
                n += 1
    bodies = bodies[:n]
    return bodies, (x[bodies], turn[bodies], v[bodies], spin[bodies])


@njit(cache=True)
def give_back(
    kept: tuple[np.ndarray, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]],
    ci: np.ndarray, isolated: np.ndarray, lo: int, hi: int, flags: int,
    island_of: np.ndarray, x: np.ndarray, turn: np.ndarray, v: np.ndarray, spin: np.ndarray,
) -> None:  # fmt: skip
    """Hand an island that cannot be finished exactly (a pair held in contact, the impacts'
    cap, a body moving otherwise in reach) back to the solver for the whole step: its bodies
    at their state of the step's start (:func:`keep_island`), out of the exact islands
    (``island_of`` -1), its rows no longer flagged exact (column ``flags``). The caller
    drops the island's logged impacts."""
    bodies, (x0, turn0, v0, spin0) = kept
    for j in range(bodies.shape[0]):
        i = bodies[j]
        x[i] = x0[j]
        turn[i] = turn0[j]
        v[i] = v0[j]
        spin[i] = spin0[j]
        island_of[i] = -1
    for r in range(lo, hi):
        ci[isolated[r], flags] &= ~FLAG_EXACT
