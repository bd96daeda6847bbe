"""The soft-step contact solver in 3D, in the 2D engine's named stages
(:mod:`carom.engines.rigid.solver`; Box2D v3's soft step, Catto 2024).

One step of ``dt`` is split into ``n`` substeps of ``h = dt/n``. Each substep **integrates
velocities** (gravity),
**warm-starts** every contact point with the impulse it ended the last substep with, **solves**
the contacts once with a soft bias that pushes overlapping bodies apart, **integrates
positions** (the centre by ``h v``; the orientation turned torque-free with its angular
momentum kept, :func:`.motion.free_turn`, which carries the gyroscopic term), and **relaxes**
once without the bias. After the substeps one **restitution** pass gives contacts that were
approaching faster than the threshold their bounce.

A contact point is a spring-damper (frequency ``f``, damping ratio ``zeta``) solved implicitly
over the substep, as in 2D; a point still apart is speculative and only stops the gap from
closing faster than ``s/h``. The separation within the step needs no new collision test: the
normal and anchors stay fixed, and ``s = base + (dx_A + dR_A c_A - dx_B - dR_B c_B) . n`` with
``dx`` each body's move and ``dR`` its turn since the step began, at the core anchors ``c``
(:mod:`.contacts`: a rolling ball's separation does not change).

Friction is Coulomb's cone per point: the tangent impulse along ``t1`` and ``t2`` is solved
from each direction's effective mass, then the pair is scaled back into the disk
``|j_t| <= mu j_n``. Rolling resistance is an angular impulse about the two tangents against the
bodies' relative rolling, within the disk ``|j_r| <= c_r sum j_n`` (``c_r`` a length [m], the
rolling-resistance coefficient: the torque needed to roll a body is ``c_r`` times the load).

The inverse inertia in the world frame is taken at the step's start and kept over its
substeps for the impulses, as Box2D does with its bodies' inertia.

Contacts are solved one after another in row order (Gauss-Seidel). Vectors are multiplied in
scalars, never with ``@`` (Numba's ``@`` calls BLAS through SciPy).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.rigid.solver import softness
from carom.engines.rigid3d.contacts import (
    F_E,
    F_JR1,
    F_JR2,
    F_MU,
    F_NX,
    F_NY,
    F_NZ,
    F_ROLL,
    F_T1X,
    F_T1Y,
    F_T1Z,
    F_T2X,
    F_T2Y,
    F_T2Z,
    I_BODY_A,
    I_BODY_B,
    I_COUNT,
    I_FLAGS,
    P_BASE,
    P_JN,
    P_JT1,
    P_JT2,
    P_KA,
    P_KB,
    P_NMASS,
    P_RAX,
    P_T1MASS,
    P_T2MASS,
    P_TOTAL,
    P_VREL,
    point_offset,
)
from carom.engines.rigid3d.motion import (
    apply_impulse,
    free_turn,
    matrix,
    relative_velocity,
    world_inverse_inertia,
)

__all__ = ["FLAG_EXACT", "solve_step"]

FLAG_EXACT = 1  # the contact was solved exactly this step (an isolated impact)


@njit(cache=True, inline="always")
def _turning(body: int, r: np.ndarray, dx: float, dy: float, dz: float, iw: np.ndarray) -> float:
    """``(r x d) . I^-1 (r x d)`` of one body [1/kg]."""
    cx = r[1] * dz - r[2] * dy
    cy = r[2] * dx - r[0] * dz
    cz = r[0] * dy - r[1] * dx
    total: float = (
        cx * (iw[body, 0] * cx + iw[body, 1] * cy + iw[body, 2] * cz)
        + cy * (iw[body, 3] * cx + iw[body, 4] * cy + iw[body, 5] * cz)
        + cz * (iw[body, 6] * cx + iw[body, 7] * cy + iw[body, 8] * cz)
    )
    return total


@njit(cache=True, inline="always")
def _mass_along(
    a: int, b: int, r_a: np.ndarray, r_b: np.ndarray, dx: float, dy: float, dz: float,
    inv_mass: np.ndarray, iw: np.ndarray,
) -> float:  # fmt: skip
    """``1 / (m_A^-1 + m_B^-1 + (r_A x d) . I_A^-1 (r_A x d) + (r_B x d) . I_B^-1 (r_B x d))``,
    the effective mass along unit ``d`` [kg] (0 if nothing can move)."""
    k = inv_mass[a] + inv_mass[b]
    k += _turning(a, r_a, dx, dy, dz, iw) + _turning(b, r_b, dx, dy, dz, iw)
    return 1.0 / k if k > 0.0 else 0.0


@njit(cache=True, inline="always")
def _angular_mass(a: int, b: int, dx: float, dy: float, dz: float, iw: np.ndarray) -> float:
    """``1 / (d . (I_A^-1 + I_B^-1) d)``: the angular effective mass about unit ``d``
    [kg m^2] (0 if neither body can turn)."""
    k = 0.0
    for body in range(2):
        c = a if body == 0 else b
        k += (
            dx * (iw[c, 0] * dx + iw[c, 1] * dy + iw[c, 2] * dz)
            + dy * (iw[c, 3] * dx + iw[c, 4] * dy + iw[c, 5] * dz)
            + dz * (iw[c, 6] * dx + iw[c, 7] * dy + iw[c, 8] * dz)
        )
    return 1.0 / k if k > 0.0 else 0.0


@njit(cache=True)
def _prepare(cf: np.ndarray, ci: np.ndarray, nc: int, inv_mass: np.ndarray, iw: np.ndarray) -> None:
    """Each point's effective masses along the normal and the tangents, and a zero total."""
    for m in range(nc):
        a = ci[m, I_BODY_A]
        b = ci[m, I_BODY_B]
        for j in range(ci[m, I_COUNT]):
            o = point_offset(j)
            r_a = cf[m, o + P_RAX : o + P_RAX + 3]
            r_b = cf[m, o + P_RAX + 3 : o + P_RAX + 6]
            cf[m, o + P_NMASS] = _mass_along(
                a, b, r_a, r_b, cf[m, F_NX], cf[m, F_NY], cf[m, F_NZ], inv_mass, iw
            )
            cf[m, o + P_T1MASS] = _mass_along(
                a, b, r_a, r_b, cf[m, F_T1X], cf[m, F_T1Y], cf[m, F_T1Z], inv_mass, iw
            )
            cf[m, o + P_T2MASS] = _mass_along(
                a, b, r_a, r_b, cf[m, F_T2X], cf[m, F_T2Y], cf[m, F_T2Z], inv_mass, iw
            )
            cf[m, o + P_TOTAL] = 0.0


