"""The soft-step contact solver, in named stages (Box2D v3's "solver2d" soft step).

One step of ``dt`` is split into ``n`` substeps of ``h = dt/n``. Each substep integrates
velocities (gravity), warm-starts every contact point with the impulse it ended the last
substep with, solves the contacts once with a soft bias that pushes overlapping bodies apart,
integrates positions, and relaxes once without the bias (so the push leaves no velocity
behind). After the substeps one restitution pass gives contacts that were approaching faster
than the threshold their bounce, and the impulses are stored for the next step.

A contact is a spring-damper of frequency ``f`` and damping ratio ``zeta`` solved implicitly
over the substep (Catto, "Solver2D", 2024): with ``omega = 2 pi f``,
``a1 = 2 zeta + h omega``, ``a2 = h omega a1``, ``a3 = 1/(1 + a2)``, the bias rate is
``omega/a1``, the mass scale ``a2 a3`` and the impulse scale ``a3``. A point still apart
(separation ``s > 0``) is speculative: it only stops the gap from closing faster than
``s/h``. The separation within the step is tracked without new collision tests: the normal
and anchors stay fixed, and ``s = s_0 + (dx_A + R(dtheta_A) r_A - dx_B - R(dtheta_B) r_B) . n
- (r_A - r_B) . n``.

Friction is Coulomb's, ``|j_t| <= mu j_n`` per point, solved after the normal impulse.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.rigid.contacts import (
    F_E,
    F_MU,
    F_NX,
    F_NY,
    I_BODY_A,
    I_BODY_B,
    I_COUNT,
    I_FLAGS,
    P_BASE,
    P_JN,
    P_JT,
    P_NMASS,
    P_RAX,
    P_RAY,
    P_RBX,
    P_RBY,
    P_TMASS,
    P_TOTAL,
    P_VREL,
    point_offset,
)
from carom.engines.rigid.motion import apply_impulse, fixed_work, relative_velocity

__all__ = ["softness", "solve_step"]

FLAG_EXACT = 1  # the contact was solved exactly this step (an isolated impact)


@njit(cache=True)
def softness(hertz: float, zeta: float, h: float) -> tuple[float, float, float]:
    """Bias rate [1/s], mass scale and impulse scale [-] of a soft contact over substep h."""
    omega = 2.0 * math.pi * hertz
    a1 = 2.0 * zeta + h * omega
    a2 = h * omega * a1
    a3 = 1.0 / (1.0 + a2)
    return omega / a1, a2 * a3, a3


@njit(cache=True)
def _prepare(
    cf: np.ndarray, ci: np.ndarray, nc: int, inv_mass: np.ndarray, inv_inertia: np.ndarray
) -> None:
    for m in range(nc):
        if ci[m, I_FLAGS] & FLAG_EXACT:
            continue
        a = ci[m, I_BODY_A]
        b = ci[m, I_BODY_B]
        nx = cf[m, F_NX]
        ny = cf[m, F_NY]
        tx = ny
        ty = -nx
        mass = inv_mass[a] + inv_mass[b]
        for j in range(ci[m, I_COUNT]):
            o = point_offset(j)
            rax = cf[m, o + P_RAX]
            ray = cf[m, o + P_RAY]
            rbx = cf[m, o + P_RBX]
            rby = cf[m, o + P_RBY]
            rna = rax * ny - ray * nx
            rnb = rbx * ny - rby * nx
            k = mass + inv_inertia[a] * rna * rna + inv_inertia[b] * rnb * rnb
            cf[m, o + P_NMASS] = 1.0 / k if k > 0.0 else 0.0
            rta = rax * ty - ray * tx
            rtb = rbx * ty - rby * tx
            k = mass + inv_inertia[a] * rta * rta + inv_inertia[b] * rtb * rtb
            cf[m, o + P_TMASS] = 1.0 / k if k > 0.0 else 0.0
            cf[m, o + P_TOTAL] = 0.0


@njit(cache=True)
def _warm_start(
    cf: np.ndarray,
    ci: np.ndarray,
    nc: int,
    inv_mass: np.ndarray,
    inv_inertia: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    work: np.ndarray,
) -> None:
    for m in range(nc):
        if ci[m, I_FLAGS] & FLAG_EXACT:
            continue
        a = ci[m, I_BODY_A]
        b = ci[m, I_BODY_B]
        nx = cf[m, F_NX]
        ny = cf[m, F_NY]
        fixed = inv_mass[a] == 0.0 or inv_mass[b] == 0.0
        for j in range(ci[m, I_COUNT]):
            o = point_offset(j)
            jn = cf[m, o + P_JN]
            jt = cf[m, o + P_JT]
            px = jn * nx + jt * ny
            py = jn * ny - jt * nx
            cf[m, o + P_TOTAL] += jn
            rax = cf[m, o + P_RAX]
            ray = cf[m, o + P_RAY]
            rbx = cf[m, o + P_RBX]
            rby = cf[m, o + P_RBY]
            if fixed:
                work[0] += fixed_work(a, b, px, py, rax, ray, rbx, rby, inv_mass, v, omega)
            apply_impulse(a, b, px, py, rax, ray, rbx, rby, inv_mass, inv_inertia, v, omega)


@njit(cache=True)
def _solve(
    cf: np.ndarray,
    ci: np.ndarray,
    nc: int,
    inv_mass: np.ndarray,
    inv_inertia: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    dx: np.ndarray,
    turn: np.ndarray,
    inv_h: float,
    use_bias: bool,
    soft_moving: tuple[float, float, float],
    soft_fixed: tuple[float, float, float],
    push_speed: float,
    work: np.ndarray,
) -> None:
    """One Gauss-Seidel pass over the contacts: normal impulses, then friction. ``dx`` (N, 2)
    and ``turn`` (N, 2: cos, sin) are each body's move and turn since the step began;
    ``work[0]`` gathers what kinematic bodies do (:func:`.motion.fixed_work`)."""
    for m in range(nc):
        if ci[m, I_FLAGS] & FLAG_EXACT:
            continue
        a = ci[m, I_BODY_A]
        b = ci[m, I_BODY_B]
        nx = cf[m, F_NX]
        ny = cf[m, F_NY]
        fixed = inv_mass[a] == 0.0 or inv_mass[b] == 0.0
        rate, mass_scale, impulse_scale = soft_fixed if fixed else soft_moving
        ca = turn[a, 0]
        sa = turn[a, 1]
        cb = turn[b, 0]
        sb = turn[b, 1]
        ddx = dx[a, 0] - dx[b, 0]
        ddy = dx[a, 1] - dx[b, 1]
        count = ci[m, I_COUNT]
        for j in range(count):
            o = point_offset(j)
            rax = cf[m, o + P_RAX]
            ray = cf[m, o + P_RAY]
            rbx = cf[m, o + P_RBX]
            rby = cf[m, o + P_RBY]
            # the separation now: anchors turned by each body's turn since the step began
            sx = ddx + (ca * rax - sa * ray) - (cb * rbx - sb * rby)
            sy = ddy + (sa * rax + ca * ray) - (sb * rbx + cb * rby)
            s = cf[m, o + P_BASE] + sx * nx + sy * ny
            bias = 0.0
            ms = 1.0
            isc = 0.0
            if s > 0.0:
                bias = s * inv_h  # speculative: close the gap, no more
            elif use_bias:
                bias = max(mass_scale * rate * s, -push_speed)
                ms = mass_scale
                isc = impulse_scale
            ux, uy = relative_velocity(a, b, rax, ray, rbx, rby, v, omega)
            un = ux * nx + uy * ny
            jn = cf[m, o + P_JN]
            dj = -cf[m, o + P_NMASS] * (ms * un + bias) - isc * jn
            new = max(jn + dj, 0.0)
            dj = new - jn
            cf[m, o + P_JN] = new
            cf[m, o + P_TOTAL] += dj
            if fixed:
                work[0] += fixed_work(
                    a, b, dj * nx, dj * ny, rax, ray, rbx, rby, inv_mass, v, omega
                )
            apply_impulse(
                a, b, dj * nx, dj * ny, rax, ray, rbx, rby, inv_mass, inv_inertia, v, omega
            )
        mu = cf[m, F_MU]
        if mu == 0.0:
            continue
        tx = ny
        ty = -nx
        for j in range(count):
            o = point_offset(j)
            rax = cf[m, o + P_RAX]
            ray = cf[m, o + P_RAY]
            rbx = cf[m, o + P_RBX]
            rby = cf[m, o + P_RBY]
            ux, uy = relative_velocity(a, b, rax, ray, rbx, rby, v, omega)
            ut = ux * tx + uy * ty
            jt = cf[m, o + P_JT]
            limit = mu * cf[m, o + P_JN]
            new = min(max(jt - cf[m, o + P_TMASS] * ut, -limit), limit)
            dj = new - jt
            cf[m, o + P_JT] = new
            if fixed:
                work[0] += fixed_work(
                    a, b, dj * tx, dj * ty, rax, ray, rbx, rby, inv_mass, v, omega
                )
            apply_impulse(
                a, b, dj * tx, dj * ty, rax, ray, rbx, rby, inv_mass, inv_inertia, v, omega
            )


@njit(cache=True)
def _restitution(
    cf: np.ndarray,
    ci: np.ndarray,
    nc: int,
    threshold: float,
    inv_mass: np.ndarray,
    inv_inertia: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    work: np.ndarray,
) -> None:
    """Points that approached faster than ``threshold`` and were pushed leave at ``-e`` times
    their approach speed (Newton's restitution, per point, in order)."""
    for m in range(nc):
        if ci[m, I_FLAGS] & FLAG_EXACT:
            continue
        e = cf[m, F_E]
        if e == 0.0:
            continue
        a = ci[m, I_BODY_A]
        b = ci[m, I_BODY_B]
        nx = cf[m, F_NX]
        ny = cf[m, F_NY]
        for j in range(ci[m, I_COUNT]):
            o = point_offset(j)
            if cf[m, o + P_VREL] > -threshold or cf[m, o + P_TOTAL] == 0.0:
                continue
            rax = cf[m, o + P_RAX]
            ray = cf[m, o + P_RAY]
            rbx = cf[m, o + P_RBX]
            rby = cf[m, o + P_RBY]
            ux, uy = relative_velocity(a, b, rax, ray, rbx, rby, v, omega)
            un = ux * nx + uy * ny
            jn = cf[m, o + P_JN]
            dj = -cf[m, o + P_NMASS] * (un + e * cf[m, o + P_VREL])
            new = max(jn + dj, 0.0)
            dj = new - jn
            cf[m, o + P_JN] = new
            cf[m, o + P_TOTAL] += dj
            work[0] += fixed_work(a, b, dj * nx, dj * ny, rax, ray, rbx, rby, inv_mass, v, omega)
            apply_impulse(
                a, b, dj * nx, dj * ny, rax, ray, rbx, rby, inv_mass, inv_inertia, v, omega
            )


@njit(cache=True)
def solve_step(
    cf: np.ndarray,
    ci: np.ndarray,
    nc: int,
    bodies: np.ndarray,
    inv_mass: np.ndarray,
    inv_inertia: np.ndarray,
    gravity_on: np.ndarray,
    x: np.ndarray,
    angle: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    gx: float,
    gy: float,
    dt: float,
    substeps: int,
    contact_hertz: float,
    damping_ratio: float,
    push_speed: float,
    restitution_threshold: float,
    work: np.ndarray,
) -> None:
    """Advance the ``bodies`` (indices) and their contacts by one step ``dt`` [s].

    Contacts flagged exact are skipped; every other contact must join bodies of ``bodies``
    or a body that does not move under impulses (static, kinematic, asleep: infinite mass).
    ``work[0]`` gains the work kinematic bodies did on the others [J].
    """
    h = dt / substeps
    hertz = min(contact_hertz, 0.25 / h)
    soft_moving = softness(hertz, damping_ratio, h)
    soft_fixed = softness(2.0 * hertz, damping_ratio, h)
    n = x.shape[0]
    dx = np.zeros((n, 2))
    dtheta = np.zeros(n)
    turn = np.zeros((n, 2))
    turn[:, 0] = 1.0
    _prepare(cf, ci, nc, inv_mass, inv_inertia)
    for _ in range(substeps):
        for i in bodies:
            if gravity_on[i]:
                v[i, 0] += h * gx
                v[i, 1] += h * gy
        _warm_start(cf, ci, nc, inv_mass, inv_inertia, v, omega, work)
        _solve(
            cf,
            ci,
            nc,
            inv_mass,
            inv_inertia,
            v,
            omega,
            dx,
            turn,
            1.0 / h,
            True,
            soft_moving,
            soft_fixed,
            push_speed,
            work,
        )
        for i in bodies:
            x[i, 0] += h * v[i, 0]
            x[i, 1] += h * v[i, 1]
            angle[i] += h * omega[i]
            dx[i, 0] += h * v[i, 0]
            dx[i, 1] += h * v[i, 1]
            dtheta[i] += h * omega[i]
            # each body's turn since the step began, once per substep (not per contact)
            turn[i, 0] = math.cos(dtheta[i])
            turn[i, 1] = math.sin(dtheta[i])
        _solve(
            cf,
            ci,
            nc,
            inv_mass,
            inv_inertia,
            v,
            omega,
            dx,
            turn,
            1.0 / h,
            False,
            soft_moving,
            soft_fixed,
            push_speed,
            work,
        )
    _restitution(cf, ci, nc, restitution_threshold, inv_mass, inv_inertia, v, omega, work)
