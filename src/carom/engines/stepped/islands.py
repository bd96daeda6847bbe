"""Islands: bodies joined by contacts. Who goes to the exact impact path, who to the solver,
who flies free; who falls asleep and who wakes.

Dynamic bodies touching (or about to touch) are joined by union-find (Tarjan 1975, path
halving); static and kinematic bodies join nothing, so the ground does not make one island of
everything on it. An island whose every contact is an impact still to happen (apart at the start
of the step, or touching and closing faster than the restitution threshold), with no kinematic
body and at most :data:`MAX_EXACT_CONTACTS` contacts, is solved exactly: its impacts are taken
in the order they happen, each at its time of impact (:mod:`carom.engines.rigid.impacts`), so a
fast body meets every wall in its way within one step; an island with no contact flies free;
the rest go to the solver. An island whose bodies all stayed slower than the sleep speed for
the sleep time sleeps: it is skipped until an awake body touches one of its bodies, which wakes
the whole island.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from carom.engines.stepped.rows import I_BODY_A, I_BODY_B
from carom.laws.kinds import KIND_DYNAMIC, KIND_KINEMATIC, KIND_STATIC

__all__ = [
    "KIND_DYNAMIC",
    "KIND_KINEMATIC",
    "KIND_STATIC",
    "MAX_EXACT_CONTACTS",
    "plan",
    "settle",
    "wake",
]


ROLE_ASLEEP = 0  # skipped
ROLE_FREE = 1  # no contact: exact free flight
ROLE_EXACT = 2  # in an island solved exactly this step
ROLE_SOLVER = 3  # in the soft-step solver
ROLE_CLOTH = 4  # a ball alone on a level cloth: moved in closed form (3D: rigid3d/cloth.py)

#: contacts of an island solved exactly, at the most: a denser cluster is the solver's
MAX_EXACT_CONTACTS = 32


@njit(cache=True, inline="always")
def _root(parent: np.ndarray, i: int) -> int:
    while parent[i] != i:
        parent[i] = parent[parent[i]]
        i = parent[i]
    return i


@njit(cache=True, inline="always")
def _union(parent: np.ndarray, kind: np.ndarray, a: int, b: int) -> None:
    """Join the islands of ``a`` and ``b`` when both are dynamic (-1, the world, joins
    nothing); the smaller root becomes the root: the same islands every run."""
    if a < 0 or b < 0 or kind[a] != KIND_DYNAMIC or kind[b] != KIND_DYNAMIC:
        return
    ra = _root(parent, a)
    rb = _root(parent, b)
    if ra < rb:
        parent[rb] = ra
    elif rb < ra:
        parent[ra] = rb


@njit(cache=True)
def plan(
    ci: np.ndarray,
    nc: int,
    closest: np.ndarray,
    closing: np.ndarray,
    skip: np.ndarray,
    kind: np.ndarray,
    awake: np.ndarray,
    exact: bool,
    apart: float,
    fast: float,
    leaving: float,
    torqued: np.ndarray,
    links: np.ndarray,
    parent: np.ndarray,
    role: np.ndarray,
    isolated: np.ndarray,
    island_first: np.ndarray,
    island_of: np.ndarray,
) -> int:
    """Join the islands and give every body a role; return the number of islands solved
    exactly, whose contact rows are written to ``isolated``, island by island.

    Parameters
    ----------
    ci : contact rows (their bodies in columns ``I_BODY_A``, ``I_BODY_B``); ``nc`` of them.
    closest, closing : (nc,) float64
        Each contact's least separation [m] and least normal relative speed [m/s] over its
        points at the start of the step (the 2D and 3D engines lay their rows out apart).
    skip : (nc,) bool
        Contacts left out: a ball's cloth, which holds it while it moves in closed form
        (:mod:`carom.engines.rigid3d.cloth`). They join nothing (their other body is static)
        and count for nothing: a ball with only its cloth flies free (the 3D engine rolls it),
        two balls on the cloth about to meet are an island solved exactly.
    kind : (N,) int64
        KIND_DYNAMIC, KIND_STATIC or KIND_KINEMATIC.
    awake : (N,) bool
        Awake dynamic bodies (others are ignored).
    exact : bool
        Whether impacts are solved exactly (else everything goes to the solver).
    apart : float
        A contact whose every point is further apart than this [m] at the start of the step
        is an impact still to happen, not a resting contact.
    fast : float
        So is a touching contact closing faster than this [m/s] (the restitution threshold):
        the impact happens at the very start of the step.
    leaving : float
        And so is a touching contact whose every point separates faster than this [m/s]: the
        pair has just bounced, and flies apart exactly (inf: never).
    torqued : (N,) bool
        Bodies given a torque for this step: an island with one is the solver's (the exact
        impacts move bodies at a constant spin between impacts).
    links : (L, 2) int64
        The bodies joints join (-1: the world): they join islands as contacts do, and an
        island with a joint is the solver's (a joint holds its bodies out of free flight).
    parent : (N,) int64
        Written: each body's island root (itself for non-dynamic bodies).
    role : (N,) int64
        Written: ROLE_* of each body.
    isolated : (nc,) int64
        Written: the contact rows of the islands solved exactly, the first island's first.
    island_first : (N + 1,) int64
        Written: island k's rows are ``isolated[island_first[k]:island_first[k + 1]]``.
    island_of : (N,) int64
        Written: the island solved exactly that each body is in, or -1.
    """
    n = kind.shape[0]
    for i in range(n):
        parent[i] = i
        island_of[i] = -1
    for m in range(nc):
        a = ci[m, I_BODY_A]
        b = ci[m, I_BODY_B]
        _union(parent, kind, a, b)
    for m in range(links.shape[0]):
        _union(parent, kind, links[m, 0], links[m, 1])
    contacts = np.zeros(n, np.int64)
    # an island with a resting contact, a kinematic body or a joint is the solver's
    solver_only = np.zeros(n, np.bool_)
    for m in range(links.shape[0]):
        for body in (links[m, 0], links[m, 1]):
            if body >= 0 and kind[body] == KIND_DYNAMIC:
                r = _root(parent, body)
                contacts[r] += 1
                solver_only[r] = True
    for m in range(nc):
        if skip[m]:
            continue
        a = ci[m, I_BODY_A]
        b = ci[m, I_BODY_B]
        owner = a if kind[a] == KIND_DYNAMIC else b
        r = _root(parent, owner)
        contacts[r] += 1
        resting = closest[m] <= apart and -fast <= closing[m] <= leaving
        if resting or kind[a] == KIND_KINEMATIC or kind[b] == KIND_KINEMATIC:
            solver_only[r] = True
    for i in range(n):
        parent[i] = _root(parent, i)
        if torqued[i]:
            solver_only[parent[i]] = True
    for i in range(n):
        if kind[i] != KIND_DYNAMIC:
            role[i] = ROLE_SOLVER if kind[i] == KIND_KINEMATIC else ROLE_ASLEEP
        elif not awake[i]:
            role[i] = ROLE_ASLEEP
        else:
            role[i] = ROLE_FREE if contacts[parent[i]] == 0 else ROLE_SOLVER
    if not exact:
        return 0
    count = 0
    number = np.full(n, -1, np.int64)  # each exact island's number, by its root
    for r in range(n):
        if (
            0 < contacts[r] <= MAX_EXACT_CONTACTS
            and not solver_only[r]
            and kind[r] == KIND_DYNAMIC
            and awake[r]
        ):
            island_first[count + 1] = contacts[r]
            number[r] = count
            count += 1
    island_first[0] = 0
    for k in range(count):
        island_first[k + 1] += island_first[k]
    filled = island_first[:count].copy()
    for m in range(nc):
        if skip[m]:
            continue
        a = ci[m, I_BODY_A]
        owner = a if kind[a] == KIND_DYNAMIC else ci[m, I_BODY_B]
        k = number[parent[owner]]
        if k >= 0:
            isolated[filled[k]] = m
            filled[k] += 1
    for i in range(n):
        if kind[i] == KIND_DYNAMIC and role[i] != ROLE_ASLEEP and number[parent[i]] >= 0:
            role[i] = ROLE_EXACT
            island_of[i] = number[parent[i]]
    return count


@njit(cache=True)
def settle(
    ci: np.ndarray,
    nc: int,
    kind: np.ndarray,
    parent: np.ndarray,
    awake: np.ndarray,
    fastest: np.ndarray,
    moving: np.ndarray,
    clock: np.ndarray,
    island: np.ndarray,
    dt: float,
    speed: float,
    time: float,
) -> None:
    """Run the sleep clocks and put to sleep every island that stayed slow for ``time`` [s]:
    ``awake[i]`` goes false and ``island[i]`` is set to the island's root (the caller stops
    those bodies, as Box2D does: they wake at rest).

    ``fastest`` (N,) is the speed of each body's fastest point [m/s] (``|v| + |w| reach``);
    ``moving`` (N,) marks kinematic bodies in motion: an island touching one stays awake.
    """
    n = kind.shape[0]
    slowest = np.full(n, np.inf)
    for i in range(n):
        if kind[i] != KIND_DYNAMIC or not awake[i]:
            continue
        if fastest[i] > speed:
            clock[i] = 0.0
        else:
            clock[i] += dt
        r = parent[i]
        slowest[r] = min(slowest[r], clock[i])
    for m in range(nc):
        a = ci[m, I_BODY_A]
        b = ci[m, I_BODY_B]
        for body, other in ((a, b), (b, a)):
            if kind[body] == KIND_DYNAMIC and kind[other] == KIND_KINEMATIC and moving[other]:
                slowest[parent[body]] = 0.0
    for i in range(n):
        if kind[i] == KIND_DYNAMIC and awake[i] and slowest[parent[i]] >= time:
            awake[i] = False
            island[i] = parent[i]


@njit(cache=True, inline="always")
def _rouse(
    a: int, b: int, kind: np.ndarray, awake: np.ndarray, moving: np.ndarray,
    island: np.ndarray, rouse: np.ndarray,
) -> bool:  # fmt: skip
    """Mark for waking the sleeping island of ``a`` or ``b`` that the pair joins to an awake
    body or a moving kinematic one (-1, the world, wakes nothing); whether it marked one."""
    if a < 0 or b < 0:
        return False
    marked = False
    for body, other in ((a, b), (b, a)):
        if kind[body] != KIND_DYNAMIC or awake[body]:
            continue
        if (kind[other] == KIND_DYNAMIC and awake[other]) or (
            kind[other] == KIND_KINEMATIC and moving[other]
        ):
            rouse[island[body]] = True
            marked = True
    return marked


@njit(cache=True)
def wake(
    ci: np.ndarray,
    nc: int,
    kind: np.ndarray,
    awake: np.ndarray,
    moving: np.ndarray,
    clock: np.ndarray,
    island: np.ndarray,
    links: np.ndarray,
) -> int:
    """Wake every sleeping island that a contact or a joint (``links``, (L, 2) bodies, -1
    the world) joins to an awake body or a moving kinematic one (``moving``, (N,) bool);
    return how many bodies woke (the caller then finds contacts again)."""
    n = kind.shape[0]
    rouse = np.zeros(n, np.bool_)
    any_island = False
    for m in range(nc):
        any_island |= _rouse(ci[m, I_BODY_A], ci[m, I_BODY_B], kind, awake, moving, island, rouse)
    for m in range(links.shape[0]):
        any_island |= _rouse(links[m, 0], links[m, 1], kind, awake, moving, island, rouse)
    if not any_island:
        return 0
    woke = 0
    for i in range(n):
        if kind[i] == KIND_DYNAMIC and not awake[i] and rouse[island[i]]:
            awake[i] = True
            clock[i] = 0.0
            woke += 1
    return woke