@njit(cache=True, inline="always")
def _fixed_work(
    a: int, b: int, px: float, py: float, pz: float, r_a: np.ndarray, r_b: np.ndarray,
    inv_mass: np.ndarray, v: np.ndarray, w: np.ndarray,
) -> float:  # fmt: skip
    """Work [J] that an impulse ``P`` on A (``-P`` on B) does through a body of infinite mass:
    the impulse on the other body times the fixed body's velocity at the point."""
    total = 0.0
    if inv_mass[a] == 0.0:
        ux = v[a, 0] + w[a, 1] * r_a[2] - w[a, 2] * r_a[1]
        uy = v[a, 1] + w[a, 2] * r_a[0] - w[a, 0] * r_a[2]
        uz = v[a, 2] + w[a, 0] * r_a[1] - w[a, 1] * r_a[0]
        total -= px * ux + py * uy + pz * uz
    if inv_mass[b] == 0.0:
        ux = v[b, 0] + w[b, 1] * r_b[2] - w[b, 2] * r_b[1]
        uy = v[b, 1] + w[b, 2] * r_b[0] - w[b, 0] * r_b[2]
        uz = v[b, 2] + w[b, 0] * r_b[1] - w[b, 1] * r_b[0]
        total += px * ux + py * uy + pz * uz
    return total


