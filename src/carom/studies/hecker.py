"""Chris Hecker's impulse formula, as published, and its one-dimensional "head-on" reading.

The formula itself, for general rigid bodies, is :func:`carom.laws.point_impulse.impulse`
(re-exported here as :func:`impulse`, the name the study and README use):

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
    check_not_both_static,
    cross_scalar_vector,
    cross_vector_vector,
    dot,
    inverse_mass,
)
from carom.errors import CaromError
from carom.laws.point_impulse import apply_tensor, impulse, impulse_batch
from carom.laws.spheres import (
    CollisionResult,
    inertia_factors,
    kinetic_energy,
    read_pair,
)

__all__ = ["Reading", "collide", "impulse"]

Reading = Literal["contact", "head-on"]
READINGS: tuple[Reading, ...] = ("contact", "head-on")


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

    >>> from carom.studies import hecker
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
    j = impulse_batch(v_ab, n, inv_m1, inv_m2, r_a, r_b, inv_i1, inv_i2, ea)
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
            w1_after = w1a + apply_tensor(inv_i1, t1)
            w2_after = w2a - apply_tensor(inv_i2, t2)

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
    return result.unbatched() if inp.single else result
