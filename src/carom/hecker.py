"""Chris Hecker's impulse formula, as published, and its one-dimensional "head-on" reading.

Hecker, "Physics, Part 3: Collision Response", Game Developer, March 1997 (2D), and
"Physics, Part 4: The Third Dimension", June 1997 (3D). For rigid bodies A and B touching at
a point with normal ``n`` and offsets ``r_A``, ``r_B`` from their centres of mass:

.. math::

    j = \\frac{-(1 + e)\\, v_{AB} \\cdot n}
             {n \\cdot n \\left(\\frac{1}{M_A} + \\frac{1}{M_B}\\right)
              + \\frac{(r_A^\\perp \\cdot n)^2}{I_A} + \\frac{(r_B^\\perp \\cdot n)^2}{I_B}}
    \\quad\\text{(2D)}

and in 3D the rotational terms become
``n . [(I_A^-1 (r_A x n)) x r_A + (I_B^-1 (r_B x n)) x r_B]``. Body A receives ``+j n`` and
body B ``-j n``, both at the contact point.

Two ways to apply it to spheres are offered, so the seven-case study can say honestly which
one gives which answer (PHYSICS.md section 2):

* ``reading="contact"``: ``n`` is the line of centres, as Hecker prescribes. For spheres
  ``r x n = 0`` and the formula is exactly the smooth-sphere law of :func:`carom.collide`.
* ``reading="head-on"``: ``n`` is taken along the relative velocity of the contact points, a
  one-dimensional reading that is right for head-on impacts and wrong for oblique ones.
"""

from __future__ import annotations

from typing import Literal

import numpy as np
from numpy.typing import ArrayLike

from carom._inputs import (
    FloatArray,
    PairInputs,
    as_float_array,
    cross_scalar_vector,
    cross_vector_vector,
    dot,
    inverse_mass,
)
from carom.errors import CaromError
from carom.response import (
    CollisionResult,
    check_not_both_static,
    inertia_factors,
    kinetic_energy,
    read_pair,
)

__all__ = ["Reading", "collide", "impulse"]

Reading = Literal["contact", "head-on"]
READINGS: tuple[Reading, ...] = ("contact", "head-on")