@njit(cache=True, inline="always")
def _turn_angular(
    a: int, b: int, jx: float, jy: float, jz: float, iw: np.ndarray, w: np.ndarray
) -> None:
    """Angular impulse ``J`` [N m s] on A and ``-J`` on B."""
    w[a, 0] += iw[a, 0] * jx + iw[a, 1] * jy + iw[a, 2] * jz
    w[a, 1] += iw[a, 3] * jx + iw[a, 4] * jy + iw[a, 5] * jz
    w[a, 2] += iw[a, 6] * jx + iw[a, 7] * jy + iw[a, 8] * jz
    w[b, 0] -= iw[b, 0] * jx + iw[b, 1] * jy + iw[b, 2] * jz
    w[b, 1] -= iw[b, 3] * jx + iw[b, 4] * jy + iw[b, 5] * jz
    w[b, 2] -= iw[b, 6] * jx + iw[b, 7] * jy + iw[b, 8] * jz


@njit(cache=True)
def _warm_start(
    cf: np.ndarray, ci: np.ndarray, nc: int, inv_mass: np.ndarray, iw: np.ndarray,
    v: np.ndarray, w: np.ndarray, work: np.ndarray,
) -> None:  # fmt: skip
    """Apply every point's impulse, and each contact's rolling impulse, from the last substep
    (or step) again."""
    for m in range(nc):
        if ci[m, I_FLAGS] & FLAG_EXACT:
            continue
        a = ci[m, I_BODY_A]
        b = ci[m, I_BODY_B]
        for j in range(ci[m, I_COUNT]):
            o = point_offset(j)
            jn = cf[m, o + P_JN]
            j1 = cf[m, o + P_JT1]
            j2 = cf[m, o + P_JT2]
            px = jn * cf[m, F_NX] + j1 * cf[m, F_T1X] + j2 * cf[m, F_T2X]
            py = jn * cf[m, F_NY] + j1 * cf[m, F_T1Y] + j2 * cf[m, F_T2Y]
            pz = jn * cf[m, F_NZ] + j1 * cf[m, F_T1Z] + j2 * cf[m, F_T2Z]
            cf[m, o + P_TOTAL] += jn
            r_a = cf[m, o + P_RAX : o + P_RAX + 3]
            r_b = cf[m, o + P_RAX + 3 : o + P_RAX + 6]
            work[0] += _fixed_work(a, b, px, py, pz, r_a, r_b, inv_mass, v, w)
            apply_impulse(a, b, px, py, pz, r_a, r_b, inv_mass, iw, v, w)
        r1 = cf[m, F_JR1]
        r2 = cf[m, F_JR2]
        if r1 != 0.0 or r2 != 0.0:
            _turn_angular(
                a, b,
                r1 * cf[m, F_T1X] + r2 * cf[m, F_T2X],
                r1 * cf[m, F_T1Y] + r2 * cf[m, F_T2Y],
                r1 * cf[m, F_T1Z] + r2 * cf[m, F_T2Z],
                iw, w,
            )  # fmt: skip


