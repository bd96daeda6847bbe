"""Isolated impacts, solved exactly: the step split at the time of impact.

An isolated pair is two bodies (or a body and a static or kinematic one) joined by one
contact and nothing else, still apart at the start of the step. Between impacts both fly
freely (:func:`carom.engines.rigid.motion.fly`, exact); the time of impact is found by
conservative advancement (Mirtich 1996): from a gap ``d`` the pair cannot touch sooner than
``d / s``, where ``s`` bounds the speed at which the gap closes (the centres' relative speed
along the closest points' direction, plus ``|omega| reach`` for each body, plus the relative
gravity over what is left of the step). Steps of ``d / s`` converge on the contact from the
safe side; a step that overshoots (a rotation the bound did not cover) is bisected back.

At the contact the impulse is Newton's restitution at the contact point with the bodies'
inertia (Hecker's formula; :mod:`carom.laws.point_impulse`), with Coulomb friction:

- one point: the impulse that makes the normal velocity ``-e un`` and stops the slip, if it
  lies in the friction cone (sticking); else the one that slides with ``|jt| = mu jn`` in the
  direction opposing the slip (sliding). Should that ever gain energy (the couplings of
  Kane's paradox), the normal impulse alone, then friction clamped to the cone.
- two points touching together (a face landing flat): the normal impulses solve the 2x2
  linear complementarity problem of Newton's law at both points exactly; friction follows
  per point, clamped.

The pair then flies on, and may meet again, or meet another body of its island or a wall,
within the step: an island's impacts are taken in the order they happen
(:mod:`carom.engines.stepped.impacts`).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.rigid.broadphase import sweep_box
from carom.engines.rigid.contacts import I_FLAGS
from carom.engines.rigid.motion import (
    apply_impulse,
    fixed_work,
    fly,
    place_piece,
    relative_velocity,
)
from carom.engines.stepped.impacts import (
    BOUNCED,
    HELD,
    NEW,
    PAIR_LOOKS,
    advance,
    approaching,
    closing_bound,
    discriminant_root,
    earliest,
    gather,
    give_back,
    impact_cap,
    island_candidates,
    keep_island,
    logged_row,
    look_around,
    near_keys,
    search,
    started_sunk,
    statics_in,
    take_isolated,
)
from carom.engines.stepped.rows import I_BODY_A, I_BODY_B
from carom.geometry.manifold2d import collide, core_witness
from carom.jit import leaf

__all__ = ["IMPACT_FIELDS", "continuous", "exact_impacts"]

#: columns of a logged impact: time into the step, body A, body B, impulse on A (x, y),
#: normal speeds before and after (the deepest point), the point (x, y), energy lost, work
#: done by a kinematic partner, the normal (x, y; from B to A)
IMPACT_FIELDS = 13


@leaf
def _gap(
    pa: int,
    pb: int,
    a: int,
    b: int,
    tau: float,
    x: np.ndarray,
    angle: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    accel: np.ndarray,
    piece_start: np.ndarray,
    piece_count: np.ndarray,
    piece_radius: np.ndarray,
    local_vertices: np.ndarray,
    local_normals: np.ndarray,
    vertices: np.ndarray,
    normals: np.ndarray,
    out: np.ndarray,
    ids: np.ndarray,
) -> tuple[float, float, float]:
    """Signed gap [m] between pieces pa (of body a) and pb (of b) after flying ``tau`` [s],
    and the unit direction from B to A along which it is measured."""
    for body, piece in ((a, pa), (b, pb)):
        px = x[body, 0] + (v[body, 0] + 0.5 * accel[body, 0] * tau) * tau
        py = x[body, 1] + (v[body, 1] + 0.5 * accel[body, 1] * tau) * tau
        place_piece(
            piece,
            px,
            py,
            angle[body] + omega[body] * tau,
            piece_start,
            piece_count,
            local_vertices,
            local_normals,
            vertices,
            normals,
        )
    sa = piece_start[pa]
    sb = piece_start[pb]
    ka = piece_count[pa]
    kb = piece_count[pb]
    d, wx, wy = core_witness(vertices, normals, sa, ka, sb, kb)
    if d > 0.0:
        return d - piece_radius[pa] - piece_radius[pb], wx, wy
    # the cores touch or overlap: the manifold's deepest point says by how much
    count = collide(
        vertices,
        normals,
        sa,
        ka,
        piece_radius[pa],
        sb,
        kb,
        piece_radius[pb],
        np.inf,
        0.0,
        out,
        ids,
    )
    deepest = 0.0
    for j in range(count):
        deepest = min(deepest, out[4 + 3 * j])
    return deepest, out[0], out[1]


@njit(cache=True, inline="always")
def _first_root(c: float, b: float, k: float) -> float:
    """Least ``h > 0`` [s] with ``c + b h - k h^2 / 2 = 0`` given ``c > 0``; inf if none."""
    root = discriminant_root(b, 2.0 * k * c)
    if root < 0.0:
        return np.inf
    if b < 0.0:
        return 2.0 * c / (root - b)
    if k > 0.0:
        return (b + root) / k
    return np.inf


@njit(cache=True, inline="always")
def _flown(
    body: int, t: float, x: np.ndarray, v: np.ndarray, accel: np.ndarray
) -> tuple[float, float, float, float]:
    """A body's centre [m] and velocity [m/s] after ``t`` [s] of free flight."""
    return (
        x[body, 0] + (v[body, 0] + 0.5 * accel[body, 0] * t) * t,
        x[body, 1] + (v[body, 1] + 0.5 * accel[body, 1] * t) * t,
        v[body, 0] + accel[body, 0] * t,
        v[body, 1] + accel[body, 1] * t,
    )


