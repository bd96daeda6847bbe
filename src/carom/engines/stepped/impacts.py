"""What both dimensions' exact impacts share: the isolated contacts taken in turn, and the
search for a pair's time of impact by conservative advancement (Mirtich 1996; Erin Catto's
time of impact in Box2D), written once as a step function the dimension calls with the gap it
measures.

The search starts at ``t = 0``. At each time it is given the gap ``d`` [m] and a bound on how
fast the gap can close from then to the horizon [m/s]; while the pieces are apart it moves on
by ``d`` over that bound, which cannot pass the first touch; within ``tol`` of touching it
stops; past it (a turn the bound missed, or a start already overlapping) it bisects back
between the last safe time and this one.
"""

from __future__ import annotations

import numpy as np
from numba import njit

from carom.engines.stepped.rows import FLAG_EXACT, I_BODY_A, I_BODY_B, I_PIECE_A, I_PIECE_B

__all__ = [
    "BISECTIONS",
    "MAX_IMPACTS",
    "MAX_ITERATIONS",
    "Search",
    "advance",
    "approaching",
    "search",
    "take_isolated",
]

#: conservative-advancement iterations before giving up on a time of impact (then the pair
#: flies on and the solver meets it at the next step)
MAX_ITERATIONS = 200
#: halvings of an overshot interval before settling on its safe end
BISECTIONS = 60
#: impacts of one pair within one step
MAX_IMPACTS = 8

#: a search's state: the last safe time, the bisected interval (lo, hi), whether it is
#: bisecting, how many gaps it has taken in its phase, and whether it still waits for a pair
#: just hit apart to part (then touching is not a new impact)
Search = tuple[float, float, float, bool, int, bool]


@njit(cache=True, inline="always")
def search(parting: bool) -> Search:
    """A new search from ``t = 0``; ``parting``: the pair has just been hit apart."""
    return 0.0, 0.0, 0.0, False, 0, parting


@njit(cache=True, inline="always")
def advance(
    state: Search, t: float, d: float, closing: float, tol: float, horizon: float
) -> tuple[bool, float, Search]:
    """One step of the search, given the gap ``d`` [m] at time ``t`` [s] and, while
    advancing, how fast it can close from ``t`` to ``horizon`` [m/s].

    Returns ``(done, time, state)``: done, the time of impact in ``[0, horizon]`` or -1 when
    there is none (or the search did not converge); else the next time to measure the gap at.
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
        if taken == BISECTIONS:
            return True, lo, state
        return False, 0.5 * (lo + hi), (safe, lo, hi, True, taken, parting)
    if d < -tol:
        # overshot: bisect back between the last safe time and t
        return False, 0.5 * (safe + t), (safe, safe, t, True, 0, parting)
    if d <= tol and not parting:
        return True, t, state
    if d > tol:
        parting = False
    if closing <= 0.0:
        return True, -1.0, state
    later = t + max(d, tol) / closing
    taken += 1
    if later > horizon or taken == MAX_ITERATIONS:
        return True, -1.0, state
    return False, later, (t, lo, hi, False, taken, parting)


@njit(cache=True, inline="always")
def take_isolated(ci: np.ndarray, m: int, flags: int) -> tuple[int, int, int, int]:
    """Contact row ``m``'s bodies and pieces ``(a, b, pa, pb)``, flagged solved exactly
    (column ``flags``)."""
    ci[m, flags] |= FLAG_EXACT
    return ci[m, I_BODY_A], ci[m, I_BODY_B], ci[m, I_PIECE_A], ci[m, I_PIECE_B]


@njit(cache=True, inline="always")
def approaching(un: np.ndarray, used: int) -> bool:
    """Whether any of the first ``used`` normal relative speeds ``un`` [m/s] approaches."""
    for j in range(used):  # noqa: SIM110 (a loop Numba compiles, not a generator)
        if un[j] < 0.0:
            return True
    return False