@njit(cache=True)
def _solve(
    cf: np.ndarray, ci: np.ndarray, nc: int, inv_mass: np.ndarray, iw: np.ndarray,
    v: np.ndarray, w: np.ndarray, moved: np.ndarray, turned: np.ndarray, inv_h: float,
    use_bias: bool, soft_moving: tuple[float, float, float],
    soft_fixed: tuple[float, float, float], push_speed: float, work: np.ndarray,
) -> None:  # fmt: skip
    """One Gauss-Seidel pass over the contacts: normal impulses, friction, rolling resistance.
    ``moved`` (N, 3) and ``turned`` (N, 9) are each body's move and turn since the step
    began."""
    for m in range(nc):
        if ci[m, I_FLAGS] & FLAG_EXACT:
            continue
        a = ci[m, I_BODY_A]
        b = ci[m, I_BODY_B]
        nx = cf[m, F_NX]
        ny = cf[m, F_NY]
        nz = cf[m, F_NZ]
        fixed = inv_mass[a] == 0.0 or inv_mass[b] == 0.0
        rate, soft_mass, soft_impulse = soft_fixed if fixed else soft_moving
        count = ci[m, I_COUNT]
        load = 0.0
        for j in range(count):
            o = point_offset(j)
            r_a = cf[m, o + P_RAX : o + P_RAX + 3]
            r_b = cf[m, o + P_RAX + 3 : o + P_RAX + 6]
            # the separation now: core anchors turned by each body's turn since the step began
            ta, tb = turned[a], turned[b]
            ka = cf[m, o + P_KA]
            kb = cf[m, o + P_KB]
            ax, ay, az = r_a[0] + ka * nx, r_a[1] + ka * ny, r_a[2] + ka * nz
            bx, by, bz = r_b[0] - kb * nx, r_b[1] - kb * ny, r_b[2] - kb * nz
            sx = (
                (moved[a, 0] - moved[b, 0])
                + (ta[0] * ax + ta[1] * ay + ta[2] * az)
                - (tb[0] * bx + tb[1] * by + tb[2] * bz)
            )
            sy = (
                (moved[a, 1] - moved[b, 1])
                + (ta[3] * ax + ta[4] * ay + ta[5] * az)
                - (tb[3] * bx + tb[4] * by + tb[5] * bz)
            )
            sz = (
                (moved[a, 2] - moved[b, 2])
                + (ta[6] * ax + ta[7] * ay + ta[8] * az)
                - (tb[6] * bx + tb[7] * by + tb[8] * bz)
            )
            s = cf[m, o + P_BASE] + sx * nx + sy * ny + sz * nz
            spec = s > 0.0  # speculative: close the gap, no more
            soft = use_bias and not spec
            mass_scale = soft_mass if soft else 1.0
            impulse_scale = soft_impulse if soft else 0.0
            if spec:
                bias = s * inv_h
            elif use_bias:
                bias = max(mass_scale * rate * s, -push_speed)
            else:
                bias = 0.0
            ux, uy, uz = relative_velocity(a, b, r_a, r_b, v, w)
            un = ux * nx + uy * ny + uz * nz
            jn = cf[m, o + P_JN]
            dj = -cf[m, o + P_NMASS] * (mass_scale * un + bias) - impulse_scale * jn
            new = max(jn + dj, 0.0)
            dj = new - jn
            cf[m, o + P_JN] = new
            cf[m, o + P_TOTAL] += dj
            load += new
            work[0] += _fixed_work(a, b, dj * nx, dj * ny, dj * nz, r_a, r_b, inv_mass, v, w)
            apply_impulse(a, b, dj * nx, dj * ny, dj * nz, r_a, r_b, inv_mass, iw, v, w)
        t1x, t1y, t1z = cf[m, F_T1X], cf[m, F_T1Y], cf[m, F_T1Z]
        t2x, t2y, t2z = cf[m, F_T2X], cf[m, F_T2Y], cf[m, F_T2Z]
        mu = cf[m, F_MU]
        for j in range(count):
            o = point_offset(j)
            r_a = cf[m, o + P_RAX : o + P_RAX + 3]
            r_b = cf[m, o + P_RAX + 3 : o + P_RAX + 6]
            ux, uy, uz = relative_velocity(a, b, r_a, r_b, v, w)
            j1 = cf[m, o + P_JT1]
            j2 = cf[m, o + P_JT2]
            n1 = j1 - cf[m, o + P_T1MASS] * (ux * t1x + uy * t1y + uz * t1z)
            n2 = j2 - cf[m, o + P_T2MASS] * (ux * t2x + uy * t2y + uz * t2z)
            limit = mu * cf[m, o + P_JN]
            size2 = n1 * n1 + n2 * n2
            if size2 > limit * limit:
                scale = limit / math.sqrt(size2)
                n1 *= scale
                n2 *= scale
            d1 = n1 - j1
            d2 = n2 - j2
            cf[m, o + P_JT1] = n1
            cf[m, o + P_JT2] = n2
            px = d1 * t1x + d2 * t2x
            py = d1 * t1y + d2 * t2y
            pz = d1 * t1z + d2 * t2z
            work[0] += _fixed_work(a, b, px, py, pz, r_a, r_b, inv_mass, v, w)
            apply_impulse(a, b, px, py, pz, r_a, r_b, inv_mass, iw, v, w)
        roll = cf[m, F_ROLL]
        if roll > 0.0:
            wx = w[a, 0] - w[b, 0]
            wy = w[a, 1] - w[b, 1]
            wz = w[a, 2] - w[b, 2]
            j1 = cf[m, F_JR1]
            j2 = cf[m, F_JR2]
            n1 = j1 - _angular_mass(a, b, t1x, t1y, t1z, iw) * (wx * t1x + wy * t1y + wz * t1z)
            n2 = j2 - _angular_mass(a, b, t2x, t2y, t2z, iw) * (wx * t2x + wy * t2y + wz * t2z)
            limit = roll * load
            size2 = n1 * n1 + n2 * n2
            if size2 > limit * limit:
                scale = limit / math.sqrt(size2) if size2 > 0.0 else 0.0
                n1 *= scale
                n2 *= scale
            d1 = n1 - j1
            d2 = n2 - j2
            cf[m, F_JR1] = n1
            cf[m, F_JR2] = n2
            _turn_angular(
                a, b, d1 * t1x + d2 * t2x, d1 * t1y + d2 * t2y, d1 * t1z + d2 * t2z, iw, w
            )