@njit(cache=True, inline="always")
def _corner_rise(
    row: int, vertices: np.ndarray, cx: float, cy: float, vx: float, vy: float, w: float,
    nx: float, ny: float,
) -> float:  # fmt: skip
    """The velocity along ``n`` [m/s] of corner ``row`` of a body centred at ``(cx, cy)`` [m],
    moving at ``(vx, vy)`` [m/s] and turning at ``w`` [rad/s]."""
    rise: float = (vx - w * (vertices[row, 1] - cy)) * nx + (vy + w * (vertices[row, 0] - cx)) * ny
    return rise


@leaf
def _curved_step(
    pa: int,
    pb: int,
    a: int,
    b: int,
    t: float,
    nx: float,
    ny: float,
    gap: float,
    x: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    accel: np.ndarray,
    piece_start: np.ndarray,
    piece_count: np.ndarray,
    piece_reach: np.ndarray,
    vertices: np.ndarray,
) -> float:
    """A step [s] in which pieces pa and pb (placed at ``t`` in ``vertices``), apart along
    ``n`` (from B to A), cannot lose ``gap`` [m] of their separation along ``n``.

    Each corner's height along ``n`` is, to first order, its height now plus its velocity's
    part along ``n`` times ``h``; what is left over is at least ``(g_n - omega^2 r) h^2 / 2``
    (Taylor's remainder: a corner at most ``r`` (the piece's reach) from its centre turning at
    ``omega``, the centres' relative acceleration ``g_n`` along ``n`` exact). The separation
    along a fixed ``n`` is at most the distance, so the least time at which some corner pair's
    bound could close the gap cannot pass the first touch. Unlike a bound on the fastest
    closing speed, it keeps the corners' real velocities: a body turning about a corner that
    touches, or sliding along a face, is not held to steps of the gap over its fastest
    corner's speed.
    """
    xa, ya, vax, vay = _flown(a, t, x, v, accel)
    xb, yb, vbx, vby = _flown(b, t, x, v, accel)
    wa = omega[a]
    wb = omega[b]
    pull = (accel[a, 0] - accel[b, 0]) * nx + (accel[a, 1] - accel[b, 1]) * ny
    k = wa * wa * piece_reach[pa] + wb * wb * piece_reach[pb] - pull
    sa, ka = piece_start[pa], piece_count[pa]
    sb, kb = piece_start[pb], piece_count[pb]
    low = np.inf  # the separation along n now: A's lowest corner less B's highest
    high = -np.inf
    lowest = sa
    highest = sb
    for i in range(sa, sa + ka):
        h = vertices[i, 0] * nx + vertices[i, 1] * ny
        if h < low:
            low, lowest = h, i
    for j in range(sb, sb + kb):
        h = vertices[j, 0] * nx + vertices[j, 1] * ny
        if h > high:
            high, highest = h, j
    # the closest pair's time first; then a pair needs its root only if its bound is below
    # zero by then (where k > 0 the bound is concave: it falls below zero only after its root)
    best = _first_root(
        gap,
        _corner_rise(lowest, vertices, xa, ya, vax, vay, wa, nx, ny)
        - _corner_rise(highest, vertices, xb, yb, vbx, vby, wb, nx, ny),
        k,
    )
    for i in range(sa, sa + ka):
        above = vertices[i, 0] * nx + vertices[i, 1] * ny - low
        rise = _corner_rise(i, vertices, xa, ya, vax, vay, wa, nx, ny)
        for j in range(sb, sb + kb):
            below = high - (vertices[j, 0] * nx + vertices[j, 1] * ny)
            c = gap + above + below
            slope = rise - _corner_rise(j, vertices, xb, yb, vbx, vby, wb, nx, ny)
            if k > 0.0 and best < np.inf and c + (slope - 0.5 * k * best) * best >= 0.0:
                continue
            best = min(best, _first_root(c, slope, k))
    return best


@njit(cache=True, inline="always")
def _facing(
    pa: int,
    pb: int,
    nx: float,
    ny: float,
    piece_start: np.ndarray,
    piece_count: np.ndarray,
    normals: np.ndarray,
) -> int:
    """The face whose normal the direction ``n`` (from B to A) is, to 1e-6: ``row + 1`` for
    a face of pb, ``-(row + 1)`` for one of pa facing the other way; 0 if neither (two corners
    closest, or a circle)."""
    for side in (1, -1):
        p = pb if side == 1 else pa
        if piece_count[p] < 3:
            continue
        for j in range(piece_start[p], piece_start[p] + piece_count[p]):
            if side * (normals[j, 0] * nx + normals[j, 1] * ny) > 1.0 - 1e-6:
                return side * (j + 1)
    return 0


