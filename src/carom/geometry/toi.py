"""Times of impact (TOI): when two spheres, or a sphere and a plane, first touch.

All functions take plain floats and return a time ``t >= 0`` [s] from now, or ``inf`` when
there is no contact to come. "Touch" means the gap closes while the bodies approach: a pair
already overlapping by round-off and still approaching collides now (``t = 0``); one
overlapping but separating never collides (Bannerman et al., arXiv 1211.6718). That rule is
what keeps round-off from hanging a run or letting an overlap grow.

References: PHYSICS.md section 4; Ericson, Real-Time Collision Detection, 5.5.3 and 5.5.5.
"""

from __future__ import annotations

import math

from numba import njit

from carom.jit import kernel_only

INF = math.inf


@njit(cache=True, error_model="numpy")
def toi_sphere_sphere(c: float, b: float, a: float) -> float:
    """First contact of two spheres in linear relative motion.

    With ``r`` the separation, ``v`` the relative velocity and ``R = a1 + a2``:
    ``c = r.r - R^2``, ``b = r.v``, ``a = v.v``; contact solves ``a t^2 + 2 b t + c = 0``.

    >>> toi_sphere_sphere(4.0 - 1.0, -2.0, 1.0)   # r = 2, closing at 1 m/s, R = 1
    1.0
    """
    if b >= 0.0:
        return INF  # separating or sliding past: the gap never closes
    if c <= 0.0:
        return 0.0  # touching or overlapped by round-off, and approaching: now
    disc = b * b - a * c
    if disc < 0.0:
        return INF  # passes by
    # smaller root (-b - sqrt(disc))/a, written without cancellation (b < 0, c > 0)
    return c / (-b + math.sqrt(disc))


@kernel_only(error_model="numpy")
def _quadratic_roots(a: float, b: float, c: float) -> tuple[float, float]:
    """Real roots of a t^2 + b t + c (NaN when absent), smaller first."""
    nan = math.nan
    if a == 0.0:
        return (-c / b, nan) if b != 0.0 else (nan, nan)
    disc = b * b - 4.0 * a * c
    if disc < 0.0:
        return nan, nan
    sq = math.sqrt(disc)
    q = -0.5 * (b + sq) if b >= 0.0 else -0.5 * (b - sq)
    r1 = q / a
    r2 = c / q if q != 0.0 else r1
    return (r1, r2) if r1 <= r2 else (r2, r1)


@njit(cache=True, error_model="numpy")
def toi_gap(d0: float, u: float, acc: float) -> float:
    """First time a gap ``d(t) = d0 + u t + acc t^2 / 2`` closes while closing.

    For a sphere against a plane: ``d0`` the distance from contact [m], ``u`` its rate
    [m/s], ``acc`` the normal acceleration [m/s^2] (gravity's component along the normal).

    >>> toi_gap(1.0, 0.0, -2.0)   # dropped from 1 m under 2 m/s^2: sqrt(2 * 1 / 2)
    1.0
    """
    touching = d0 <= 0.0
    if touching:
        # in contact (or overlapped by round-off): collide now only if closing
        if u < 0.0 or (u == 0.0 and acc < 0.0):
            return 0.0
        if u == 0.0 or acc >= 0.0:
            return INF  # leaving for good, or resting without a push
        # Leaving now but pulled back: it is back where it started after 2 u / |acc|. (Not
        # "when the gap closes": overlapped by round-off, d0 < 0, and leaving slower than
        # sqrt(2 |acc d0|), the gap never opens, and a body told INF falls through.)
        return -2.0 * u / acc
    half = 0.5 * acc
    if half == 0.0:
        return -d0 / u if u < 0.0 else INF
    lo, hi = _quadratic_roots(half, u, d0)  # NaN when there is no real root: never > 0
    # d0 > 0: the gap first closes at the smallest positive root
    if lo > 0.0:
        return lo
    if hi > 0.0:
        return hi
    return INF


@kernel_only(error_model="numpy")
def _horner(c4: float, c3: float, c2: float, c1: float, c0: float, t: float) -> float:
    return (((c4 * t + c3) * t + c2) * t + c1) * t + c0


@kernel_only(error_model="numpy")
def _bisect(c4: float, c3: float, c2: float, c1: float, c0: float, lo: float, hi: float) -> float:
    """A root of the polynomial in [lo, hi] given a sign change, to the last bit."""
    f_lo = _horner(c4, c3, c2, c1, c0, lo)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        if mid <= lo or mid >= hi:
            break
        f_mid = _horner(c4, c3, c2, c1, c0, mid)
        if (f_mid > 0.0) == (f_lo > 0.0):
            lo, f_lo = mid, f_mid
        else:
            hi = mid
    return hi


@njit(cache=True, error_model="numpy")
def first_root_quartic(
    c4: float, c3: float, c2: float, c1: float, c0: float, t_max: float
) -> float:
    """First time in [0, t_max] where ``f = c4 t^4 + ... + c0`` falls to zero from above.

    Used when the relative motion is accelerated (a sphere under gravity against a static
    sphere): ``f(t) = |r + v t + g t^2/2|^2 - R^2``. The roots of ``f''`` (a quadratic) split
    the interval where ``f'`` is monotone; bisection finds the roots of ``f'`` in each, which
    split it where ``f`` is monotone; the first piece on which ``f`` goes from positive to
    non-positive is bisected to the last bit. No root is missed and no iteration can stall.
    """
    if c0 <= 0.0:
        # touching (or overlapped by round-off)
        if c1 < 0.0 or (c1 == 0.0 and c2 < 0.0):
            return 0.0  # closing: now
        # Parting. If the acceleration brings them back, they meet when f is back at c0:
        # the first fall to zero of (f - c0) / t = c4 t^3 + c3 t^2 + c2 t + c1 (of
        # c4 t^2 + c3 t + c2 when c1 = 0). Not "when f falls to zero": overlapped by
        # round-off and parting slowly, f may never rise above zero, and a pair told INF
        # would pass through each other.
        if c1 > 0.0:
            return _first_fall(0.0, c4, c3, c2, c1, t_max)
        if c2 > 0.0:
            return _first_fall(0.0, 0.0, c4, c3, c2, t_max)
        return INF
    return _first_fall(c4, c3, c2, c1, c0, t_max)