@njit(cache=True)
def _restitution(
    cf: np.ndarray, ci: np.ndarray, nc: int, threshold: float, inv_mass: np.ndarray,
    iw: np.ndarray, v: np.ndarray, w: np.ndarray, work: np.ndarray,
) -> None:  # fmt: skip
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
        nz = cf[m, F_NZ]
        for j in range(ci[m, I_COUNT]):
            o = point_offset(j)
            if cf[m, o + P_VREL] > -threshold or cf[m, o + P_TOTAL] == 0.0:
                continue
            r_a = cf[m, o + P_RAX : o + P_RAX + 3]
            r_b = cf[m, o + P_RAX + 3 : o + P_RAX + 6]
            ux, uy, uz = relative_velocity(a, b, r_a, r_b, v, w)
            un = ux * nx + uy * ny + uz * nz
            jn = cf[m, o + P_JN]
            dj = -cf[m, o + P_NMASS] * (un + e * cf[m, o + P_VREL])
            new = max(jn + dj, 0.0)
            dj = new - jn
            cf[m, o + P_JN] = new
            cf[m, o + P_TOTAL] += dj
            work[0] += _fixed_work(a, b, dj * nx, dj * ny, dj * nz, r_a, r_b, inv_mass, v, w)
            apply_impulse(a, b, dj * nx, dj * ny, dj * nz, r_a, r_b, inv_mass, iw, v, w)


@njit(cache=True, inline="always")
def _axis_angle(ax: float, ay: float, az: float, out: np.ndarray) -> None:
    """The rotation by the angle ``|a|`` about ``a`` [rad] into ``out`` (9,), row-major
    (Rodrigues)."""
    angle = math.sqrt(ax * ax + ay * ay + az * az)
    out[:] = 0.0
    out[0] = out[4] = out[8] = 1.0
    if angle == 0.0:
        return
    kx, ky, kz = ax / angle, ay / angle, az / angle
    c = math.cos(angle)
    s = math.sin(angle)
    t = 1.0 - c
    out[0] = c + t * kx * kx
    out[1] = t * kx * ky - s * kz
    out[2] = t * kx * kz + s * ky
    out[3] = t * kx * ky + s * kz
    out[4] = c + t * ky * ky
    out[5] = t * ky * kz - s * kx
    out[6] = t * kx * kz - s * ky
    out[7] = t * ky * kz + s * kx
    out[8] = c + t * kz * kz


