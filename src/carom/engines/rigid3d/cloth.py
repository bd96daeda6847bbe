"""Balls on a level cloth, moved in closed form within the step (the billiards model).

A ball (one sphere, the same moment of inertia ``I = k m R^2`` about every axis) resting on a
level static plane, touching nothing else, is not given to the soft step: its motion over the
step is the closed form of a ball on cloth (Leckie and Greenspan 2005; Kiefl's pooltool,
2024), so it is the same at any rate. With ``n`` the plane's upward normal, gravity ``-g n``,
the contact point at ``-R n`` from the centre and the slip there ``u = v - R w x n``:

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

Who is on the cloth is decided afresh each step (:func:`select`): a ball alone on a level
static plane, touching it (within the islands' ``apart`` of it) and moving along it (its
normal speed within what gravity gives in a step), with no force, torque or joint on it, and a
cloth rough enough to keep it rolling (``c / (R (1 + k)) <= mu``). Anything else near it
(another ball, a cushion, within the step's reach: the contacts are made for the whole step's
motion) makes its island the solver's or the exact path's, as before. Rolling resistance acts
here only while the ball rolls, as in the billiards model; the soft step also applies it while
a ball slides.
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
from carom.engines.stepped.islands import ROLE_CLOTH, ROLE_SOLVER
from carom.engines.stepped.rows import FLAG_EXACT, I_BODY_A, I_BODY_B, I_PIECE_A, I_PIECE_B
from carom.laws.kinds import KIND_DYNAMIC, KIND_STATIC

__all__ = ["roll_all", "select"]

#: a slip below this many ulps of the ball's speeds is round-off: the ball rolls
_ROUND = 64.0 * np.finfo(np.float64).eps
#: the plane is level when gravity's part along it is below this fraction of g
_LEVEL = 1e-12


@njit(cache=True)
def select(
    ci: np.ndarray, cf: np.ndarray, nc: int, closest: np.ndarray, closing: np.ndarray,
    kind: np.ndarray, role: np.ndarray, body_pieces: np.ndarray, piece_kind: np.ndarray,
    piece_vcount: np.ndarray, piece_radius: np.ndarray, mass: np.ndarray, inertia: np.ndarray,
    accel: np.ndarray, pushed: np.ndarray, links: np.ndarray, apart: float, dt: float,
    speculative: float, normals: np.ndarray, piece_fstart: np.ndarray, balls: np.ndarray,
    rows: np.ndarray,
) -> int:  # fmt: skip
    """Give the balls on a level cloth this step ROLE_CLOTH, flag their contact rows solved
    exactly (the solver skips them) and write them to ``balls`` and ``rows``; return how many.

    ``closest``, ``closing`` (nc,) are each contact's least separation [m] and normal speed
    [m/s] (:func:`carom.engines.stepped.islands.plan`'s), ``role`` (N,) the roles it gave,
    ``accel`` (N, 3) each body's acceleration [m/s^2], ``pushed`` (N,) the bodies with a force
    or a torque this step, ``links`` (L, 2) the bodies joints join (module docstring),
    ``normals`` (F, 3) the placed pieces' face normals from ``piece_fstart`` (P,) on.
    ``speculative`` [m] is how far beyond its steady motion a contact is made: friction
    changes a ball's path by at most ``mu g dt^2 / 2`` over the step, which must stay within
    it, so that whatever the ball could reach has a contact (and the ball is not alone).
    """
    n = kind.shape[0]
    count = np.zeros(n, np.int64)
    for m in range(nc):
        for body in (ci[m, I_BODY_A], ci[m, I_BODY_B]):
            if body >= 0:
                count[body] += 1
    for m in range(links.shape[0]):
        for body in (links[m, 0], links[m, 1]):
            if body >= 0:
                count[body] += 1
    found = 0
    for m in range(nc):
        a = ci[m, I_BODY_A]
        b = ci[m, I_BODY_B]
        if a < 0 or b < 0:
            continue
        if kind[a] == KIND_DYNAMIC and kind[b] == KIND_STATIC:
            ball, plane = a, ci[m, I_PIECE_B]
        elif kind[b] == KIND_DYNAMIC and kind[a] == KIND_STATIC:
            ball, plane = b, ci[m, I_PIECE_A]
        else:
            continue
        if role[ball] != ROLE_SOLVER or count[ball] != 1 or pushed[ball]:
            continue
        piece = body_pieces[ball]
        if (
            body_pieces[ball + 1] != piece + 1
            or piece_kind[piece] != PIECE_ROUND
            or piece_vcount[piece] != 1
            or piece_kind[plane] != PIECE_PLANE
        ):
            continue
        k = inertia[ball]
        moment = k[0, 0]
        if (
            k[1, 1] != moment
            or k[2, 2] != moment
            or k[0, 1] != 0.0
            or k[0, 2] != 0.0
            or k[1, 2] != 0.0
        ):
            continue
        f = piece_fstart[plane]  # the plane's upward normal
        nx, ny, nz = normals[f, 0], normals[f, 1], normals[f, 2]
        g = -(accel[ball, 0] * nx + accel[ball, 1] * ny + accel[ball, 2] * nz)
        if not g > 0.0:
            continue
        side = math.sqrt(
            (accel[ball, 0] + g * nx) ** 2
            + (accel[ball, 1] + g * ny) ** 2
            + (accel[ball, 2] + g * nz) ** 2
        )
        if side > _LEVEL * g:
            continue
        if abs(closest[m]) > apart or abs(closing[m]) > g * dt:
            continue
        radius = piece_radius[piece]
        mu = cf[m, F_MU]
        ratio = moment / (mass[ball] * radius * radius)
        if not (mu > 0.0 and cf[m, F_ROLL] <= mu * radius * (1.0 + ratio)):
            continue
        if 0.5 * mu * g * dt * dt > speculative:
            continue  # (friction could take it beyond the contacts made for the step)
        role[ball] = ROLE_CLOTH
        ci[m, I_FLAGS] |= FLAG_EXACT
        balls[found] = ball
        rows[found] = m
        found += 1
    return found


@njit(cache=True, inline="always")
def _cross_n(
    nx: float, ny: float, nz: float, x: float, y: float, z: float
) -> tuple[float, float, float]:
    """``n x (x, y, z)``."""
    return ny * z - nz * y, nz * x - nx * z, nx * y - ny * x


@njit(cache=True)
def roll(
    i: int, dt: float, substeps: int, normal: tuple[float, float, float],
    cloth: tuple[float, float, float, float, float], x: np.ndarray, q: np.ndarray,
    v: np.ndarray, w: np.ndarray, inertia: np.ndarray, inv_inertia: np.ndarray,
) -> None:  # fmt: skip
    """Ball ``i`` on the cloth for ``dt`` [s] in closed form (module docstring): ``normal``
    the plane's upward unit normal, ``cloth`` its ``(g, mu, c, R, k)``: gravity [m/s^2],
    friction [-], rolling resistance [m], the ball's radius [m] and ``I / (m R^2)`` [-].
    Row ``i`` of ``x``, ``v``, ``w`` (N, 3) and ``q`` (N, 4) is changed."""
    nx, ny, nz = normal
    g, mu, c, radius, k = cloth
    moment = inertia[i][0, 0]
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
        bx, by, bz = _cross_n(nx, ny, nz, ex, ey, ez)
        x[i, 0] += t * (vx - 0.5 * t * decel * ex)
        x[i, 1] += t * (vy - 0.5 * t * decel * ey)
        x[i, 2] += t * (vz - 0.5 * t * decel * ez)
        tq = moment * spin_rate
        spin = (ax, ay, az, wn)
        _turn(i, t, substeps, q, w, inertia, inv_inertia, spin, normal, (tq * bx, tq * by, tq * bz))
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
        bx, by, bz = _cross_n(nx, ny, nz, ex, ey, ez)
        x[i, 0] += t * (vx - 0.5 * t * decel * ex)
        x[i, 1] += t * (vy - 0.5 * t * decel * ey)
        x[i, 2] += t * (vz - 0.5 * t * decel * ez)
        spin_rate = -decel / radius  # along n x v^
        tq = moment * spin_rate
        spin = (ax, ay, az, wn)
        _turn(i, t, substeps, q, w, inertia, inv_inertia, spin, normal, (tq * bx, tq * by, tq * bz))
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


@njit(cache=True)
def roll_all(
    balls: np.ndarray, rows: np.ndarray, cf: np.ndarray, ci: np.ndarray, dt: float,
    substeps: int, x: np.ndarray, q: np.ndarray, v: np.ndarray, w: np.ndarray,
    accel: np.ndarray, mass: np.ndarray, inertia: np.ndarray, inv_inertia: np.ndarray,
    body_pieces: np.ndarray, piece_radius: np.ndarray,
    plane_at: tuple[np.ndarray, np.ndarray, np.ndarray],
) -> None:  # fmt: skip
    """The balls ``balls`` (k,) that :func:`select` found, on the cloth of contact ``rows``
    (k,), for ``dt`` [s]: each set on the cloth, its centre a radius from the plane, then
    :func:`roll`; each row's point carries the load ``m g dt`` [N s] as the step's normal
    impulse (what a contact report reads). ``plane_at``: each piece's first placed vertex
    and face normal (V, 3), (F, 3) with its start in them (P, 2): a plane's point and upward
    normal."""
    vertices, normals, starts = plane_at
    for r in range(balls.shape[0]):
        i = balls[r]
        m = rows[r]
        plane = ci[m, I_PIECE_B] if ci[m, I_BODY_A] == i else ci[m, I_PIECE_A]
        f = starts[plane, 1]
        nx, ny, nz = normals[f, 0], normals[f, 1], normals[f, 2]
        p = starts[plane, 0]
        radius = piece_radius[body_pieces[i]]
        gap = (
            nx * (x[i, 0] - vertices[p, 0])
            + ny * (x[i, 1] - vertices[p, 1])
            + nz * (x[i, 2] - vertices[p, 2])
            - radius
        )
        x[i, 0] -= gap * nx
        x[i, 1] -= gap * ny
        x[i, 2] -= gap * nz
        g = -(accel[i, 0] * nx + accel[i, 1] * ny + accel[i, 2] * nz)
        k = inertia[i][0, 0] / (mass[i] * radius * radius)
        roll(
            i, dt, substeps, (nx, ny, nz), (g, cf[m, F_MU], cf[m, F_ROLL], radius, k), x, q, v,
            w, inertia, inv_inertia,
        )  # fmt: skip
        cf[m, point_offset(0) + P_TOTAL] = mass[i] * g * dt