@leaf
def _face_step(
    fp: int,
    f: int,
    wp: int,
    w: int,
    t: float,
    nx: float,
    ny: float,
    target: float,
    horizon: float,
    x: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    accel: np.ndarray,
    piece_start: np.ndarray,
    piece_count: np.ndarray,
    piece_reach: np.ndarray,
    vertices: np.ndarray,
) -> float:
    """A step [s] in which the separation of piece ``wp``'s core (of body ``w``) from piece
    ``fp``'s (of body ``f``) along the normal ``n`` of a face of ``fp``, the normal turning with its
    body, cannot fall to ``target`` [m] (pieces placed at ``t``; ``horizon`` [s] the
    search's); 0 if it is not above it now.

    As Box2D's time of impact follows a face in its body's frame, so here: ``fp``'s extent
    along its own face normal is fixed, and each corner of ``wp`` has a height above it whose
    first derivative is known now and whose second is bounded over the horizon (the relative
    acceleration, the corner's turning, the normal's turning, its Coriolis coupling with the
    relative velocity). A face turning under a corner does not count as a corner of its own
    rising at the face's end, as a fixed direction would have it."""
    xfx, xfy, vfx, vfy = _flown(f, t, x, v, accel)
    xwx, xwy, vwx, vwy = _flown(w, t, x, v, accel)
    of = omega[f]
    ow = omega[w]
    reach = piece_reach[wp]
    dv = math.hypot(vwx - vfx, vwy - vfy)
    da = math.hypot(accel[w, 0] - accel[f, 0], accel[w, 1] - accel[f, 1])
    apart = math.hypot(xwx - xfx, xwy - xfy)
    span = horizon - t
    # the least the heights' second derivative can be over the horizon, negated
    k = (
        da
        + ow * ow * reach
        + 2.0 * abs(of) * (dv + da * span + abs(ow) * reach)
        + of * of * (apart + reach + dv * span + 0.5 * da * span * span)
    )
    top = -np.inf  # fp's extent along its normal, from its centre (fixed in its frame)
    for j in range(piece_start[fp], piece_start[fp] + piece_count[fp]):
        top = max(top, (vertices[j, 0] - xfx) * nx + (vertices[j, 1] - xfy) * ny)
    best = np.inf
    for i in range(piece_start[wp], piece_start[wp] + piece_count[wp]):
        rx = vertices[i, 0] - xfx
        ry = vertices[i, 1] - xfy
        c = rx * nx + ry * ny - top - target  # how far this corner may sink [m]
        if c <= 0.0:
            return 0.0
        # d/dt (r . n): the corner's velocity relative to f's centre along n, plus r along
        # the normal's turn (omega_f perp(n))
        ux = vwx - ow * (vertices[i, 1] - xwy) - vfx
        uy = vwy + ow * (vertices[i, 0] - xwx) - vfy
        slope = ux * nx + uy * ny + of * (ry * nx - rx * ny)
        if best < np.inf and c + (slope - 0.5 * k * best) * best >= 0.0:
            continue
        best = min(best, _first_root(c, slope, k))
    return best


@leaf
def time_of_impact(
    pa: int,
    pb: int,
    a: int,
    b: int,
    horizon: float,
    tol: float,
    parting: int,
    x: np.ndarray,
    angle: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    accel: np.ndarray,
    piece_start: np.ndarray,
    piece_count: np.ndarray,
    piece_radius: np.ndarray,
    piece_reach: np.ndarray,
    local_vertices: np.ndarray,
    local_normals: np.ndarray,
    vertices: np.ndarray,
    normals: np.ndarray,
    out: np.ndarray,
    ids: np.ndarray,
    allow: float = 0.0,
) -> float:
    """First time in ``[0, horizon]`` [s] at which the pieces come within ``tol`` [m] of
    touching (of overlapping by ``allow`` [m], if given), by conservative advancement; -1 if
    they do not (after many steps, the furthest time known safe: the caller looks again).

    ``parting``: how the pair was left at its last meeting (``NEW``, ``HELD`` or ``BOUNCED``
    of :mod:`carom.engines.stepped.impacts`); unless ``NEW``, the contact it starts in is not
    a new impact, and the search first lets the gap open beyond ``tol``."""
    spin = abs(omega[a]) * piece_reach[pa] + abs(omega[b]) * piece_reach[pb]
    gx = accel[a, 0] - accel[b, 0]
    gy = accel[a, 1] - accel[b, 1]
    state = search(parting)
    t = 0.0
    while True:
        d, wx, wy = _gap(
            pa, pb, a, b, t, x, angle, v, omega, accel, piece_start, piece_count, piece_radius,
            local_vertices, local_normals, vertices, normals, out, ids,
        )  # fmt: skip
        # how fast the gap can close until it could first be closed
        ux = (v[a, 0] + accel[a, 0] * t) - (v[b, 0] + accel[b, 0] * t)
        uy = (v[a, 1] + accel[a, 1] * t) - (v[b, 1] + accel[b, 1] * t)
        gap = max(d + allow, tol)
        closing = closing_bound(gap, ux * wx + uy * wy, gx * wx + gy * wy, spin)
        if wx != 0.0 or wy != 0.0:
            curved = _curved_step(
                pa, pb, a, b, t, wx, wy, gap, x, v, omega, accel, piece_start, piece_count,
                piece_reach, vertices,
            )  # fmt: skip
            face = _facing(pa, pb, wx, wy, piece_start, piece_count, normals)
            if face != 0:  # the gap runs along a face's normal: follow the face as it turns
                fp, f, wp, w = (pb, b, pa, a) if face > 0 else (pa, a, pb, b)
                row = abs(face) - 1
                # the cores' separation the step must keep above [m]
                core = d - gap + piece_radius[pa] + piece_radius[pb]
                curved = max(
                    curved,
                    _face_step(
                        fp, f, wp, w, t, normals[row, 0], normals[row, 1], core, horizon,
                        x, v, omega, accel, piece_start, piece_count, piece_reach, vertices,
                    ),
                )  # fmt: skip
            # the longest of the safe steps (inf: the pieces cannot touch)
            if closing > 0.0 and curved > gap / closing:
                closing = gap / curved
        done, t, state = advance(state, t, d + allow, closing, tol, horizon)
        if done:
            return t