def impulse(
    v_ab: ArrayLike,
    n: ArrayLike,
    m_a: ArrayLike,
    m_b: ArrayLike,
    *,
    e: ArrayLike = 1.0,
    r_a: ArrayLike | None = None,
    r_b: ArrayLike | None = None,
    inertia_a: ArrayLike | None = None,
    inertia_b: ArrayLike | None = None,
) -> FloatArray:
    """Hecker's impulse magnitude ``j`` for two rigid bodies touching at one point.

    Body A receives the impulse ``j n`` and body B ``-j n`` at the contact point; the
    formula is in the module docstring. ``n`` need not be a unit vector (it enters as
    ``n . n``), but then ``j n`` and not ``j`` is the impulse.

    Parameters
    ----------
    v_ab : (d,) or (n, d) array_like
        Relative velocity of the contact points, ``(v_A + w_A x r_A) - (v_B + w_B x r_B)``
        [m/s], d = 2 or 3.
    n : (d,) or (n, d) array_like
        Contact normal, pointing from B to A [-]; must not be zero.
    m_a, m_b : float or (n,) array_like
        Masses [kg]; ``math.inf`` for an immovable body.
    e : float or (n,) array_like, default 1.0
        Coefficient of restitution in [0, 1] [-].
    r_a, r_b : (d,) or (n, d) array_like, optional
        Offsets from each centre of mass to the contact point [m]; default zero (no rotation).
    inertia_a, inertia_b : float, (n,), (3, 3) or (n, 3, 3) array_like, optional
        Moments of inertia [kg m^2]: a scalar about z in 2D; in 3D a scalar (isotropic) or
        the world-frame tensor. ``math.inf`` for a body that cannot turn. Required when the
        matching offset is given.

    Returns
    -------
    float or (n,) float64
        ``j`` [N s]: the impulse on A is ``j n``; it makes the normal relative velocity of
        the contact points ``v_AB' . n = -e v_AB . n``. Positive when the bodies approach.

    Examples
    --------
    A 1 kg rod end hit square-on: its centre moves and it turns.

    >>> from carom import hecker
    >>> j = hecker.impulse([0.0, -1.0], [0.0, 1.0], 1.0, float("inf"), e=1.0,
    ...                    r_a=[0.5, 0.0], inertia_a=1.0 / 12.0)
    >>> round(float(j), 6)
    0.5
    """
    inp = PairInputs()
    inp.vector("v_ab", v_ab, unit="m/s")
    inp.vector("n", n, unit="-")
    for name, value in (("m_a", m_a), ("m_b", m_b)):
        inp.scalar(
            name,
            value,
            low=0.0,
            high=np.inf,
            low_open=True,
            allow_inf=True,
            unit="kg",
            hint="use math.inf for an immovable body",
        )
    inp.scalar("e", e, low=0.0, high=1.0, unit="-")
    assert inp.dim is not None
    dim = inp.dim
    zero = np.zeros(dim)
    inp.vector("r_a", zero if r_a is None else r_a, unit="m")
    inp.vector("r_b", zero if r_b is None else r_b, unit="m")
    nb, a = inp.broadcast()
    check_not_both_static(a["m_a"], a["m_b"])
    if (dot(a["n"], a["n"]) == 0.0).any():
        raise CaromError("n must not be the zero vector: it is the contact normal")
    inv_i_a = _inverse_inertia("inertia_a", inertia_a, r_a is not None, dim, nb)
    inv_i_b = _inverse_inertia("inertia_b", inertia_b, r_b is not None, dim, nb)
    j = _impulse_batch(
        a["v_ab"],
        a["n"],
        inverse_mass(a["m_a"]),
        inverse_mass(a["m_b"]),
        a["r_a"],
        a["r_b"],
        inv_i_a,
        inv_i_b,
        a["e"],
    )
    return j[0] if inp.single else j


def _inverse_inertia(
    name: str, value: ArrayLike | None, needed: bool, dim: int, n: int
) -> FloatArray:
    """Inverse inertia, (n,) in 2D or (n, 3, 3) in 3D; zero for inf or when no offset."""
    if value is None:
        if needed:
            raise CaromError(
                f"{name} is required when the contact offset of that body is given: the "
                f"offset turns the body, and how much depends on its moment of inertia [kg m^2]"
            )
        return np.zeros(n) if dim == 2 else np.zeros((n, 3, 3))
    arr = as_float_array(name, value)
    if dim == 2 or arr.ndim in (0, 1):
        if arr.ndim > 1 or (arr.ndim == 1 and arr.shape[0] not in (1, n)):
            raise CaromError(f"{name} must be a scalar or have shape ({n},); got {arr.shape}")
        if (np.isnan(arr) | (arr <= 0)).any():
            raise CaromError(
                f"{name} must be positive [kg m^2] (math.inf: cannot turn); got {arr.tolist()}"
            )
        inv = np.broadcast_to(inverse_mass(np.atleast_1d(arr)), (n,))
        return np.array(inv) if dim == 2 else inv[:, None, None] * np.eye(3)
    if arr.shape[-2:] != (3, 3) or arr.ndim not in (2, 3):
        raise CaromError(
            f"{name} must be a scalar or a (3, 3) tensor (or (n, 3, 3)); got shape {arr.shape}"
        )
    tensors = np.broadcast_to(arr, (n, 3, 3))
    if not np.isfinite(tensors).all() or not np.allclose(tensors, tensors.transpose(0, 2, 1)):
        raise CaromError(f"{name} must be a finite symmetric tensor [kg m^2]")
    if (np.linalg.eigvalsh(tensors) <= 0).any():
        raise CaromError(f"{name} must be positive definite: every principal moment > 0")
    inverse: FloatArray = np.linalg.inv(tensors).astype(np.float64)
    return inverse