@njit(cache=True)
def solve_step(
    cf: np.ndarray,
    ci: np.ndarray,
    nc: int,
    bodies: np.ndarray,
    inv_mass: np.ndarray,
    inertia: np.ndarray,
    inv_inertia: np.ndarray,
    gravity_on: np.ndarray,
    movers: np.ndarray,
    x: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    g: np.ndarray,
    dt: float,
    substeps: int,
    contact_hertz: float,
    damping_ratio: float,
    push_speed: float,
    restitution_threshold: float,
    work: np.ndarray,
) -> None:
    """Advance the ``bodies`` (indices) and their contacts by one step ``dt`` [s].

    Contacts flagged exact are skipped; every other contact must join bodies of ``bodies`` or
    a body that impulses do not move (static, kinematic: infinite mass); the kinematic ones
    among them are ``movers`` (indices), whose steady motion over the substeps counts in the
    contacts' separations (the driver moves them after the step). ``inertia`` and
    ``inv_inertia`` (N, 3, 3) are body-frame tensors; ``g`` (3,) [m/s^2] acts on the bodies
    with ``gravity_on``; ``work[0]`` gains the work kinematic bodies did on the others [J].
    """
    h = dt / substeps
    hertz = min(contact_hertz, 0.25 / h)
    soft_moving = softness(hertz, damping_ratio, h)
    soft_fixed = softness(2.0 * hertz, damping_ratio, h)
    n = x.shape[0]
    iw = np.zeros((n, 9))
    world_inverse_inertia(q, inv_inertia, iw)
    moved = np.zeros((n, 3))
    turned = np.zeros((n, 9))
    start = np.empty((n, 9))  # each body's rotation at the step's start
    r = np.empty(9)
    for i in range(n):
        turned[i, 0] = turned[i, 4] = turned[i, 8] = 1.0
    for i in bodies:
        matrix(q, i, r)
        start[i] = r
    _prepare(cf, ci, nc, inv_mass, iw)
    elapsed = 0.0
    for _ in range(substeps):
        for i in bodies:
            if gravity_on[i]:
                v[i, 0] += h * g[0]
                v[i, 1] += h * g[1]
                v[i, 2] += h * g[2]
        _warm_start(cf, ci, nc, inv_mass, iw, v, w, work)
        _solve(
            cf, ci, nc, inv_mass, iw, v, w, moved, turned, 1.0 / h, True, soft_moving,
            soft_fixed, push_speed, work,
        )  # fmt: skip
        for i in bodies:
            for k in range(3):
                x[i, k] += h * v[i, k]
                moved[i, k] += h * v[i, k]
            free_turn(i, h, 1, q, w, inertia, inv_inertia)
            # the turn since the step began: R(q) R(q_start)^T
            matrix(q, i, r)
            s0 = start[i]
            for a in range(3):
                for c in range(3):
                    turned[i, 3 * a + c] = (
                        r[3 * a] * s0[3 * c] + r[3 * a + 1] * s0[3 * c + 1]
                        + r[3 * a + 2] * s0[3 * c + 2]
                    )  # fmt: skip
        elapsed += h
        for i in movers:  # kinematic bodies: their own steady motion (the driver moves them)
            for k in range(3):
                moved[i, k] = elapsed * v[i, k]
            _axis_angle(w[i, 0] * elapsed, w[i, 1] * elapsed, w[i, 2] * elapsed, turned[i])
        _solve(
            cf, ci, nc, inv_mass, iw, v, w, moved, turned, 1.0 / h, False, soft_moving,
            soft_fixed, push_speed, work,
        )  # fmt: skip
    _restitution(cf, ci, nc, restitution_threshold, inv_mass, iw, v, w, work)