@njit(cache=True, inline="always")
def _point_speeds(
    a: int, b: int, rax: float, ray: float, rbx: float, rby: float, v: np.ndarray,
    omega: np.ndarray,
) -> float:  # fmt: skip
    """A bound on the sizes of both bodies' velocities at a contact point, ``|v| +
    |omega| |r|`` each [m/s]: the scale of the relative velocity's round-off."""
    speeds: float = (
        math.hypot(v[a, 0], v[a, 1]) + abs(omega[a]) * math.hypot(rax, ray)
        + math.hypot(v[b, 0], v[b, 1]) + abs(omega[b]) * math.hypot(rbx, rby)
    )  # fmt: skip
    return speeds


@njit(cache=True)
def _solve_two(k11: float, k12: float, k22: float, b1: float, b2: float) -> tuple[float, float]:
    """Impulses ``l >= 0`` with ``w = K l - b >= 0`` and ``l . w = 0`` (2x2 LCP, by cases)."""
    det = k11 * k22 - k12 * k12
    if det > 1e-14 * k11 * k22:
        l1 = (k22 * b1 - k12 * b2) / det
        l2 = (k11 * b2 - k12 * b1) / det
        if l1 >= 0.0 and l2 >= 0.0:
            return l1, l2
    l1 = max(b1 / k11, 0.0)
    if l1 > 0.0 and k12 * l1 - b2 >= 0.0:
        return l1, 0.0
    l2 = max(b2 / k22, 0.0)
    if l2 > 0.0 and k12 * l2 - b1 >= 0.0:
        return 0.0, l2
    if b1 <= 0.0 and b2 <= 0.0:
        return 0.0, 0.0
    # degenerate (parallel rows): share the larger single-point impulse
    if l1 >= l2:
        return l1, 0.0
    return 0.0, l2


@njit(cache=True)
def _point_impulse(
    un: float, ut: float, knn: float, knt: float, ktt: float, e: float, mu: float
) -> tuple[float, float]:
    """Normal and tangent impulse [N s] of one contact point (module docstring)."""
    if un >= 0.0:
        return 0.0, 0.0
    target = -(1.0 + e) * un
    if mu > 0.0:
        det = knn * ktt - knt * knt
        if det > 0.0:
            jn = (ktt * target + knt * ut) / det
            jt = (-knn * ut - knt * target) / det
            if jn >= 0.0 and abs(jt) <= mu * jn:
                gain = (
                    jn * un + jt * ut + 0.5 * (knn * jn * jn + 2.0 * knt * jn * jt + ktt * jt * jt)
                )
                if gain <= 0.0:
                    return jn, jt
        slip = ut if ut != 0.0 else -(-knn * ut - knt * target)
        direction = 1.0 if slip > 0.0 else -1.0
        denom = knn - mu * direction * knt
        if denom > 0.0:
            jn = target / denom
            jt = -mu * direction * jn
            gain = jn * un + jt * ut + 0.5 * (knn * jn * jn + 2.0 * knt * jn * jt + ktt * jt * jt)
            if jn >= 0.0 and gain <= 0.0:
                return jn, jt
    jn = target / knn
    if mu == 0.0:
        return jn, 0.0
    # the normal impulse alone, then friction clamped: never gains energy (the friction is
    # the energy-minimising tangent impulse for that normal impulse, moved into the cone)
    jt = min(max(-(ut + knt * jn) / ktt, -mu * jn), mu * jn)
    return jn, jt


@njit(cache=True, inline="always")
def _kinetic(
    a: int,
    b: int,
    v: np.ndarray,
    omega: np.ndarray,
    inv_mass: np.ndarray,
    mass: np.ndarray,
    inertia: np.ndarray,
) -> float:
    """Kinetic energy of bodies a and b [J], those that move (finite mass) only."""
    energy = 0.0
    for body in (a, b):
        if inv_mass[body] > 0.0:
            energy += 0.5 * mass[body] * (v[body, 0] ** 2 + v[body, 1] ** 2)
            energy += 0.5 * inertia[body] * omega[body] ** 2
    return energy


