"""The point impulse between two rigid bodies with inertia: Chris Hecker's formula.

Hecker, "Physics, Part 3: Collision Response", Game Developer, March 1997 (2D), and
"Physics, Part 4: The Third Dimension", June 1997 (3D); PHYSICS.md section 2. For rigid
bodies A and B touching at a point with normal ``n`` and offsets ``r_A``, ``r_B`` from their
centres of mass:

.. math::

    j = \\frac{-(1 + e)\\, v_{AB} \\cdot n}
             {n \\cdot n \\left(\\frac{1}{M_A} + \\frac{1}{M_B}\\right)
              + \\frac{(r_A^\\perp \\cdot n)^2}{I_A} + \\frac{(r_B^\\perp \\cdot n)^2}{I_B}}
    \\quad\\text{(2D)}

and in 3D the rotational terms become
``n . [(I_A^-1 (r_A x n)) x r_A + (I_B^-1 (r_B x n)) x r_B]``. Body A receives ``+j n`` and
body B ``-j n``, both at the contact point. This is Newton's restitution at the contact point
of general rigid bodies, and what the rigid-body engine's exact single impacts are checked
against; :mod:`carom.studies.hecker` applies it to spheres in two readings.
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from carom._inputs import (
    FloatArray,
    PairInputs,
    as_float_array,
    check_not_both_static,
    cross_vector_vector,
    dot,
    inverse_mass,
)
from carom.errors import CaromError

__all__ = ["impulse"]


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

    >>> from carom.studies import hecker
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
    inv_i_a = inverse_inertia("inertia_a", inertia_a, r_a is not None, dim, nb)
    inv_i_b = inverse_inertia("inertia_b", inertia_b, r_b is not None, dim, nb)
    j = impulse_batch(
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


def inverse_inertia(
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


def apply_tensor(tensors: FloatArray, vectors: FloatArray) -> FloatArray:
    """Row-wise matrix-vector product of (n, 3, 3) and (n, 3), in a fixed summation order."""
    return (
        tensors[:, :, 0] * vectors[:, 0:1]
        + tensors[:, :, 1] * vectors[:, 1:2]
        + tensors[:, :, 2] * vectors[:, 2:3]
    )


def impulse_batch(
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
        ang_a = np.cross(apply_tensor(inv_i_a, np.cross(r_a, n)), r_a)
        ang_b = np.cross(apply_tensor(inv_i_b, np.cross(r_b, n)), r_b)
        denominator = denominator + dot(n, ang_a + ang_b)
    result: FloatArray = -(1.0 + e) * dot(v_ab, n) / denominator
    return result