def _apply(tensors: FloatArray, vectors: FloatArray) -> FloatArray:
    """Row-wise matrix-vector product of (n, 3, 3) and (n, 3), in a fixed summation order."""
    return (
        tensors[:, :, 0] * vectors[:, 0:1]
        + tensors[:, :, 1] * vectors[:, 1:2]
        + tensors[:, :, 2] * vectors[:, 2:3]
    )


def _impulse_batch(
    v_ab: FloatArray,
    n: FloatArray,
    inv_m_a: FloatArray,
    inv_m_b: FloatArray,
    r_a: FloatArray,
    r_b: FloatArray,
    inv_i_a: FloatArray,
    inv_i_b: FloatArray,
    e: FloatArray,
) -> FloatArray:
    """The formula on broadcast arrays: (n, d) vectors, (n,) or (n, 3, 3) inverse inertia."""
    denominator = dot(n, n) * (inv_m_a + inv_m_b)
    if n.shape[1] == 2:
        # r_perp . n = (-r_y, r_x) . n = r x n (the z component)
        ra_perp_n = cross_vector_vector(r_a, n)
        rb_perp_n = cross_vector_vector(r_b, n)
        denominator = denominator + ra_perp_n**2 * inv_i_a + rb_perp_n**2 * inv_i_b
    else:
        ang_a = np.cross(_apply(inv_i_a, np.cross(r_a, n)), r_a)
        ang_b = np.cross(_apply(inv_i_b, np.cross(r_b, n)), r_b)
        denominator = denominator + dot(n, ang_a + ang_b)
    result: FloatArray = -(1.0 + e) * dot(v_ab, n) / denominator
    return result