@njit(cache=True)
def _impact(
    a: int,
    b: int,
    count: int,
    out: np.ndarray,
    touch: float,
    e: float,
    mu: float,
    x: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    inv_mass: np.ndarray,
    inv_inertia: np.ndarray,
    mass: np.ndarray,
    inertia: np.ndarray,
    record: np.ndarray,
) -> bool:
    """Apply the exact impulse of the touching points of manifold ``out``; fill ``record``.
    Returns False when no touching point approaches (nothing done)."""
    nx = out[0]
    ny = out[1]
    tx = ny
    ty = -nx
    deepest = np.inf
    for j in range(count):
        deepest = min(deepest, out[4 + 3 * j])
    rax = np.empty(2)
    ray = np.empty(2)
    rbx = np.empty(2)
    rby = np.empty(2)
    un = np.empty(2)
    ut = np.empty(2)
    used = 0
    scale = 0.0  # the largest sum of the two bodies' point speeds [m/s]
    for j in range(count):
        if out[4 + 3 * j] > deepest + touch:
            continue
        # each body's own surface point: the manifold's point lies halfway across the gap
        # (at most the advancement's tolerance), so the lever arms are exact
        half = 0.5 * out[4 + 3 * j]
        px = out[2 + 3 * j]
        py = out[3 + 3 * j]
        rax[used] = px + half * nx - x[a, 0]
        ray[used] = py + half * ny - x[a, 1]
        rbx[used] = px - half * nx - x[b, 0]
        rby[used] = py - half * ny - x[b, 1]
        ux, uy = relative_velocity(a, b, rax[used], ray[used], rbx[used], rby[used], v, omega)
        un[used] = ux * nx + uy * ny
        ut[used] = ux * tx + uy * ty
        scale = max(
            scale, _point_speeds(a, b, rax[used], ray[used], rbx[used], rby[used], v, omega)
        )
        used += 1
    if not approaching(un, used, scale):
        return False
    ma = inv_mass[a]
    mb = inv_mass[b]
    ia = inv_inertia[a]
    ib = inv_inertia[b]
    energy = _kinetic(a, b, v, omega, inv_mass, mass, inertia)
    jn = np.zeros(2)
    jt = np.zeros(2)
    if used == 1:
        rna = rax[0] * ny - ray[0] * nx
        rnb = rbx[0] * ny - rby[0] * nx
        rta = rax[0] * ty - ray[0] * tx
        rtb = rbx[0] * ty - rby[0] * tx
        knn = ma + mb + ia * rna * rna + ib * rnb * rnb
        ktt = ma + mb + ia * rta * rta + ib * rtb * rtb
        knt = ia * rna * rta + ib * rnb * rtb
        jn[0], jt[0] = _point_impulse(un[0], ut[0], knn, knt, ktt, e, mu)
    else:
        rn1a = rax[0] * ny - ray[0] * nx
        rn1b = rbx[0] * ny - rby[0] * nx
        rn2a = rax[1] * ny - ray[1] * nx
        rn2b = rbx[1] * ny - rby[1] * nx
        k11 = ma + mb + ia * rn1a * rn1a + ib * rn1b * rn1b
        k22 = ma + mb + ia * rn2a * rn2a + ib * rn2b * rn2b
        k12 = ma + mb + ia * rn1a * rn2a + ib * rn1b * rn2b
        jn[0], jn[1] = _solve_two(k11, k12, k22, -(1.0 + e) * un[0], -(1.0 + e) * un[1])
    # apply the normal impulses, then friction point by point (clamped to each cone)
    work = 0.0  # by a kinematic partner (its velocity does not change)
    for j in range(used):
        px = jn[j] * nx + jt[j] * tx
        py = jn[j] * ny + jt[j] * ty
        work += fixed_work(a, b, px, py, rax[j], ray[j], rbx[j], rby[j], inv_mass, v, omega)
        apply_impulse(a, b, px, py, rax[j], ray[j], rbx[j], rby[j], inv_mass, inv_inertia, v, omega)
    if used == 2 and mu > 0.0:
        for j in range(2):
            ux, uy = relative_velocity(a, b, rax[j], ray[j], rbx[j], rby[j], v, omega)
            rta = rax[j] * ty - ray[j] * tx
            rtb = rbx[j] * ty - rby[j] * tx
            ktt = ma + mb + ia * rta * rta + ib * rtb * rtb
            dj = min(max(-(ux * tx + uy * ty) / ktt, -mu * jn[j]), mu * jn[j])
            jt[j] = dj
            work += fixed_work(
                a, b, dj * tx, dj * ty, rax[j], ray[j], rbx[j], rby[j], inv_mass, v, omega
            )
            apply_impulse(
                a,
                b,
                dj * tx,
                dj * ty,
                rax[j],
                ray[j],
                rbx[j],
                rby[j],
                inv_mass,
                inv_inertia,
                v,
                omega,
            )
    after = _kinetic(a, b, v, omega, inv_mass, mass, inertia)
    # the record: the first touching point's speeds, the total impulse on A
    j0 = 0
    ux, uy = relative_velocity(a, b, rax[j0], ray[j0], rbx[j0], rby[j0], v, omega)
    record[1] = a
    record[2] = b
    record[3] = (jn[0] + jn[1]) * nx + (jt[0] + jt[1]) * tx
    record[4] = (jn[0] + jn[1]) * ny + (jt[0] + jt[1]) * ty
    record[5] = un[j0]
    record[6] = ux * nx + uy * ny
    record[7] = x[a, 0] + rax[j0]
    record[8] = x[a, 1] + ray[j0]
    record[9] = energy - after + work
    record[10] = work
    record[11] = nx
    record[12] = ny
    return True


