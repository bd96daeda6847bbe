"""Where bodies and their pieces are: placing pieces in the world, and free flight.

A body's pose is its centre of mass ``x`` [m] and angle ``theta`` [rad]; its pieces' corners
and edge normals are stored in the body's frame (centred on the centre of mass) and placed in
the world by ``x + R(theta) v``. Free flight under uniform gravity ``g`` is exact:
``x(t) = x + v t + g t^2/2``, ``theta(t) = theta + omega t``.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from carom.engines.stepped.loads import fit_to_move
from carom.jit import leaf

__all__ = [
    "apply_impulse",
    "fly",
    "fly_all",
    "kick",
    "mechanical_energy",
    "place_piece",
    "place_pieces",
    "relative_velocity",
]


@leaf
def place_piece(
    p: int,
    px: float,
    py: float,
    angle: float,
    piece_start: np.ndarray,
    piece_count: np.ndarray,
    local_vertices: np.ndarray,
    local_normals: np.ndarray,
    vertices: np.ndarray,
    normals: np.ndarray,
) -> None:
    """Place piece ``p`` of a body at ``(px, py)`` [m] turned by ``angle`` [rad]: its corners
    into ``vertices``, its normals into ``normals`` (rows as in ``local_vertices``)."""
    c = math.cos(angle)
    s = math.sin(angle)
    for k in range(piece_start[p], piece_start[p] + piece_count[p]):
        lx = local_vertices[k, 0]
        ly = local_vertices[k, 1]
        vertices[k, 0] = px + (c * lx - s * ly)
        vertices[k, 1] = py + (s * lx + c * ly)
        nx = local_normals[k, 0]
        ny = local_normals[k, 1]
        normals[k, 0] = c * nx - s * ny
        normals[k, 1] = s * nx + c * ny


@leaf
def place_pieces(
    x: np.ndarray,
    angle: np.ndarray,
    which: np.ndarray,
    body_pieces: np.ndarray,
    piece_start: np.ndarray,
    piece_count: np.ndarray,
    local_vertices: np.ndarray,
    local_normals: np.ndarray,
    vertices: np.ndarray,
    normals: np.ndarray,
) -> None:
    """Place the pieces of every body with ``which[b]`` true at its pose."""
    for b in range(x.shape[0]):
        if which[b]:
            for p in range(body_pieces[b], body_pieces[b + 1]):
                place_piece(
                    p,
                    x[b, 0],
                    x[b, 1],
                    angle[b],
                    piece_start,
                    piece_count,
                    local_vertices,
                    local_normals,
                    vertices,
                    normals,
                )


@njit(cache=True, inline="always")
def relative_velocity(
    a: int,
    b: int,
    rax: float,
    ray: float,
    rbx: float,
    rby: float,
    v: np.ndarray,
    omega: np.ndarray,
) -> tuple[float, float]:
    """Velocity of body A's point at ``r_A`` less body B's at ``r_B`` [m/s]
    (``v + omega x r``, 2D)."""
    pax, pay = point_velocity(a, rax, ray, v, omega)
    pbx, pby = point_velocity(b, rbx, rby, v, omega)
    return pax - pbx, pay - pby


@njit(cache=True, inline="always")
def point_velocity(
    body: int, rx: float, ry: float, v: np.ndarray, omega: np.ndarray
) -> tuple[float, float]:
    """Velocity [m/s] of the point of ``body`` at offset ``r`` from its centre of mass:
    ``v + omega x r`` (2D)."""
    return v[body, 0] - omega[body] * ry, v[body, 1] + omega[body] * rx


@njit(cache=True, inline="always")
def apply_impulse(
    a: int,
    b: int,
    px: float,
    py: float,
    rax: float,
    ray: float,
    rbx: float,
    rby: float,
    inv_mass: np.ndarray,
    inv_inertia: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
) -> None:
    """Impulse ``P`` [N s] on A at ``r_A`` and ``-P`` on B at ``r_B``."""
    ma = inv_mass[a]
    mb = inv_mass[b]
    v[a, 0] += ma * px
    v[a, 1] += ma * py
    omega[a] += inv_inertia[a] * (rax * py - ray * px)
    v[b, 0] -= mb * px
    v[b, 1] -= mb * py
    omega[b] -= inv_inertia[b] * (rbx * py - rby * px)


@njit(cache=True, inline="always")
def fixed_work(
    a: int,
    b: int,
    px: float,
    py: float,
    rax: float,
    ray: float,
    rbx: float,
    rby: float,
    inv_mass: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
) -> float:
    """Work [J] that the impulse ``P`` on A and ``-P`` on B (as :func:`apply_impulse`) draws
    from a body that impulses do not move (infinite mass: static, kinematic, asleep): the
    impulse on the other body times the fixed body's velocity at the contact point. Zero
    for a body at rest; a moving kinematic body feeds (or takes) that much energy."""
    work = 0.0
    if inv_mass[a] == 0.0:
        ux, uy = point_velocity(a, rax, ray, v, omega)
        work -= px * ux + py * uy
    if inv_mass[b] == 0.0:
        ux, uy = point_velocity(b, rbx, rby, v, omega)
        work += px * ux + py * uy
    return work


@njit(cache=True, inline="always")
def fly(
    b: int,
    t: float,
    x: np.ndarray,
    angle: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    gx: float,
    gy: float,
) -> None:
    """Move body ``b`` in free flight for ``t`` [s] under acceleration ``(gx, gy)``, exactly."""
    x[b, 0] += (v[b, 0] + 0.5 * gx * t) * t
    x[b, 1] += (v[b, 1] + 0.5 * gy * t) * t
    v[b, 0] += gx * t
    v[b, 1] += gy * t
    angle[b] += omega[b] * t


@leaf
def fly_all(
    rows: np.ndarray, t: float, x: np.ndarray, angle: np.ndarray, v: np.ndarray,
    omega: np.ndarray, accel: np.ndarray,
) -> None:  # fmt: skip
    """Bodies ``rows`` (k,) in free flight for ``t`` [s], each under its acceleration
    ``accel`` (n, 2) [m/s^2] (:func:`fly` in one compiled call)."""
    for r in range(rows.shape[0]):
        b = rows[r]
        fly(b, t, x, angle, v, omega, accel[b, 0], accel[b, 1])


@leaf
def mechanical_energy(
    rows: np.ndarray,
    dynamic: np.ndarray,
    mass: np.ndarray,
    inertia: np.ndarray,
    x: np.ndarray,
    v: np.ndarray,
    omega: np.ndarray,
    gx: float,
    gy: float,
) -> float:
    """Kinetic plus gravitational potential energy [J] of the dynamic bodies among ``rows``
    (positions ``x`` (N, 2) [m], velocities ``v`` (N, 2) [m/s], ``omega`` (N,) [rad/s])."""
    total = 0.0
    for i in rows:
        if dynamic[i]:
            kinetic = mass[i] * (v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1])
            kinetic += inertia[i] * omega[i] * omega[i]
            total += 0.5 * kinetic - mass[i] * (x[i, 0] * gx + x[i, 1] * gy)
    return total


@leaf
def kick(
    ids: np.ndarray, impulses: np.ndarray, points: np.ndarray, x: np.ndarray, v: np.ndarray,
    omega: np.ndarray, inv_mass: np.ndarray, inv_inertia: np.ndarray, mass: np.ndarray,
    inertia: np.ndarray, checks: tuple[np.ndarray, np.ndarray, float],
    sleep: tuple[np.ndarray, np.ndarray],
) -> tuple[bool, float]:  # fmt: skip
    """Impulses on bodies ``ids`` (k,), in order (a body named twice takes both): impulse j
    [N s] is row j of ``impulses`` (k, 2), or its only row (1, 2); it acts at the world point
    row j (or the only row) of ``points`` [m], or at the centre of mass when ``points`` has
    no rows. The bodies wake (``sleep``: awake flags and sleep clocks). First, ``checks``
    (alive, dynamic, largest: :func:`carom.engines.stepped.loads.fit_to_move`): when one
    fails nothing is done. Returns whether it was done and the kinetic energy the impulses
    gave [J] (their work)."""
    alive, dynamic, largest = checks
    if not fit_to_move(ids, alive, dynamic, impulses, points, largest):
        return False, 0.0
    work = 0.0
    last_j = impulses.shape[0] - 1
    last_p = points.shape[0] - 1
    for k in range(ids.shape[0]):
        i = ids[k]
        jx, jy = impulses[min(k, last_j), 0], impulses[min(k, last_j), 1]
        before = mass[i] * (v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1]) + inertia[i] * omega[i] ** 2
        v[i, 0] += inv_mass[i] * jx
        v[i, 1] += inv_mass[i] * jy
        if last_p >= 0:
            rx = points[min(k, last_p), 0] - x[i, 0]
            ry = points[min(k, last_p), 1] - x[i, 1]
            omega[i] += inv_inertia[i] * (rx * jy - ry * jx)
        after = mass[i] * (v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1]) + inertia[i] * omega[i] ** 2
        work += 0.5 * (after - before)
        sleep[0][i] = True
        sleep[1][i] = 0.0
    return True, work