def collide(
    x1: ArrayLike,
    v1: ArrayLike,
    m1: ArrayLike,
    x2: ArrayLike,
    v2: ArrayLike,
    m2: ArrayLike,
    *,
    e: ArrayLike = 1.0,
    reading: Reading = "contact",
    w1: ArrayLike | None = None,
    w2: ArrayLike | None = None,
    radius1: ArrayLike | None = None,
    radius2: ArrayLike | None = None,
    q: float | tuple[float, float] | None = None,
) -> CollisionResult:
    """Two spheres (or disks) after impact by Hecker's formula; inputs as :func:`carom.collide`.

    The pair collides when its centres approach, ``(v1 - v2) . (x1 - x2) < 0`` (the same
    detection test for every reading). The impulse ``j n`` then follows Hecker's formula with
    the contact at ``x1 - a1 n_c`` on the line of centres ``n_c`` (offsets zero when no radii
    are given) and ``n`` chosen by ``reading``:

    * ``"contact"``: ``n = n_c``, the line of centres (Hecker's prescription);
    * ``"head-on"``: ``n = -v_AB / |v_AB|``, along the relative velocity of the contact points,
      as if every impact were head-on.

    Parameters
    ----------
    x1, v1, m1, x2, v2, m2, e, w1, w2, radius1, radius2, q
        As for :func:`carom.collide` (units m, m/s, kg, rad/s; shapes (d,) or (n, d)).
    reading : {"contact", "head-on"}, default "contact"
        Which normal the formula is given (see above).

    Returns
    -------
    CollisionResult
        As from :func:`carom.collide`, with ``normal`` the ``n`` used, ``beta`` None, and
        ``ke_lost = ke_before - ke_after`` (Hecker gives no closed form for it).

    Examples
    --------
    A billiard cut shot: the head-on reading sends the struck ball along the cue ball's path.

    >>> from carom import hecker
    >>> x1, x2 = [-0.17320508075688773, -0.1], [0.0, 0.0]
    >>> r = hecker.collide(x1, [1.0, 0.0], 1.0, x2, [0.0, 0.0], 1.0, reading="head-on")
    >>> r.v2.round(12).tolist()
    [1.0, 0.0]
    """
    if reading not in READINGS:
        raise CaromError(f"reading must be one of {READINGS}; got {reading!r}")
    spins = w1 is not None or w2 is not None
    inp = read_pair(
        x1,
        v1,
        m1,
        x2,
        v2,
        m2,
        e=e,
        w1=w1,
        w2=w2,
        radius1=radius1,
        radius2=radius2,
        with_spins=spins,
        radii_for="spins",
    )
    assert inp.dim is not None
    dim = inp.dim
    q1, q2 = inertia_factors(q, dim)
    nb, a = inp.broadcast()
    check_not_both_static(a["m1"], a["m2"])
    x1a, v1a, m1a, x2a, v2a, m2a, ea = (a[k] for k in ("x1", "v1", "m1", "x2", "v2", "m2", "e"))
    r = x1a - x2a
    dist2 = dot(r, r)
    if (dist2 == 0.0).any():
        i = int(np.argmax(dist2 == 0.0))
        raise CaromError(f"x1 and x2 coincide at index {i}: the line of centres is undefined")
    n_c = r / np.sqrt(dist2)[:, None]

    radius1a = a.get("radius1", np.zeros(nb))
    radius2a = a.get("radius2", np.zeros(nb))
    r_a = -radius1a[:, None] * n_c
    r_b = radius2a[:, None] * n_c
    w1a = a.get("w1")
    w2a = a.get("w2")
    v_ab = v1a - v2a
    if w1a is not None and w2a is not None:
        # contact-point velocity v + w x r, with r_A = -a1 n_c and r_B = +a2 n_c
        v_ab = v_ab + cross_scalar_vector(w1a, r_a) - cross_scalar_vector(w2a, r_b)

    approaching = dot(v1a - v2a, r) < 0.0
    if reading == "contact":
        n = n_c
    else:
        speed = np.sqrt(dot(v_ab, v_ab))
        safe = np.where(speed > 0.0, speed, 1.0)
        n = np.where((speed > 0.0)[:, None], -v_ab / safe[:, None], n_c)

    inv_m1 = inverse_mass(m1a)
    inv_m2 = inverse_mass(m2a)
    with np.errstate(divide="ignore"):
        inv_i1 = np.where(np.isinf(m1a), 0.0, inv_m1 / (q1 * radius1a**2)) if spins else 0 * m1a
        inv_i2 = np.where(np.isinf(m2a), 0.0, inv_m2 / (q2 * radius2a**2)) if spins else 0 * m2a
    if dim == 3:
        inv_i1 = inv_i1[:, None, None] * np.eye(3)
        inv_i2 = inv_i2[:, None, None] * np.eye(3)
    j = _impulse_batch(v_ab, n, inv_m1, inv_m2, r_a, r_b, inv_i1, inv_i2, ea)
    applied = approaching & (dot(v_ab, n) < 0.0)
    J = np.where(applied, j, 0.0)[:, None] * n

    v1_after = v1a + J * inv_m1[:, None]
    v2_after = v2a - J * inv_m2[:, None]
    w1_after = w2_after = None
    if w1a is not None and w2a is not None:
        t1 = cross_vector_vector(r_a, J)
        t2 = cross_vector_vector(r_b, J)
        if dim == 2:
            w1_after = w1a + inv_i1 * t1
            w2_after = w2a - inv_i2 * t2
        else:
            w1_after = w1a + _apply(inv_i1, t1)
            w2_after = w2a - _apply(inv_i2, t2)

    ke_before = kinetic_energy(m1a, v1a, w1a, a.get("radius1"), q1) + kinetic_energy(
        m2a, v2a, w2a, a.get("radius2"), q2
    )
    ke_after = kinetic_energy(m1a, v1_after, w1_after, a.get("radius1"), q1) + kinetic_energy(
        m2a, v2_after, w2_after, a.get("radius2"), q2
    )
    rel_after = v1_after - v2_after
    result = CollisionResult(
        v1=v1_after,
        v2=v2_after,
        w1=w1_after,
        w2=w2_after,
        impulse=J,
        normal=n,
        approach_speed=-dot(v1a - v2a, n),
        separation_speed=dot(rel_after, n),
        relative_speed_after=np.sqrt(dot(rel_after, rel_after)),
        ke_before=ke_before,
        ke_after=ke_after,
        ke_lost=ke_before - ke_after,
        beta=None,
        applied=applied,
    )
    return result._unbatched() if inp.single else result