@njit(cache=True)
def exact_impacts(
    islands: tuple[np.ndarray, np.ndarray, int, np.ndarray],
    pairs: np.ndarray,
    n_pairs: int,
    boxes: np.ndarray,
    reach: tuple[
        tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        np.ndarray,
        np.ndarray,
        np.ndarray,
    ],
    ci: np.ndarray,
    x: np.ndarray,
    angle: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    accel: np.ndarray,
    kind: np.ndarray,
    inv_mass: np.ndarray,
    inv_inertia: np.ndarray,
    mass: np.ndarray,
    inertia: np.ndarray,
    material: np.ndarray,
    e_table: np.ndarray,
    mu_table: np.ndarray,
    body_pieces: np.ndarray,
    piece_body: np.ndarray,
    piece_start: np.ndarray,
    piece_count: np.ndarray,
    piece_radius: np.ndarray,
    piece_reach: np.ndarray,
    local_vertices: np.ndarray,
    local_normals: np.ndarray,
    vertices: np.ndarray,
    normals: np.ndarray,
    dt: float,
    touch: float,
    margin: float,
    slow: float,
) -> tuple[np.ndarray, int]:
    """Advance each island solved exactly through the step, its impacts taken in the order
    they happen (:mod:`carom.engines.stepped.impacts`).

    ``islands``: the contact rows of the islands (flagged exact here), island k's from
    ``first[k]`` to ``first[k + 1]``, how many islands, and each body's island or -1
    (:func:`carom.engines.stepped.islands.plan`); ``pairs[:n_pairs]`` the broad phase's pairs
    and ``boxes`` (P, 4) the swept boxes it found them with (widened here where a body turned
    by an impact can reach further); ``reach``: the static tree (node boxes, left, first,
    count, order, its items' boxes), the static pieces it does not hold, and the pieces of
    bodies that are not static; ``accel`` (N, 2) each body's free acceleration;
    ``material``, ``e_table``, ``mu_table`` the coefficients; ``margin`` [m] the broad
    phase's; ``slow`` [m/s] the restitution threshold: a pair that meets no impact, or one
    slower than this, more than :data:`~carom.engines.stepped.impacts.PAIR_LOOKS` times in
    the step is held in contact, and its island stops there (given back to the solver for
    the whole step if it took no impact yet). Returns the impacts' log (rows of
    :data:`IMPACT_FIELDS`) and how many rows it holds.
    """
    isolated, island_first, n_islands, island_of = islands
    out = np.empty(8)
    ids = np.empty(2, np.int64)
    cand_first, cand, watch_first, watch = gather(
        pairs, n_pairs, piece_body, kind, island_of, n_islands
    )
    clock = np.zeros(x.shape[0])  # each island body's own time into the step [s]
    log = np.zeros((max(16, 2 * island_first[n_islands]), IMPACT_FIELDS))
    logged = 0
    for k in range(n_islands):
        lo, hi = island_first[k], island_first[k + 1]
        for r in range(lo, hi):
            take_isolated(ci, isolated[r], I_FLAGS)
        kept = keep_island(ci, isolated, lo, hi, island_of, x, angle, v, omega)
        logged_before = logged
        cp, n = island_candidates(cand, cand_first[k], cand_first[k + 1], pairs)
        hit = np.empty(cp.shape[0])  # each candidate's time of impact into the step [s]
        parting = np.full(cp.shape[0], NEW)
        # how deep a pair that stopped approaching while overlapping already was [m]: only
        # sinking deeper is an impact (a pair met late by a search, or left by the solver)
        sunk = np.zeros(cp.shape[0])
        # each candidate's turns as the earliest that met no impact or a slow one
        looks = np.zeros(cp.shape[0], np.int64)
        for c in range(n):
            hit[c] = _next_impact(
                cp[c, 0], cp[c, 1], 0.0, dt, NEW, clock, island_of, x, angle, v, omega,
                accel, piece_body, piece_start, piece_count, piece_radius, piece_reach,
                local_vertices, local_normals, vertices, normals, out, ids,
            )  # fmt: skip
        now = 0.0
        taken = 0
        cap = impact_cap(n)
        stopped = False
        for _ in range(2 * cap):
            c = earliest(hit, 0, n)
            if c < 0:
                break
            now = hit[c]
            if looks[c] == PAIR_LOOKS:  # a pair held in contact, not meeting in impacts
                stopped = True
                break
            pa, pb = cp[c, 0], cp[c, 1]
            a, b = piece_body[pa], piece_body[pb]
            for body, piece in ((a, pa), (b, pb)):
                _sync(body, now, clock, island_of, x, angle, v, omega, accel)
                place_piece(
                    piece, x[body, 0], x[body, 1], angle[body], piece_start, piece_count,
                    local_vertices, local_normals, vertices, normals,
                )  # fmt: skip
            tol = 1e-9 * (piece_reach[pa] + piece_reach[pb])
            count = collide(
                vertices, normals, piece_start[pa], piece_count[pa], piece_radius[pa],
                piece_start[pb], piece_count[pb], piece_radius[pb], 2.0 * tol + touch, 0.0,
                out, ids,
            )  # fmt: skip
            log = logged_row(log, logged)
            ma, mb = material[a], material[b]
            parting[c] = HELD
            if count == 0 or not _impact(
                a, b, count, out, touch, e_table[ma, mb], mu_table[ma, mb], x, v, omega,
                inv_mass, inv_inertia, mass, inertia, log[logged],
            ):  # fmt: skip
                # touching, not approaching: wait for the gap to open (or close past touch)
                looks[c] += 1
                for j in range(count):
                    sunk[c] = max(sunk[c], -out[4 + 3 * j])
                hit[c] = _next_impact(
                    pa, pb, now, dt, HELD, clock, island_of, x, angle, v, omega, accel,
                    piece_body, piece_start, piece_count, piece_radius, piece_reach,
                    local_vertices, local_normals, vertices, normals, out, ids, sunk[c],
                )  # fmt: skip
                continue
            sunk[c] = 0.0
            if -log[logged, 5] < slow:  # met again slowly: perhaps held in contact
                looks[c] += 1
            elif e_table[ma, mb] > 0.0:  # hit apart at speed: the search waits for it to part
                parting[c] = BOUNCED
            log[logged, 0] = now
            logged += 1
            taken += 1
            stopped = taken == cap
            for body in (a, b):
                if not stopped and island_of[body] >= 0:
                    cp, n, stopped = _reach(
                        body, k, now, dt, cp, n, island_of, pairs, boxes, reach, watch,
                        watch_first, body_pieces, piece_body, x, angle, v, omega, accel,
                        piece_start, piece_count, piece_radius, piece_reach, local_vertices,
                        local_normals, vertices, normals, margin,
                    )  # fmt: skip
            if stopped:
                break
            if hit.shape[0] < cp.shape[0]:  # candidates were added: room for their times
                more = cp.shape[0] - hit.shape[0]
                hit = np.concatenate((hit, np.empty(more)))
                parting = np.concatenate((parting, np.full(more, NEW)))
                sunk = np.concatenate((sunk, np.zeros(more)))
                looks = np.concatenate((looks, np.zeros(more, np.int64)))
            for d in range(n):
                da, db = piece_body[cp[d, 0]], piece_body[cp[d, 1]]
                if da in (a, b) or db in (a, b):
                    hit[d] = _next_impact(
                        cp[d, 0], cp[d, 1], now, dt, parting[d], clock, island_of, x, angle,
                        v, omega, accel, piece_body, piece_start, piece_count, piece_radius,
                        piece_reach, local_vertices, local_normals, vertices, normals, out,
                        ids, sunk[d],
                    )  # fmt: skip
        else:
            stopped = True  # (as many looks as impacts allowed, twice over)
        if stopped and logged == logged_before:  # no impact yet: the solver's whole step
            give_back(kept, ci, isolated, lo, hi, I_FLAGS, island_of, x, angle, v, omega)
            continue
        # the island's bodies to the end of the step, or to its last impact (the solver
        # takes them from there in the next step: they lose the rest of this one)
        end = now if stopped else dt
        for r in range(lo, hi):
            for body in (ci[isolated[r], I_BODY_A], ci[isolated[r], I_BODY_B]):
                _sync(body, end, clock, island_of, x, angle, v, omega, accel)
    return log, logged


