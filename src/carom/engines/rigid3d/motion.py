"""Where 3D bodies and their pieces are: rotations, placing pieces, impulses and free flight.

A body's pose is its centre of mass ``x`` [m] and a unit quaternion ``q = (w, x, y, z)`` (body
to world, rotation matrix ``R``); its pieces are stored in the body's frame and placed by
``x + R v``. Its inverse inertia in the world is ``R I^-1 R^T`` (``I`` the body-frame tensor).

Free flight under uniform gravity moves the centre exactly (``x + v t + g t^2/2``). The
rotation of a body whose angular velocity is constant (a ball, any body spinning about a
principal axis, one not spinning) is exact too: ``|w| t`` about ``w``. Otherwise the torque-free
body's angular velocity changes (Euler's equations: the gyroscopic term) while its angular
momentum ``L`` in the world stays fixed; :func:`free_turn` keeps ``L`` exactly and integrates
the orientation alone, ``dq/dt = (w, 0) q / 2`` with ``w = R I^-1 R^T L``, by the classical
Runge-Kutta method (error ``O((h |w|)^5)`` a step). The solver turns its bodies the same way
between impulses, so contacts, which change ``L`` only by their impulses' moments, keep the
total angular momentum to round-off; and as ``w = I^-1 L`` with ``L`` fixed, no spin can grow
without bound (the energy stays below ``|L|^2 / (2 I_min)``), where an explicit gyroscopic
step would gain energy.

Vectors are multiplied in scalars, never with ``@`` (Numba's ``@`` calls BLAS through SciPy).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from carom.engines.stepped.loads import fit_to_move
from carom.geometry.rotation import matrix, turn

__all__ = [
    "apply_impulse",
    "fly",
    "fly_all",
    "free_turn",
    "kick",
    "mechanical_energy",
    "place_piece",
    "place_pieces",
    "relative_velocity",
    "spin_energy",
    "turn_under",
    "world_inverse_inertia",
    "world_inverse_row",
]


@njit(cache=True)
def place_piece(
    p: int, x: np.ndarray, q: np.ndarray, body: int, piece_vstart: np.ndarray,
    piece_vcount: np.ndarray, piece_fstart: np.ndarray, piece_fcount: np.ndarray,
    local_vertices: np.ndarray, local_normals: np.ndarray, vertices: np.ndarray,
    normals: np.ndarray,
) -> None:  # fmt: skip
    """Place piece ``p`` at the pose in row ``body`` of ``x`` (centre) and ``q``
    (quaternion): its corners into ``vertices`` (V, 3), its face normals into ``normals``
    (F, 3)."""
    r = np.empty(9)
    matrix(q, body, r)
    for k in range(piece_vstart[p], piece_vstart[p] + piece_vcount[p]):
        lx, ly, lz = local_vertices[k, 0], local_vertices[k, 1], local_vertices[k, 2]
        vertices[k, 0] = x[body, 0] + r[0] * lx + r[1] * ly + r[2] * lz
        vertices[k, 1] = x[body, 1] + r[3] * lx + r[4] * ly + r[5] * lz
        vertices[k, 2] = x[body, 2] + r[6] * lx + r[7] * ly + r[8] * lz
    for k in range(piece_fstart[p], piece_fstart[p] + piece_fcount[p]):
        lx, ly, lz = local_normals[k, 0], local_normals[k, 1], local_normals[k, 2]
        normals[k, 0] = r[0] * lx + r[1] * ly + r[2] * lz
        normals[k, 1] = r[3] * lx + r[4] * ly + r[5] * lz
        normals[k, 2] = r[6] * lx + r[7] * ly + r[8] * lz


@njit(cache=True)
def place_pieces(
    x: np.ndarray, q: np.ndarray, which: np.ndarray, body_pieces: np.ndarray,
    piece_vstart: np.ndarray, piece_vcount: np.ndarray, piece_fstart: np.ndarray,
    piece_fcount: np.ndarray, local_vertices: np.ndarray, local_normals: np.ndarray,
    vertices: np.ndarray, normals: np.ndarray,
) -> None:  # fmt: skip
    """Place the pieces of every body with ``which[b]`` true at its pose (:func:`place_piece`)."""
    for b in range(x.shape[0]):
        if not which[b]:
            continue
        for p in range(body_pieces[b], body_pieces[b + 1]):
            place_piece(
                p, x, q, b, piece_vstart, piece_vcount, piece_fstart, piece_fcount,
                local_vertices, local_normals, vertices, normals,
            )  # fmt: skip


@njit(cache=True, inline="always")
def world_inverse_row(body: int, q: np.ndarray, inv_inertia: np.ndarray, out: np.ndarray) -> None:
    """Body ``body``'s inverse inertia in the world now, ``R I^-1 R^T``, into row ``body`` of
    ``out`` (N, 9) [1/(kg m^2)], row-major."""
    r = np.empty(9)
    matrix(q, body, r)
    for i in range(3):
        for j in range(3):
            total = 0.0
            for k in range(3):
                rik = r[3 * i + k]
                if rik == 0.0:
                    continue
                for m in range(3):
                    total += rik * inv_inertia[body, k, m] * r[3 * j + m]
            out[body, 3 * i + j] = total


@njit(cache=True)
def world_inverse_inertia(q: np.ndarray, inv_inertia: np.ndarray, out: np.ndarray) -> None:
    """Every body's inverse inertia in the world (:func:`world_inverse_row`), into ``out``
    (N, 9)."""
    for b in range(q.shape[0]):
        world_inverse_row(b, q, inv_inertia, out)


@njit(cache=True, inline="always")
def spin_energy(iw: np.ndarray, body: int, w: np.ndarray) -> float:
    """Twice the rotational energy, ``w . I w`` [J], of body ``body`` from its world inverse
    inertia (row of ``iw``, (N, 9)): ``I = (I^-1)^-1`` by the adjugate (symmetric)."""
    k = iw[body]
    c00 = k[4] * k[8] - k[5] * k[7]
    c01 = k[5] * k[6] - k[3] * k[8]
    c02 = k[3] * k[7] - k[4] * k[6]
    det = k[0] * c00 + k[1] * c01 + k[2] * c02
    c11 = k[0] * k[8] - k[2] * k[6]
    c12 = k[1] * k[6] - k[0] * k[7]
    c22 = k[0] * k[4] - k[1] * k[3]
    x0, x1, x2 = w[body, 0], w[body, 1], w[body, 2]
    quad: float = (
        c00 * x0 * x0 + c11 * x1 * x1 + c22 * x2 * x2
        + 2.0 * (c01 * x0 * x1 + c02 * x0 * x2 + c12 * x1 * x2)
    ) / det  # fmt: skip
    return quad


@njit(cache=True, inline="always")
def _times(k: np.ndarray, b: int, x: float, y: float, z: float) -> tuple[float, float, float]:
    """Row ``b`` of ``k`` (N, 9) as a 3x3 matrix, times (x, y, z)."""
    return (
        k[b, 0] * x + k[b, 1] * y + k[b, 2] * z,
        k[b, 3] * x + k[b, 4] * y + k[b, 5] * z,
        k[b, 6] * x + k[b, 7] * y + k[b, 8] * z,
    )


@njit(cache=True, inline="always")
def relative_velocity(
    a: int, b: int, ra: np.ndarray, rb: np.ndarray, v: np.ndarray, w: np.ndarray
) -> tuple[float, float, float]:
    """Velocity [m/s] of A's point at ``x_A + ra`` less B's at ``x_B + rb``:
    ``(v_A + w_A x r_A) - (v_B + w_B x r_B)``."""
    ax = v[a, 0] + w[a, 1] * ra[2] - w[a, 2] * ra[1]
    ay = v[a, 1] + w[a, 2] * ra[0] - w[a, 0] * ra[2]
    az = v[a, 2] + w[a, 0] * ra[1] - w[a, 1] * ra[0]
    bx = v[b, 0] + w[b, 1] * rb[2] - w[b, 2] * rb[1]
    by = v[b, 1] + w[b, 2] * rb[0] - w[b, 0] * rb[2]
    bz = v[b, 2] + w[b, 0] * rb[1] - w[b, 1] * rb[0]
    return ax - bx, ay - by, az - bz


@njit(cache=True, inline="always")
def apply_impulse(
    a: int, b: int, px: float, py: float, pz: float, ra: np.ndarray, rb: np.ndarray,
    inv_mass: np.ndarray, inv_inertia_world: np.ndarray, v: np.ndarray, w: np.ndarray,
) -> None:  # fmt: skip
    """Impulse ``P`` [N s] on A at ``ra`` and ``-P`` on B at ``rb``."""
    v[a, 0] += inv_mass[a] * px
    v[a, 1] += inv_mass[a] * py
    v[a, 2] += inv_mass[a] * pz
    tx = ra[1] * pz - ra[2] * py
    ty = ra[2] * px - ra[0] * pz
    tz = ra[0] * py - ra[1] * px
    dx, dy, dz = _times(inv_inertia_world, a, tx, ty, tz)
    w[a, 0] += dx
    w[a, 1] += dy
    w[a, 2] += dz
    v[b, 0] -= inv_mass[b] * px
    v[b, 1] -= inv_mass[b] * py
    v[b, 2] -= inv_mass[b] * pz
    tx = rb[1] * pz - rb[2] * py
    ty = rb[2] * px - rb[0] * pz
    tz = rb[0] * py - rb[1] * px
    dx, dy, dz = _times(inv_inertia_world, b, tx, ty, tz)
    w[b, 0] -= dx
    w[b, 1] -= dy
    w[b, 2] -= dz


@njit(cache=True, inline="always")
def _spin_rate(
    q0: float, q1: float, q2: float, q3: float, lx: float, ly: float, lz: float,
    inv_body: np.ndarray,
) -> tuple[float, float, float, float]:  # fmt: skip
    """``dq/dt = (w, 0) q / 2`` with ``w = R I^-1 R^T L`` at orientation ``q`` (unnormalised
    is fine: it is normalised here)."""
    norm = np.sqrt(q0 * q0 + q1 * q1 + q2 * q2 + q3 * q3)
    w, x, y, z = q0 / norm, q1 / norm, q2 / norm, q3 / norm
    r00 = 1.0 - 2.0 * (y * y + z * z)
    r01 = 2.0 * (x * y - w * z)
    r02 = 2.0 * (x * z + w * y)
    r10 = 2.0 * (x * y + w * z)
    r11 = 1.0 - 2.0 * (x * x + z * z)
    r12 = 2.0 * (y * z - w * x)
    r20 = 2.0 * (x * z - w * y)
    r21 = 2.0 * (y * z + w * x)
    r22 = 1.0 - 2.0 * (x * x + y * y)
    # L in the body frame, then w there, then back to the world
    bx = r00 * lx + r10 * ly + r20 * lz
    by = r01 * lx + r11 * ly + r21 * lz
    bz = r02 * lx + r12 * ly + r22 * lz
    k = inv_body
    ox = k[0, 0] * bx + k[0, 1] * by + k[0, 2] * bz
    oy = k[1, 0] * bx + k[1, 1] * by + k[1, 2] * bz
    oz = k[2, 0] * bx + k[2, 1] * by + k[2, 2] * bz
    wx = r00 * ox + r01 * oy + r02 * oz
    wy = r10 * ox + r11 * oy + r12 * oz
    wz = r20 * ox + r21 * oy + r22 * oz
    # (w, 0) q / 2 on the normalised q
    return (
        0.5 * (-wx * x - wy * y - wz * z),
        0.5 * (wx * w + wy * z - wz * y),
        0.5 * (wy * w + wz * x - wx * z),
        0.5 * (wz * w + wx * y - wy * x),
    )


@njit(cache=True)
def free_turn(
    i: int, dt: float, substeps: int, q: np.ndarray, w: np.ndarray, inertia: np.ndarray,
    inv_inertia: np.ndarray,
) -> None:  # fmt: skip
    """Turn body ``i`` torque-free for ``dt`` [s]: exactly (``|w| dt`` about ``w``) when its
    angular velocity stays constant (``I w`` parallel to ``w``); otherwise its angular
    momentum ``L`` in the world is kept exactly and the orientation integrated by Runge-Kutta
    in ``substeps`` steps, or more so that none turns it by more than 0.02 rad (the error,
    ``(h |w|)^5 / 120`` a step, stays below 3e-11 of the energy); ``w`` is then the angular
    velocity that carries ``L`` at the new orientation."""
    turn_under(i, dt, substeps, q, w, inertia, inv_inertia, 0.0, 0.0, 0.0)


@njit(cache=True)
def turn_under(
    i: int, dt: float, substeps: int, q: np.ndarray, w: np.ndarray, inertia: np.ndarray,
    inv_inertia: np.ndarray, tx: float, ty: float, tz: float,
) -> None:  # fmt: skip
    """Turn body ``i`` for ``dt`` [s] under the constant world torque ``(tx, ty, tz)`` [N m]:
    its angular momentum is ``L + T t`` exactly, the orientation integrated as in
    :func:`free_turn` (which this is, with no torque)."""
    torqued = tx != 0.0 or ty != 0.0 or tz != 0.0
    r = np.empty(9)
    matrix(q, i, r)
    bx = r[0] * w[i, 0] + r[3] * w[i, 1] + r[6] * w[i, 2]
    by = r[1] * w[i, 0] + r[4] * w[i, 1] + r[7] * w[i, 2]
    bz = r[2] * w[i, 0] + r[5] * w[i, 1] + r[8] * w[i, 2]
    k = inertia[i]
    # I w in the body frame; the spin is steady when it is parallel to w
    sx = k[0, 0] * bx + k[0, 1] * by + k[0, 2] * bz
    sy = k[1, 0] * bx + k[1, 1] * by + k[1, 2] * bz
    sz = k[2, 0] * bx + k[2, 1] * by + k[2, 2] * bz
    cx = by * sz - bz * sy
    cy = bz * sx - bx * sz
    cz = bx * sy - by * sx
    size = abs(cx) + abs(cy) + abs(cz)
    steady = size <= 1e-15 * (abs(sx) + abs(sy) + abs(sz)) * (abs(bx) + abs(by) + abs(bz))
    if steady and not torqued:
        turn(q, i, w[i, 0], w[i, 1], w[i, 2], dt, 3)
        return
    # the angular momentum in the world, fixed
    lx = r[0] * sx + r[1] * sy + r[2] * sz
    ly = r[3] * sx + r[4] * sy + r[5] * sz
    lz = r[6] * sx + r[7] * sy + r[8] * sz
    kinv = inv_inertia[i]
    spin = np.sqrt(w[i, 0] ** 2 + w[i, 1] ** 2 + w[i, 2] ** 2)
    if torqued:  # the most it spins by the end, from the most I^-1 can give T
        most = np.abs(kinv).sum() * np.sqrt(tx * tx + ty * ty + tz * tz) * dt
        spin += most
    pieces = max(substeps, int(np.ceil(spin * dt / 0.02)))
    h = dt / pieces
    for k in range(pieces):
        p0, p1, p2, p3 = q[i, 0], q[i, 1], q[i, 2], q[i, 3]
        # L at the piece's start, middle and end (no torque: the same L throughout)
        t0, t1 = k * h, (k + 0.5) * h
        mx, my, mz = lx + tx * t1, ly + ty * t1, lz + tz * t1
        a0, a1, a2, a3 = _spin_rate(p0, p1, p2, p3, lx + tx * t0, ly + ty * t0, lz + tz * t0, kinv)
        b0, b1, b2, b3 = _spin_rate(
            p0 + 0.5 * h * a0, p1 + 0.5 * h * a1, p2 + 0.5 * h * a2, p3 + 0.5 * h * a3,
            mx, my, mz, kinv,
        )  # fmt: skip
        c0, c1, c2, c3 = _spin_rate(
            p0 + 0.5 * h * b0, p1 + 0.5 * h * b1, p2 + 0.5 * h * b2, p3 + 0.5 * h * b3,
            mx, my, mz, kinv,
        )  # fmt: skip
        t2 = (k + 1) * h
        d0, d1, d2, d3 = _spin_rate(
            p0 + h * c0, p1 + h * c1, p2 + h * c2, p3 + h * c3, lx + tx * t2, ly + ty * t2,
            lz + tz * t2, kinv,
        )  # fmt: skip
        p0 += h / 6.0 * (a0 + 2.0 * b0 + 2.0 * c0 + d0)
        p1 += h / 6.0 * (a1 + 2.0 * b1 + 2.0 * c1 + d1)
        p2 += h / 6.0 * (a2 + 2.0 * b2 + 2.0 * c2 + d2)
        p3 += h / 6.0 * (a3 + 2.0 * b3 + 2.0 * c3 + d3)
        norm = np.sqrt(p0 * p0 + p1 * p1 + p2 * p2 + p3 * p3)
        q[i, 0], q[i, 1], q[i, 2], q[i, 3] = p0 / norm, p1 / norm, p2 / norm, p3 / norm
    # the angular velocity that carries L at the new orientation
    lx += tx * dt
    ly += ty * dt
    lz += tz * dt
    matrix(q, i, r)
    bx = r[0] * lx + r[3] * ly + r[6] * lz
    by = r[1] * lx + r[4] * ly + r[7] * lz
    bz = r[2] * lx + r[5] * ly + r[8] * lz
    ox = kinv[0, 0] * bx + kinv[0, 1] * by + kinv[0, 2] * bz
    oy = kinv[1, 0] * bx + kinv[1, 1] * by + kinv[1, 2] * bz
    oz = kinv[2, 0] * bx + kinv[2, 1] * by + kinv[2, 2] * bz
    w[i, 0] = r[0] * ox + r[1] * oy + r[2] * oz
    w[i, 1] = r[3] * ox + r[4] * oy + r[5] * oz
    w[i, 2] = r[6] * ox + r[7] * oy + r[8] * oz


@njit(cache=True)
def fly(
    i: int,
    dt: float,
    substeps: int,
    x: np.ndarray,
    q: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    ax: float,
    ay: float,
    az: float,
    inertia: np.ndarray,
    inv_inertia: np.ndarray,
    torque: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> None:
    """Body ``i`` in free flight for ``dt`` [s] under acceleration ``a`` [m/s^2]: the centre
    exactly, the rotation by :func:`turn_under` the world ``torque`` [N m] (by default none:
    :func:`free_turn`)."""
    x[i, 0] += dt * (v[i, 0] + 0.5 * dt * ax)
    x[i, 1] += dt * (v[i, 1] + 0.5 * dt * ay)
    x[i, 2] += dt * (v[i, 2] + 0.5 * dt * az)
    v[i, 0] += dt * ax
    v[i, 1] += dt * ay
    v[i, 2] += dt * az
    turn_under(i, dt, substeps, q, w, inertia, inv_inertia, torque[0], torque[1], torque[2])


@njit(cache=True)
def fly_all(
    rows: np.ndarray, dt: float, substeps: int, x: np.ndarray, q: np.ndarray, v: np.ndarray,
    w: np.ndarray, accel: np.ndarray, inertia: np.ndarray, inv_inertia: np.ndarray,
    torque: np.ndarray,
) -> None:  # fmt: skip
    """Bodies ``rows`` (k,) in free flight for ``dt`` [s], each under its acceleration
    ``accel`` (n, 3) [m/s^2] and world torque ``torque`` (n, 3) [N m] (:func:`fly` in one
    compiled call)."""
    for r in range(rows.shape[0]):
        i = rows[r]
        fly(
            i, dt, substeps, x, q, v, w, accel[i, 0], accel[i, 1], accel[i, 2], inertia,
            inv_inertia, (torque[i, 0], torque[i, 1], torque[i, 2]),
        )  # fmt: skip


@njit(cache=True)
def mechanical_energy(
    rows: np.ndarray, dynamic: np.ndarray, mass: np.ndarray, inertia: np.ndarray, x: np.ndarray,
    v: np.ndarray, q: np.ndarray, w: np.ndarray, gx: float, gy: float, gz: float,
) -> float:  # fmt: skip
    """Kinetic (``m v^2/2 + w.I w/2``) and gravitational (``-m g.x``) energy of the dynamic
    bodies among ``rows`` [J]."""
    r = np.empty(9)
    total = 0.0
    for i in rows:
        if not dynamic[i]:
            continue
        matrix(q, i, r)
        bx = r[0] * w[i, 0] + r[3] * w[i, 1] + r[6] * w[i, 2]
        by = r[1] * w[i, 0] + r[4] * w[i, 1] + r[7] * w[i, 2]
        bz = r[2] * w[i, 0] + r[5] * w[i, 1] + r[8] * w[i, 2]
        k = inertia[i]
        spin = (
            bx * (k[0, 0] * bx + k[0, 1] * by + k[0, 2] * bz)
            + by * (k[1, 0] * bx + k[1, 1] * by + k[1, 2] * bz)
            + bz * (k[2, 0] * bx + k[2, 1] * by + k[2, 2] * bz)
        )
        speed2 = v[i, 0] * v[i, 0] + v[i, 1] * v[i, 1] + v[i, 2] * v[i, 2]
        total += 0.5 * mass[i] * speed2 + 0.5 * spin
        total -= mass[i] * (gx * x[i, 0] + gy * x[i, 1] + gz * x[i, 2])
    return total


@njit(cache=True)
def kick(
    ids: np.ndarray, impulses: np.ndarray, points: np.ndarray, x: np.ndarray, v: np.ndarray,
    q: np.ndarray, w: np.ndarray, inv_mass: np.ndarray, inv_inertia: np.ndarray,
    mass: np.ndarray, inertia: np.ndarray, checks: tuple[np.ndarray, np.ndarray, float],
    sleep: tuple[np.ndarray, np.ndarray],
) -> tuple[bool, float]:  # fmt: skip
    """Impulses on the dynamic bodies ``ids`` (k,), in order, checked first and waking the
    bodies, as the 2D kernel (:func:`carom.engines.rigid.motion.kick`), rows of 3; an impulse
    at a point turns the body by its world inverse inertia ``R I^-1 R^T (r x J)``. Returns
    whether it was done and the kinetic energy they gave [J]."""
    alive, dynamic, largest = checks
    if not fit_to_move(ids, alive, dynamic, impulses, points, largest):
        return False, 0.0
    work = 0.0
    last_j = impulses.shape[0] - 1
    last_p = points.shape[0] - 1
    inverse = np.empty((1, 9))
    moment = np.empty(3)
    for k in range(ids.shape[0]):
        i = ids[k]
        jj = impulses[min(k, last_j)]
        one = ids[k : k + 1]
        before = mechanical_energy(one, dynamic, mass, inertia, x, v, q, w, 0.0, 0.0, 0.0)
        for c in range(3):
            v[i, c] += inv_mass[i] * jj[c]
        if last_p >= 0:
            p = points[min(k, last_p)]
            rx, ry, rz = p[0] - x[i, 0], p[1] - x[i, 1], p[2] - x[i, 2]
            moment[0] = ry * jj[2] - rz * jj[1]
            moment[1] = rz * jj[0] - rx * jj[2]
            moment[2] = rx * jj[1] - ry * jj[0]
            world_inverse_row(0, q[i : i + 1], inv_inertia[i : i + 1], inverse)
            for a in range(3):
                w[i, a] += (
                    inverse[0, 3 * a] * moment[0]
                    + inverse[0, 3 * a + 1] * moment[1]
                    + inverse[0, 3 * a + 2] * moment[2]
                )
        work += mechanical_energy(one, dynamic, mass, inertia, x, v, q, w, 0.0, 0.0, 0.0) - before
        sleep[0][i] = True
        sleep[1][i] = 0.0
    return True, work
