"""Balls on a level cloth, moved in closed form within the step (the billiards model).

A ball (one sphere, the same moment of inertia ``I = k m R^2`` about every axis) resting on a
level static plane is not given to the soft step: its motion over the step is the closed form
of a ball on cloth (Leckie and Greenspan 2005; Kiefl's pooltool, 2024), so it is the same at
any rate. With ``n`` the plane's upward normal, gravity ``-g n``, the contact point at
``-R n`` from the centre and the slip there ``u = v - R w x n``:

- **sliding** (``u != 0``): friction ``mu m g`` against the slip. ``dv/dt = -mu g u^``,
  ``dw/dt = (mu g / (k R)) n x u^``, so ``du/dt = -mu g (1 + 1/k) u^``: the slip keeps its
  direction and shrinks at a steady rate until ``t_s = |u| / (mu g (1 + 1/k))``
  (``2 |u| / (7 mu g)`` for a solid ball). The spin about ``n`` is not changed;
- **rolling** (``u = 0``): the rolling resistance ``c`` [m] (a torque ``c m g`` against the
  roll, :class:`carom.Material`) slows the ball at ``a = c g / (R (1 + k))``, still rolling,
  until it stops at ``|v| / a``;
- **at rest**: no motion in the plane; the spin about ``n`` goes on (carom has no spinning
  friction).

Positions follow from the velocities (each phase's is quadratic in time), spins in the plane
from the rolling condition. The orientation (which a ball's motion does not depend on) turns
under each phase's steady angular acceleration (:func:`.motion.turn_under`).

The plane holds the ball, touching it: the ball is set on its surface (a ball that came to
rest in the soft step had sunk by its static deflection, ``g / omega^2``, 0.07 mm at the
default stiffness), its normal velocity (a round-off of the resting contact) is dropped, and
the ledger books the energy of both, as it books the friction's. Every ball on the cloth is
then at the same height, so two that meet do so along a level normal.

Who is on the cloth is decided afresh each step (:func:`candidates`): a ball on a level static
plane, touching it (within the islands' ``apart`` of it) and moving along it (not falling
faster than gravity makes it in a step, not leaving faster than a hop that stays within
``apart``), with no force, torque or joint on it, and a cloth rough enough to keep it rolling
(``c / (R (1 + k)) <= mu``). Its cloth is then left out of the islands
(:func:`carom.engines.stepped.islands.plan`): a ball with nothing else near rolls alone
(:func:`roll_all`); balls about to meet each other or a cushion (their contacts apart, or
closing or leaving fast) are an island solved exactly (:mod:`.impacts`), which rolls them in
closed form between impacts, meets two balls by :func:`carom.collide`'s law
(:func:`ball_impact`) and a ball and a cushion at the cushion's nose. A ball resting against
another or against a cushion, or touching anything else, stays with the soft step. Rolling
resistance acts here only while the ball rolls, as in the billiards model; the soft step also
applies it while a ball slides.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.rigid3d.contacts import (
    F_MU,
    F_ROLL,
    I_FLAGS,
    P_TOTAL,
    point_offset,
)
from carom.engines.rigid3d.model import PIECE_PLANE, PIECE_ROUND
from carom.engines.rigid3d.motion import turn_under
from carom.engines.stepped.rows import FLAG_EXACT, I_BODY_A, I_BODY_B, I_PIECE_A, I_PIECE_B
from carom.laws.batch import (
    IN_BETA,
    IN_E,
    IN_FRICTION,
    IN_M1,
    IN_M2,
    IN_R1,
    IN_R2,
    IN_ROWS,
    IN_V1,
    IN_V2,
    IN_W1,
    IN_W2,
    IN_X1,
    IN_X2,
    OUT_APPLIED,
    OUT_APPROACH,
    OUT_J,
    OUT_KE_AFTER,
    OUT_KE_BEFORE,
    OUT_N,
    OUT_ROWS,
    OUT_SEPARATION,
    OUT_V1,
    OUT_V2,
    OUT_W1,
    OUT_W2,
    law_block,
)
from carom.laws.kernels import LAW_WALTON
from carom.laws.kinds import KIND_DYNAMIC, KIND_KINEMATIC, KIND_STATIC

__all__ = [
    "SUPPORT",
    "ball_impact",
    "ball_shaped",
    "candidates",
    "loaded",
    "roll",
    "roll_all",
    "seat",
]

#: a slip below this many ulps of the ball's speeds is round-off: the ball rolls
_ROUND = 64.0 * np.finfo(np.float64).eps
#: a face is level when its unit normal is within this of gravity's upward direction
_LEVEL = 1e-12


def ball_shaped(
    kind: np.ndarray, body_pieces: np.ndarray, piece_kind: np.ndarray,
    piece_vcount: np.ndarray, inertia: np.ndarray,
) -> np.ndarray:  # fmt: skip
    """Which bodies (N,) bool could roll on a cloth: dynamic, one sphere (a round piece of one
    corner), the same moment of inertia about every axis (fixed for an engine's life: its
    driver asks once)."""
    one = np.diff(body_pieces) == 1
    first = np.minimum(body_pieces[:-1], max(piece_kind.shape[0] - 1, 0))
    sphere = one & (piece_kind[first] == PIECE_ROUND) & (piece_vcount[first] == 1)
    diagonal = inertia[:, [0, 1, 2], [0, 1, 2]]
    isotropic = (diagonal == diagonal[:, :1]).all(axis=1)
    isotropic &= (inertia[:, 0, 1] == 0.0) & (inertia[:, 0, 2] == 0.0)
    isotropic &= inertia[:, 1, 2] == 0.0
    shaped: np.ndarray = (kind == KIND_DYNAMIC) & sphere & isotropic
    return shaped


#: columns of a ball's cloth (:func:`candidates`'s ``support``): its upward unit normal (3), a
#: point of it (3) [m], gravity across it g [m/s^2], friction mu [-], rolling resistance c [m],
#: the ball's radius R [m] and I / (m R^2) [-]
S_NORMAL, S_POINT, S_G, S_MU, S_ROLL, S_RADIUS, S_RATIO = 0, 3, 6, 7, 8, 9, 10
SUPPORT = 11


@njit(cache=True)
def candidates(
    ci: np.ndarray, cf: np.ndarray, nc: int, closest: np.ndarray, closing: np.ndarray,
    kind: np.ndarray, awake: np.ndarray, shaped: np.ndarray, body_pieces: np.ndarray,
    piece_kind: np.ndarray, piece_radius: np.ndarray, mass: np.ndarray, inertia: np.ndarray,
    accel: np.ndarray, pushed: np.ndarray, links: np.ndarray,
    limits: tuple[float, float, float, float, float], x: np.ndarray, v: np.ndarray,
    placed: tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
        np.ndarray, np.ndarray,
    ], skip: np.ndarray, held: np.ndarray, support: np.ndarray,
) -> int:  # fmt: skip
    """Find the balls on a level cloth this step; return how many.

    Each gets ``held[i]`` = (its cloth's contact row, the cloth's piece) (-1, -1 for every
    other body), ``support[i]`` its cloth (columns ``S_*``), and its cloth's row is marked in
    ``skip`` (nc,): :func:`carom.engines.stepped.islands.plan` leaves it out, so that a ball
    with nothing else near is free (and rolls, :func:`roll_all`) and balls about to meet are
    an island solved exactly (:mod:`.impacts`, which rolls them between impacts).

    A ball is on the cloth when (module docstring):

    - the only static body it rests on is a level face of a static piece (a plane, or a
      polytope's face its contact point cannot leave within the step), touching it
      (within ``apart``), not falling faster than a step of gravity gives nor leaving faster
      than a hop within ``apart``; the cloth rough enough to keep it rolling
      (``c <= mu R (1 + k)``) and ``mu g dt^2 / 2`` within ``speculative``: the contacts are
      made for the step's steady motion, and friction must not take the ball beyond them;
    - it is awake, no force, torque (``pushed`` (N,)) or joint (``links`` (L, 2)) acts on it;
    - every other contact it has is an impact still to happen (apart, closing faster than
      ``fast`` or leaving faster than ``leaving``: the islands' test), with a static body (a
      cushion: the exact path meets it) or with a ball on the cloth: balls resting against
      each other or on a cushion are the solver's, and so is a ball touching a kinematic body
      or a dynamic one that is not a ball.

    ``closest``, ``closing`` (nc,): each contact's least separation [m] and normal speed
    [m/s]; ``shaped`` (N,): :func:`ball_shaped`; ``accel`` (N, 3) [m/s^2]; ``limits``:
    ``(apart, fast, leaving, dt, speculative)``; ``placed``: the placed pieces' vertices
    (V, 3) and face normals (F, 3), and the model's ``piece_vstart``, ``piece_fstart``,
    ``piece_fcount``, ``piece_cstart``, ``face_first``, ``face_size`` and ``corners``
    (:class:`.model.Model3D`).
    """
    apart, fast, leaving, dt, speculative = limits
    n = kind.shape[0]
    others = np.zeros(n, np.int64)  # contacts with anything not dynamic
    barred = np.zeros(n, np.bool_)
    for i in range(n):
        held[i, 0] = -1
        held[i, 1] = -1
    for m in range(links.shape[0]):
        for body in (links[m, 0], links[m, 1]):
            if body >= 0:
                barred[body] = True
    for m in range(nc):
        skip[m] = False
        a = ci[m, I_BODY_A]
        b = ci[m, I_BODY_B]
        resting = closest[m] <= apart and -fast <= closing[m] <= leaving
        for body, other in ((a, b), (b, a)):
            if body < 0 or not shaped[body]:
                continue
            if other < 0 or kind[other] == KIND_KINEMATIC:
                barred[body] = True
            elif kind[other] == KIND_STATIC:
                if resting:  # (a cushion ahead is an impact still to happen)
                    others[body] += 1
            elif not shaped[other] or resting:
                barred[body] = True  # touching a body that is not a ball, or resting on one
    for m in range(nc):
        a = ci[m, I_BODY_A]
        b = ci[m, I_BODY_B]
        if a < 0 or b < 0:
            continue
        if shaped[a] and kind[b] == KIND_STATIC:
            ball, plane = a, ci[m, I_PIECE_B]
        elif shaped[b] and kind[a] == KIND_STATIC:
            ball, plane = b, ci[m, I_PIECE_A]
        else:
            continue
        if barred[ball] or others[ball] != 1 or pushed[ball] or not awake[ball]:
            continue
        if piece_kind[plane] == PIECE_ROUND:
            continue
        piece = body_pieces[ball]
        moment = inertia[ball][0, 0]
        g = math.sqrt(accel[ball, 0] ** 2 + accel[ball, 1] ** 2 + accel[ball, 2] ** 2)
        # touching, not falling faster than a step of gravity gives, and not leaving faster
        # than a hop that would stay within the touching distance (``u^2 / 2g <= apart``)
        if not g > 0.0 or abs(closest[m]) > apart or closing[m] < -g * dt:
            continue
        if closing[m] > 0.0 and closing[m] * closing[m] > 2.0 * g * apart:
            continue
        radius = piece_radius[piece]
        mu = cf[m, F_MU]
        # how far the contact point can go over the step
        reach = dt * math.sqrt(v[ball, 0] ** 2 + v[ball, 1] ** 2 + v[ball, 2] ** 2)
        reach += mu * g * dt * dt + apart
        up = (-accel[ball, 0] / g, -accel[ball, 1] / g, -accel[ball, 2] / g)
        if not _level_face(plane, up, (x[ball, 0], x[ball, 1], x[ball, 2]), radius, reach,
                           piece_kind, placed, support[ball]):  # fmt: skip
            continue
        ratio = moment / (mass[ball] * radius * radius)
        if not (mu > 0.0 and cf[m, F_ROLL] <= mu * radius * (1.0 + ratio)):
            continue
        if 0.5 * mu * g * dt * dt > speculative:
            continue  # (friction could take it beyond the contacts made for the step)
        held[ball, 0] = m
        held[ball, 1] = plane
        support[ball, S_G] = g
        support[ball, S_MU] = mu
        support[ball, S_ROLL] = cf[m, F_ROLL]
        support[ball, S_RADIUS] = radius
        support[ball, S_RATIO] = ratio
    # a ball whose partner is not on the cloth leaves it too (the pair is the solver's)
    changed = True
    while changed:
        changed = False
        for m in range(nc):
            a = ci[m, I_BODY_A]
            b = ci[m, I_BODY_B]
            if a < 0 or b < 0 or kind[a] != KIND_DYNAMIC or kind[b] != KIND_DYNAMIC:
                continue
            if (held[a, 0] >= 0) != (held[b, 0] >= 0):
                for body in (a, b):
                    held[body, 0] = -1
                    held[body, 1] = -1
                changed = True
    found = 0
    for i in range(n):
        if held[i, 0] >= 0:
            skip[held[i, 0]] = True
            found += 1
    return found


@njit(cache=True)
def _level_face(
    plane: int, up: tuple[float, float, float], centre: tuple[float, float, float],
    radius: float, reach: float, piece_kind: np.ndarray, placed: tuple[
        np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray,
        np.ndarray, np.ndarray,
    ], out: np.ndarray,
) -> bool:  # fmt: skip
    """Whether static piece ``plane`` holds the ball at ``centre`` on a level face (its
    outward normal ``up`` within :data:`_LEVEL`) that its contact point stays on while it
    moves up to ``reach`` [m]; if so, ``out`` (6,) gets the face's normal and a point of it."""
    vertices, normals, vstart, fstart, fcount, cstart, face_first, face_size, corners = placed
    flat = piece_kind[plane] == PIECE_PLANE  # (a plane: one face, its point the vertex)
    best = -1
    nearest = np.inf
    for f in range(fstart[plane], fstart[plane] + (1 if flat else fcount[plane])):
        tilt = (normals[f, 0] - up[0]) ** 2 + (normals[f, 1] - up[1]) ** 2
        tilt += (normals[f, 2] - up[2]) ** 2
        if tilt > _LEVEL * _LEVEL:
            continue
        c = vstart[plane] + (0 if flat else corners[cstart[plane] + face_first[f]])
        height = (
            normals[f, 0] * (centre[0] - vertices[c, 0])
            + normals[f, 1] * (centre[1] - vertices[c, 1])
            + normals[f, 2] * (centre[2] - vertices[c, 2])
        )
        if abs(height - radius) < nearest:
            nearest = abs(height - radius)
            best = f
    if best < 0:
        return False
    f = best
    nx, ny, nz = normals[f, 0], normals[f, 1], normals[f, 2]
    if flat:
        c = vstart[plane]
    else:
        # the face is a convex polygon, counter-clockwise seen from outside: the ball's
        # contact point must stay within it by the reach
        first = cstart[plane] + face_first[f]
        size = face_size[f]
        for j in range(size):
            a = vstart[plane] + corners[first + j]
            b = vstart[plane] + corners[first + (j + 1 if j + 1 < size else 0)]
            ex = vertices[b, 0] - vertices[a, 0]
            ey = vertices[b, 1] - vertices[a, 1]
            ez = vertices[b, 2] - vertices[a, 2]
            ix, iy, iz = _cross_n(nx, ny, nz, ex, ey, ez)  # along the face, inwards
            size_i = math.sqrt(ix * ix + iy * iy + iz * iz)
            inside = (
                ix * (centre[0] - vertices[a, 0])
                + iy * (centre[1] - vertices[a, 1])
                + iz * (centre[2] - vertices[a, 2])
            ) / size_i
            if not inside > reach:
                return False
        c = vstart[plane] + corners[first]
    out[0], out[1], out[2] = nx, ny, nz
    out[3], out[4], out[5] = vertices[c, 0], vertices[c, 1], vertices[c, 2]
    return True


@njit(cache=True, inline="always")
def _cross_n(
    nx: float, ny: float, nz: float, x: float, y: float, z: float
) -> tuple[float, float, float]:
    """``n x (x, y, z)``."""
    return ny * z - nz * y, nz * x - nx * z, nx * y - ny * x


@njit(cache=True)
def roll(
    i: int, dt: float, substeps: int, cloth: np.ndarray, x: np.ndarray, q: np.ndarray,
    v: np.ndarray, w: np.ndarray, inertia: np.ndarray, inv_inertia: np.ndarray,
) -> None:  # fmt: skip
    """Ball ``i`` on the cloth for ``dt`` [s] in closed form (module docstring); ``cloth``
    (:data:`SUPPORT`,) its cloth (columns ``S_*``: the upward unit normal, gravity, friction,
    rolling resistance, the ball's radius and ``I / (m R^2)``). Row ``i`` of ``x``, ``v``,
    ``w`` (N, 3) and ``q`` (N, 4) is changed; a velocity across the cloth is dropped (the
    cloth holds the ball)."""
    nx, ny, nz = cloth[S_NORMAL], cloth[S_NORMAL + 1], cloth[S_NORMAL + 2]
    normal = (nx, ny, nz)
    g, mu, c = cloth[S_G], cloth[S_MU], cloth[S_ROLL]
    radius, k = cloth[S_RADIUS], cloth[S_RATIO]
    vn = v[i, 0] * nx + v[i, 1] * ny + v[i, 2] * nz
    vx, vy, vz = v[i, 0] - vn * nx, v[i, 1] - vn * ny, v[i, 2] - vn * nz
    wn = w[i, 0] * nx + w[i, 1] * ny + w[i, 2] * nz
    ax, ay, az = w[i, 0] - wn * nx, w[i, 1] - wn * ny, w[i, 2] - wn * nz  # the spin in the plane
    left = dt
    # the slip u = v - R w x n = v + R n x w
    cx, cy, cz = _cross_n(nx, ny, nz, ax, ay, az)
    ux, uy, uz = vx + radius * cx, vy + radius * cy, vz + radius * cz
    slip = math.sqrt(ux * ux + uy * uy + uz * uz)
    scale = math.sqrt(vx * vx + vy * vy + vz * vz) + radius * math.sqrt(ax * ax + ay * ay + az * az)
    if slip > _ROUND * scale:
        # sliding: the slip shrinks along its own direction at mu g (1 + 1/k)
        ex, ey, ez = ux / slip, uy / slip, uz / slip
        t_slide = slip / (mu * g * (1.0 + 1.0 / k))
        t = min(left, t_slide)
        decel = mu * g
        spin_rate = mu * g / (k * radius)  # |dw/dt|, along n x u^
        _phase(i, t, substeps, x, q, w, inertia, inv_inertia, (vx, vy, vz), (ex, ey, ez),
               decel, spin_rate, (ax, ay, az, wn), normal)  # fmt: skip
        bx, by, bz = _cross_n(nx, ny, nz, ex, ey, ez)
        vx -= t * decel * ex
        vy -= t * decel * ey
        vz -= t * decel * ez
        ax += t * spin_rate * bx
        ay += t * spin_rate * by
        az += t * spin_rate * bz
        left -= t
        if t < t_slide:
            _write(i, v, w, (vx, vy, vz), (ax, ay, az), wn, normal)
            return
    # rolling: the spin in the plane is the rolling one, w = n x v / R
    ax, ay, az = _cross_n(nx, ny, nz, vx / radius, vy / radius, vz / radius)
    speed = math.sqrt(vx * vx + vy * vy + vz * vz)
    if left > 0.0 and speed > 0.0:
        ex, ey, ez = vx / speed, vy / speed, vz / speed
        decel = c * g / (radius * (1.0 + k))
        t_roll = speed / decel if decel > 0.0 else np.inf
        t = min(left, t_roll)
        # the spin in the plane follows the roll: -decel / R along n x v^
        _phase(i, t, substeps, x, q, w, inertia, inv_inertia, (vx, vy, vz), (ex, ey, ez),
               decel, -decel / radius, (ax, ay, az, wn), normal)  # fmt: skip
        left -= t
        if t < t_roll:
            vx -= t * decel * ex
            vy -= t * decel * ey
            vz -= t * decel * ez
            ax, ay, az = _cross_n(nx, ny, nz, vx / radius, vy / radius, vz / radius)
        else:
            vx = vy = vz = 0.0
            ax = ay = az = 0.0
    if left > 0.0:  # at rest on the cloth: only the spin about n, steady
        spin = (ax, ay, az, wn)
        _turn(i, left, substeps, q, w, inertia, inv_inertia, spin, normal, (0.0, 0.0, 0.0))
    _write(i, v, w, (vx, vy, vz), (ax, ay, az), wn, normal)


@njit(cache=True, inline="always")
def _phase(
    i: int, t: float, substeps: int, x: np.ndarray, q: np.ndarray, w: np.ndarray,
    inertia: np.ndarray, inv_inertia: np.ndarray, lin: tuple[float, float, float],
    along: tuple[float, float, float], decel: float, spin_rate: float,
    spin: tuple[float, float, float, float], normal: tuple[float, float, float],
) -> None:  # fmt: skip
    """One phase of ``t`` [s]: ball ``i``'s centre moves from velocity ``lin`` slowing at
    ``decel`` [m/s^2] along ``-along``, and it turns from ``spin`` (in the plane, then about the
    normal) with its spin changing at ``spin_rate`` [rad/s^2] along ``n x along``."""
    ex, ey, ez = along
    x[i, 0] += t * (lin[0] - 0.5 * t * decel * ex)
    x[i, 1] += t * (lin[1] - 0.5 * t * decel * ey)
    x[i, 2] += t * (lin[2] - 0.5 * t * decel * ez)
    bx, by, bz = _cross_n(normal[0], normal[1], normal[2], ex, ey, ez)
    tq = inertia[i][0, 0] * spin_rate
    _turn(i, t, substeps, q, w, inertia, inv_inertia, spin, normal, (tq * bx, tq * by, tq * bz))


@njit(cache=True, inline="always")
def _write(
    i: int, v: np.ndarray, w: np.ndarray, lin: tuple[float, float, float],
    plane_spin: tuple[float, float, float], wn: float, normal: tuple[float, float, float],
) -> None:  # fmt: skip
    """Ball ``i``'s velocity and spin (in the plane, and ``wn`` about the normal)."""
    v[i, 0], v[i, 1], v[i, 2] = lin
    w[i, 0] = plane_spin[0] + wn * normal[0]
    w[i, 1] = plane_spin[1] + wn * normal[1]
    w[i, 2] = plane_spin[2] + wn * normal[2]


@njit(cache=True, inline="always")
def _turn(
    i: int, t: float, substeps: int, q: np.ndarray, w: np.ndarray, inertia: np.ndarray,
    inv_inertia: np.ndarray, spin: tuple[float, float, float, float],
    normal: tuple[float, float, float], torque: tuple[float, float, float],
) -> None:  # fmt: skip
    """Turn ball ``i``'s orientation over a phase of ``t`` [s] that starts with the spin
    ``spin`` (in the plane, then about the normal) under the steady ``torque`` [N m]."""
    w[i, 0] = spin[0] + spin[3] * normal[0]
    w[i, 1] = spin[1] + spin[3] * normal[1]
    w[i, 2] = spin[2] + spin[3] * normal[2]
    turn_under(i, t, substeps, q, w, inertia, inv_inertia, torque[0], torque[1], torque[2])


@njit(cache=True, inline="always")
def seat(i: int, cloth: np.ndarray, x: np.ndarray) -> None:
    """Set ball ``i`` on its cloth (``cloth``: :data:`SUPPORT`,): its centre a radius from
    the cloth's plane, along the normal."""
    nx, ny, nz = cloth[S_NORMAL], cloth[S_NORMAL + 1], cloth[S_NORMAL + 2]
    gap = (
        nx * (x[i, 0] - cloth[S_POINT])
        + ny * (x[i, 1] - cloth[S_POINT + 1])
        + nz * (x[i, 2] - cloth[S_POINT + 2])
        - cloth[S_RADIUS]
    )
    x[i, 0] -= gap * nx
    x[i, 1] -= gap * ny
    x[i, 2] -= gap * nz


@njit(cache=True)
def roll_all(
    balls: np.ndarray, held: np.ndarray, support: np.ndarray, ci: np.ndarray, cf: np.ndarray,
    dt: float,
    substeps: int, x: np.ndarray, q: np.ndarray, v: np.ndarray, w: np.ndarray,
    mass: np.ndarray, inertia: np.ndarray, inv_inertia: np.ndarray,
) -> None:  # fmt: skip
    """The balls ``balls`` (k,) that :func:`candidates` found alone on their cloth
    (``held``, ``support``), for ``dt`` [s]: each set on the cloth (:func:`seat`), then
    :func:`roll`."""
    for r in range(balls.shape[0]):
        i = balls[r]
        seat(i, support[i], x)
        roll(i, dt, substeps, support[i], x, q, v, w, inertia, inv_inertia)
    loaded(balls, held, support, ci, cf, dt, mass)


@njit(cache=True)
def loaded(
    balls: np.ndarray, held: np.ndarray, support: np.ndarray, ci: np.ndarray, cf: np.ndarray,
    dt: float, mass: np.ndarray,
) -> None:  # fmt: skip
    """Flag the cloth rows of ``balls`` (k,) solved exactly (the solver skips them), and give
    each row's point the load ``m g dt`` [N s] as the step's normal impulse (what a contact
    report reads)."""
    for r in range(balls.shape[0]):
        i = balls[r]
        m = held[i, 0]
        ci[m, I_FLAGS] |= FLAG_EXACT
        cf[m, point_offset(0) + P_TOTAL] = mass[i] * support[i, S_G] * dt


@njit(cache=True)
def ball_impact(
    a: int,
    b: int,
    support: np.ndarray,
    e: float,
    mu: float,
    x: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    mass: np.ndarray,
    record: np.ndarray,
) -> bool:
    """The impact of balls ``a`` and ``b`` on the cloth, touching now: :func:`carom.collide`'s,
    the same arithmetic (:func:`carom.laws.batch.law_block`, one pair): Walton's law with
    Coulomb friction ``mu`` [-] and no sticking restitution (a smooth one when ``mu`` is 0: the
    same bits), restitution ``e`` [-], the balls' masses, radii and ``I / (m R^2)``. Their
    velocities and spins (N, 3) are set to its results; ``record`` (:data:`.impacts.IMPACT_FIELDS`,)
    gets the impact (columns 1 to 15). Returns False, changing nothing, when they do not
    approach.

    The impulse's part across the cloth (friction's, from topspin or draw: at most
    ``mu (1 + e) / 2`` of the approach speed) is the cloth's to answer: the balls stay on it,
    and :func:`roll` drops the velocity across it, as pooltool does (module docstring)."""
    s = np.zeros((IN_ROWS, 1))
    o = np.empty((OUT_ROWS, 1))
    for c in range(3):
        s[IN_X1 + c, 0] = x[a, c]
        s[IN_X2 + c, 0] = x[b, c]
        s[IN_V1 + c, 0] = v[a, c]
        s[IN_V2 + c, 0] = v[b, c]
        s[IN_W1 + c, 0] = w[a, c]
        s[IN_W2 + c, 0] = w[b, c]
    s[IN_M1, 0] = mass[a]
    s[IN_M2, 0] = mass[b]
    s[IN_E, 0] = e
    s[IN_R1, 0] = support[a, S_RADIUS]
    s[IN_R2, 0] = support[b, S_RADIUS]
    s[IN_BETA, 0] = 0.0
    s[IN_FRICTION, 0] = mu
    law_block(s, o, 1, True, LAW_WALTON, True, support[a, S_RATIO], support[b, S_RATIO])
    if o[OUT_APPLIED, 0] == 0.0:
        return False
    for c in range(3):
        v[a, c] = o[OUT_V1 + c, 0]
        v[b, c] = o[OUT_V2 + c, 0]
        w[a, c] = o[OUT_W1 + c, 0]
        w[b, c] = o[OUT_W2 + c, 0]
        record[3 + c] = o[OUT_J + c, 0]
        record[8 + c] = x[a, c] - support[a, S_RADIUS] * o[OUT_N + c, 0]
        record[13 + c] = o[OUT_N + c, 0]
    record[1] = a
    record[2] = b
    record[6] = -o[OUT_APPROACH, 0]
    record[7] = o[OUT_SEPARATION, 0]
    record[11] = o[OUT_KE_BEFORE, 0] - o[OUT_KE_AFTER, 0]
    record[12] = 0.0
    return True