@njit(cache=True, inline="always")
def _sync(
    body: int, t: float, clock: np.ndarray, island_of: np.ndarray, x: np.ndarray,
    angle: np.ndarray, v: np.ndarray, omega: np.ndarray, accel: np.ndarray,
) -> None:  # fmt: skip
    """Fly a body of an island from its own clock to ``t`` [s] into the step (a static
    body stays)."""
    if island_of[body] >= 0 and t > clock[body]:
        fly(body, t - clock[body], x, angle, v, omega, accel[body, 0], accel[body, 1])
        clock[body] = t


@leaf
def _next_impact(
    pa: int, pb: int, now: float, dt: float, parting: int, clock: np.ndarray,
    island_of: np.ndarray, x: np.ndarray, angle: np.ndarray, v: np.ndarray,
    omega: np.ndarray, accel: np.ndarray, piece_body: np.ndarray, piece_start: np.ndarray,
    piece_count: np.ndarray, piece_radius: np.ndarray, piece_reach: np.ndarray,
    local_vertices: np.ndarray, local_normals: np.ndarray, vertices: np.ndarray,
    normals: np.ndarray, out: np.ndarray, ids: np.ndarray, allow: float = 0.0,
) -> float:  # fmt: skip
    """Time into the step [s] of pieces pa and pb's next impact after ``now`` (their
    overlapping by more than ``allow`` [m]), before the step's end ``dt``; inf if none.
    Their bodies are flown to ``now`` first."""
    a, b = piece_body[pa], piece_body[pb]
    _sync(a, now, clock, island_of, x, angle, v, omega, accel)
    _sync(b, now, clock, island_of, x, angle, v, omega, accel)
    t = time_of_impact(
        pa, pb, a, b, dt - now, 1e-9 * (piece_reach[pa] + piece_reach[pb]), parting, x, angle,
        v, omega, accel, piece_start, piece_count, piece_radius, piece_reach, local_vertices,
        local_normals, vertices, normals, out, ids, allow,
    )  # fmt: skip
    return now + t if t >= 0.0 else np.inf


@njit(cache=True)
def _reach(
    body: int, k: int, now: float, dt: float, cp: np.ndarray, n: int,
    island_of: np.ndarray, pairs: np.ndarray,
    boxes: np.ndarray, reach: tuple[
        tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        np.ndarray, np.ndarray, np.ndarray,
    ], watch: np.ndarray, watch_first: np.ndarray, body_pieces: np.ndarray,
    piece_body: np.ndarray, x: np.ndarray, angle: np.ndarray, v: np.ndarray,
    omega: np.ndarray, accel: np.ndarray, piece_start: np.ndarray, piece_count: np.ndarray,
    piece_radius: np.ndarray, piece_reach: np.ndarray, local_vertices: np.ndarray,
    local_normals: np.ndarray, vertices: np.ndarray, normals: np.ndarray, margin: float,
) -> tuple[np.ndarray, int, bool]:  # fmt: skip
    """After an impact turned ``body`` (of island ``k``, at ``now``): where it can go by the
    step's end ``dt``, each piece's swept box from now; beyond the box its pairs were found
    in, the statics there join the candidates ``cp[:n]``
    (:func:`carom.engines.stepped.impacts.look_around`). Returns the candidates, their
    count, and whether the island must stop (a body moving otherwise in reach)."""
    box = np.empty(4)
    for p in range(body_pieces[body], body_pieces[body + 1]):
        place_piece(
            p, x[body, 0], x[body, 1], angle[body], piece_start, piece_count, local_vertices,
            local_normals, vertices, normals,
        )  # fmt: skip
        sweep_box(
            p, vertices, piece_start, piece_count, piece_radius, piece_reach, v[body, 0],
            v[body, 1], omega[body], accel[body, 0], accel[body, 1], dt - now, True, 0.0,
            margin, box,
        )  # fmt: skip
        cp, n, stop = look_around(
            p, k, box, boxes, island_of, piece_body, reach, (pairs, watch, watch_first), cp, n
        )
        if stop:
            return cp, n, True
    return cp, n, False