@kernel_only(error_model="numpy")
def _root_bound(c4: float, c3: float, c2: float, c1: float, c0: float) -> float:
    """Twice Cauchy's bound ``1 + max |c_k / c_lead|`` on the roots' magnitudes: beyond it the
    polynomial is at least half its leading term in size, so no round-off flips its sign
    (INF for a constant)."""
    if c4 != 0.0:
        largest = max(abs(c3), abs(c2), abs(c1), abs(c0)) / abs(c4)
    elif c3 != 0.0:
        largest = max(abs(c2), abs(c1), abs(c0)) / abs(c3)
    elif c2 != 0.0:
        largest = max(abs(c1), abs(c0)) / abs(c2)
    elif c1 != 0.0:
        largest = abs(c0) / abs(c1)
    else:
        return INF
    return 2.0 * (1.0 + largest)


@kernel_only(error_model="numpy")
def _fall_on(c4: float, c3: float, c2: float, c1: float, c0: float, lo: float, hi: float) -> float:
    """First time in (lo, hi] where the quartic, positive at ``lo``, falls to zero, on a piece
    where its derivative changes sign at most once (INF if it does not): split at that
    critical point, and bisect the first part whose end is at or below zero."""
    d_lo = _horner(0.0, 4.0 * c4, 3.0 * c3, 2.0 * c2, c1, lo)
    d_hi = _horner(0.0, 4.0 * c4, 3.0 * c3, 2.0 * c2, c1, hi)
    if (d_lo > 0.0) != (d_hi > 0.0):
        p = _bisect(0.0, 4.0 * c4, 3.0 * c3, 2.0 * c2, c1, lo, hi)
        if p > lo and _horner(c4, c3, c2, c1, c0, p) <= 0.0:
            return _bisect(c4, c3, c2, c1, c0, lo, p)
        lo = p
    if hi > lo and _horner(c4, c3, c2, c1, c0, hi) <= 0.0:
        return _bisect(c4, c3, c2, c1, c0, lo, hi)
    return INF


@kernel_only(error_model="numpy")
def _first_fall(c4: float, c3: float, c2: float, c1: float, c0: float, t_max: float) -> float:
    """First time in (0, t_max] where the quartic, positive at 0 (``c0 > 0``), falls to zero.

    ``t_max`` may be infinite (a body at rest on a floor has no shell to leave); the search
    then ends at twice Cauchy's bound on the roots, beyond which the polynomial keeps its
    leading coefficient's sign. (Bisecting towards infinity found nothing: a ball pulled back
    onto one resting below it was never scheduled by the resting one, and sank into it.)
    """
    if not t_max > 0.0:
        return INF
    if t_max == INF:
        t_max = _root_bound(c4, c3, c2, c1, c0)
        if t_max == INF:
            return INF  # constant: positive for ever
    # critical points of f': roots of f'' = 12 c4 t^2 + 6 c3 t + 2 c2; they cut (0, t_max)
    # into at most three pieces, on each of which f' changes sign at most once
    s1, s2 = _quadratic_roots(12.0 * c4, 6.0 * c3, 2.0 * c2)
    a = s1 if s1 > 0.0 and s1 < t_max else INF
    b = s2 if s2 > 0.0 and s2 < t_max else INF
    if b < a:
        a, b = b, a
    lo = 0.0
    for hi in (a, b, t_max):
        if hi == INF:
            continue
        t = _fall_on(c4, c3, c2, c1, c0, lo, hi)
        if t != INF:
            return t
        lo = hi
    return INF


@njit(cache=True, error_model="numpy")
def shell_exit_time(off2: float, off_v: float, speed2: float, acc: float, delta: float) -> float:
    """When a body may first be ``delta`` from its shell centre [s] (a lower bound).

    ``off2`` is the squared distance from the centre [m^2], ``off_v`` the offset's rate
    ``d . v`` [m^2/s], ``speed2 = |v|^2`` [m^2/s^2] and ``acc = |acceleration|`` [m/s^2].
    In straight-line motion the time is exact: the positive root of
    ``|d + v t|^2 = delta^2``. Under acceleration it is the safe bound
    ``|d| + |v| t + acc t^2 / 2 = delta``.

    >>> shell_exit_time(0.0, 0.0, 4.0, 0.0, 1.0)   # from the centre at 2 m/s, 1 m to go
    0.5
    """
    c = off2 - delta * delta
    if c >= 0.0:
        return 0.0
    if acc == 0.0:
        if speed2 == 0.0:
            return INF
        # speed2 t^2 + 2 off_v t + c = 0 with c < 0: one positive root, cancellation-free
        sq = math.sqrt(off_v * off_v - speed2 * c)
        return -c / (off_v + sq) if off_v > 0.0 else (sq - off_v) / speed2
    room = delta - math.sqrt(off2)
    speed = math.sqrt(speed2)
    # positive root of acc/2 t^2 + speed t - room = 0, cancellation-free
    rate = speed + math.sqrt(speed * speed + 2.0 * acc * room)
    return 2.0 * room / rate if rate > 0.0 else INF