@njit(cache=True)
def continuous(
    bodies: np.ndarray, x0: np.ndarray, angle0: np.ndarray, x: np.ndarray,
    angle: np.ndarray, v: np.ndarray, omega: np.ndarray, ci: np.ndarray, nc: int,
    closest: np.ndarray, reach: tuple[
        tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray],
        np.ndarray, np.ndarray, np.ndarray,
    ], dynamic: np.ndarray, body_reach: np.ndarray, body_pieces: np.ndarray,
    piece_body: np.ndarray, piece_start: np.ndarray, piece_count: np.ndarray,
    piece_radius: np.ndarray, piece_reach: np.ndarray, local_vertices: np.ndarray,
    local_normals: np.ndarray, vertices: np.ndarray, normals: np.ndarray, dt: float,
    speculative: float, slop: float,
) -> int:  # fmt: skip
    """Continuous collision of the solver's bodies against static geometry, as Box2D's:
    each dynamic body of ``bodies`` that moved further this step than the speculative
    distance [m] (from ``x0``, ``angle0`` to ``x``, ``angle``) is swept along that motion
    against the static pieces in reach; at the first touch it is put back there, its
    velocity kept. A static piece among its contacts (``nc`` rows, each one's least
    separation at the start ``closest``) within the speculative distance at the start is the
    solver's to hold: only sinking ``slop`` [m] deeper into it than at the start counts, and
    puts the body back where it was as deep as at the start. Returns how many bodies were put
    back."""
    tree, open_statics, _, filters = reach
    n_pieces = piece_body.shape[0]
    # (made at the first body that moved far: most steps have none)
    keys = np.empty(0, np.int64)
    still = np.zeros((0, 2))
    out = np.empty(8)
    ids = np.empty(2, np.int64)
    box = np.empty(4)
    found = np.empty(64, np.int64)
    put_back = 0
    for b in bodies:
        if not dynamic[b]:
            continue
        dx, dy = x[b, 0] - x0[b, 0], x[b, 1] - x0[b, 1]
        turn = angle[b] - angle0[b]
        if math.sqrt(dx * dx + dy * dy) + abs(turn) * body_reach[b] <= speculative:
            continue
        if still.shape[0] == 0:
            keys = near_keys(ci, nc, closest, speculative, n_pieces)
            still = np.zeros((x.shape[0], 2))
        # the step's motion as a straight sweep from the start: a free flight at the mean
        # velocity, no acceleration
        end_x, end_y, end_angle = x[b, 0], x[b, 1], angle[b]
        vx, vy, w = v[b, 0], v[b, 1], omega[b]
        x[b, 0], x[b, 1], angle[b] = x0[b, 0], x0[b, 1], angle0[b]
        v[b, 0], v[b, 1], omega[b] = dx / dt, dy / dt, turn / dt
        touch = np.inf
        for p in range(body_pieces[b], body_pieces[b + 1]):
            place_piece(
                p, x[b, 0], x[b, 1], angle[b], piece_start, piece_count, local_vertices,
                local_normals, vertices, normals,
            )  # fmt: skip
            sweep_box(
                p, vertices, piece_start, piece_count, piece_radius, piece_reach, v[b, 0],
                v[b, 1], omega[b], 0.0, 0.0, dt, False, 0.0, 0.0, box,
            )  # fmt: skip
            found, total = statics_in(box, tree, open_statics, found, filters, p, piece_body)
            for j in range(total):
                q = found[j]
                # a contact near at the start is the solver's: only sinking into it by
                # more than the slop (linear_slop) beyond where it began is a touch
                near, depth = started_sunk(keys, closest, p, q, n_pieces)
                for allow in (depth + slop, depth):
                    # (sunk past the slop: put back where it was as deep as at the start)
                    t = time_of_impact(
                        p, q, b, piece_body[q], dt, 1e-9 * (piece_reach[p] + piece_reach[q]),
                        NEW, x, angle, v, omega, still, piece_start, piece_count,
                        piece_radius, piece_reach, local_vertices, local_normals, vertices,
                        normals, out, ids, allow,
                    )  # fmt: skip
                    if t < 0.0 or not near:
                        break
                if 0.0 <= t < touch:
                    touch = t
        if touch < dt:
            fly(b, touch, x, angle, v, omega, 0.0, 0.0)
            put_back += 1
        else:
            x[b, 0], x[b, 1], angle[b] = end_x, end_y, end_angle
        v[b, 0], v[b, 1], omega[b] = vx, vy, w
    return put_back
