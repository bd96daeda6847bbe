"""Closed-form impulse laws for the collision of two spheres (3D) or disks (2D).

The laws of PHYSICS.md sections 1 and 3, for one pair or a batch (computed in one compiled
pass, :mod:`carom.laws.batch`; this module checks the arguments and shapes the result):

* **smooth** spheres: an impulse along the line of centres with Newton's restitution ``e``;
* **rough** spheres with a constant tangential restitution ``beta``;
* **Walton's** Coulomb model: ``beta`` capped so that the tangential impulse never exceeds
  ``friction`` times the normal impulse.

All three apply one impulse ``J`` (on body 1; ``-J`` on body 2) at the contact point, so linear
momentum is conserved exactly and angular momentum about the contact point is conserved.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields
from typing import Any

import numpy as np
from numpy.typing import ArrayLike

from carom._inputs import (
    FloatArray,
    PairInputs,
    check_not_both_static,
    dot,
)
from carom.errors import CaromError
from carom.laws.batch import CASE_PAIRS, case_of, collide_rows, streams
from carom.laws.kernels import LAW_ROUGH, LAW_SMOOTH, LAW_WALTON

__all__ = [
    "CollisionResult",
    "collide",
    "default_inertia_factor",
    "inertia_factors",
    "kinetic_energy",
    "read_pair",
]


def default_inertia_factor(dim: int) -> float:
    """Inertia factor ``q`` in ``I = q m a^2`` of a uniform body: 2/5 sphere (3D), 1/2 disk (2D)."""
    return 0.4 if dim == 3 else 0.5


@dataclass(frozen=True)
class CollisionResult:
    """The outcome of a two-body impact; every field has the caller's batch shape.

    For a single pair vectors are ``(d,)`` and scalars are NumPy float64 scalars; for a batch of
    ``n`` pairs vectors are ``(n, d)`` and scalars ``(n,)``. Spins are scalars per body in 2D and
    3-vectors in 3D.

    Attributes
    ----------
    v1, v2 : (d,) or (n, d) float64
        Velocities after the impact [m/s].
    w1, w2 : float, (3,), (n,) or (n, 3) float64, or None
        Spins after the impact [rad/s]; ``None`` when the call neither gave spins nor used a
        rough law.
    impulse : (d,) or (n, d) float64
        Impulse on body 1 [N s]; body 2 receives its opposite. Zero where ``applied`` is false.
    normal : (d,) or (n, d) float64
        Unit impulse direction used by the law; for :func:`collide` the line of centres,
        pointing from body 2 to body 1.
    approach_speed : float or (n,) float64
        Normal closing speed before the impact, ``-(v1 - v2) . n`` [m/s]; positive when the
        pair approaches.
    separation_speed : float or (n,) float64
        Normal opening speed after the impact, ``(v1' - v2') . n`` [m/s]; equals
        ``e * approach_speed`` under Newton's law.
    relative_speed_after : float or (n,) float64
        ``|v1' - v2'|`` [m/s], the speed at which the centres move apart.
    ke_before, ke_after : float or (n,) float64
        Kinetic energy, translational plus rotational, of the bodies of finite mass [J].
        Rotational energy is counted when spins are given or a rough law is used.
    ke_lost : float or (n,) float64
        Energy dissipated by the impact, from the closed form
        ``1/2 mu (1 - e^2) u^2 + 1/2 mu_t (1 - beta^2) |g_t|^2`` [J] (never negative). Equals
        ``ke_before - ke_after`` unless a partner of infinite mass moves (it then does work).
    beta : float or (n,) float64, or None
        Tangential restitution actually applied (Walton's cap included); ``None`` for smooth.
    applied : bool or (n,) bool
        Whether an impulse was applied: false for a pair already separating, or at rest
        relative to each other, along the normal.
    """

    v1: FloatArray
    v2: FloatArray
    w1: FloatArray | None
    w2: FloatArray | None
    impulse: FloatArray
    normal: FloatArray
    approach_speed: FloatArray
    separation_speed: FloatArray
    relative_speed_after: FloatArray
    ke_before: FloatArray
    ke_after: FloatArray
    ke_lost: FloatArray
    beta: FloatArray | None
    applied: Any

    def unbatched(self) -> CollisionResult:
        """The same result with the batch axis of length 1 removed."""
        values: dict[str, Any] = {}
        for f in fields(self):
            value = getattr(self, f.name)
            if value is None:
                values[f.name] = None
            elif f.name == "applied":
                values[f.name] = bool(value[0])
            else:
                values[f.name] = value[0]
        return CollisionResult(**values)


def kinetic_energy(
    m: FloatArray,
    v: FloatArray,
    w: FloatArray | None,
    radius: FloatArray | None,
    q: float,
) -> FloatArray:
    """``1/2 m |v|^2 + 1/2 q m a^2 |w|^2`` per row [J]; a body of infinite mass counts zero."""
    finite = np.isfinite(m)
    m_f = np.where(finite, m, 0.0)
    ke = 0.5 * m_f * dot(v, v)
    if w is not None and radius is not None:
        w_squared = w * w if w.ndim == 1 else dot(w, w)
        ke = ke + 0.5 * q * m_f * radius * radius * w_squared
    return ke


def collide(
    x1: ArrayLike,
    v1: ArrayLike,
    m1: ArrayLike,
    x2: ArrayLike,
    v2: ArrayLike,
    m2: ArrayLike,
    *,
    e: ArrayLike = 1.0,
    w1: ArrayLike | None = None,
    w2: ArrayLike | None = None,
    radius1: ArrayLike | None = None,
    radius2: ArrayLike | None = None,
    q: float | tuple[float, float] | None = None,
    beta: ArrayLike | None = None,
    friction: ArrayLike | None = None,
    beta0: ArrayLike | None = None,
    out: CollisionResult | None = None,
) -> CollisionResult:
    r"""Velocities (and spins) of two spheres or disks just after they collide.

    The impulse on body 1 is (PHYSICS.md sections 1 and 3)

    .. math::

        J = -\mu (1 + e) g_n - \mu_t (1 + \beta) g_t,

    with ``n = (x1 - x2)/|x1 - x2|``, contact-point relative velocity
    ``g = v1 - v2 - (a1 w1 + a2 w2) x n`` split into ``g_n = (g.n) n`` and ``g_t = g - g_n``,
    reduced mass ``mu = m1 m2 / (m1 + m2)`` and tangential effective mass
    ``1/mu_t = (1 + 1/q1)/m1 + (1 + 1/q2)/m2``. Then ``v1' = v1 + J/m1``,
    ``v2' = v2 - J/m2``, ``w_i' = w_i - a_i (n x J) / I_i`` with ``I_i = q_i m_i a_i^2``, so
    ``g_n' = -e g_n`` and ``g_t' = -beta g_t``. Smooth spheres have no tangential impulse
    (``beta = -1``). Walton's model (``friction`` given) uses
    ``beta = min(beta0, -1 + friction (1 + e) (mu/mu_t) |g_n| / |g_t|)`` so that
    ``|J_t| <= friction |J_n|`` (Luding et al., PRE 58, 3416, 1998). A pair that is not
    approaching (``(v1 - v2) . n >= 0``) receives no impulse.

    Parameters
    ----------
    x1, x2 : (d,) or (n, d) array_like
        Centres at the instant of impact [m], d = 2 or 3. Only the direction ``x1 - x2``
        matters; the centres must not coincide.
    v1, v2 : (d,) or (n, d) array_like
        Velocities before the impact [m/s].
    m1, m2 : float or (n,) array_like
        Masses [kg], positive; ``math.inf`` makes a body static (a wall or a pinned sphere).
        At most one body of a pair may be static.
    e : float or (n,) array_like, default 1.0
        Normal coefficient of restitution in [0, 1] [-]: 1 elastic, 0 perfectly plastic.
    w1, w2 : float, (3,), (n,) or (n, 3) array_like, optional
        Spins before the impact [rad/s]: a scalar per body in 2D, a 3-vector in 3D.
        Default zero. Giving spins requires the radii.
    radius1, radius2 : float or (n,) array_like, optional
        Radii ``a1``, ``a2`` [m], positive; required by the rough laws and by spins.
    q : float or (float, float), optional
        Inertia factors ``I = q m a^2`` in (0, 1] [-], one for both bodies or one each.
        Default 2/5 (solid sphere) in 3D, 1/2 (disk) in 2D.
    beta : float or (n,) array_like, optional
        Constant tangential restitution in [-1, 1] [-]: -1 smooth, 0 the contact point stops
        sliding, +1 perfectly rough. Not together with ``friction``.
    friction : float or (n,) array_like, optional
        Coulomb friction coefficient ``mu_f >= 0`` [-] for Walton's model.
    beta0 : float or (n,) array_like, optional
        Walton's sticking tangential restitution in [-1, 1] [-], default 0 (plain Coulomb
        friction: a sticking contact stops slipping; glass beads have about 0.4).
    out : CollisionResult, optional
        The result of an earlier batch call with the same batch length, dimension and law,
        to be written over instead of allocating new arrays (for calls in a loop). It is
        returned. Its arrays must not share memory with the inputs. If the call raises, they
        may have been partly written.

    Returns
    -------
    CollisionResult
        Velocities, spins, impulse, normal, speeds and energies in the caller's batch shape.

    Raises
    ------
    CaromError
        A subclass of ``ValueError`` naming the argument and offending value: masses not
        positive (or both infinite), non-finite vectors, ``e``, ``beta``, ``beta0`` out of
        range, negative ``friction``, coincident centres, batch lengths that do not
        broadcast, a dimension other than 2 or 3, or a missing radius.

    Examples
    --------
    Equal masses, head-on, elastic: the spheres exchange velocities.

    >>> import carom
    >>> r = carom.collide([0, 0], [1, 0], 1.0, [0.2, 0], [-1, 0], 1.0, e=1.0)
    >>> r.v1.tolist(), r.v2.tolist()
    ([-1.0, 0.0], [1.0, 0.0])
    >>> float(r.ke_lost)
    0.0
    """
    rough = beta is not None or friction is not None
    if beta is not None and friction is not None:
        raise CaromError(
            "give either beta (constant tangential restitution) or friction (Walton's Coulomb "
            "model, with beta0 as its sticking restitution), not both"
        )
    if beta0 is not None and friction is None:
        raise CaromError("beta0 is Walton's sticking restitution and needs friction= as well")

    spins = w1 is not None or w2 is not None or rough
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
        radii_for="the rough laws" if rough else "spins",
        defer_values=True,
    )
    assert inp.dim is not None
    dim = inp.dim
    q1, q2 = inertia_factors(q, dim)
    if beta is not None:
        inp.scalar("beta", beta, low=-1.0, high=1.0, unit="-", hint="-1 smooth, +1 rough")
    if friction is not None:
        inp.scalar("friction", friction, low=0.0, high=math.inf, unit="-")
        inp.scalar("beta0", 0.0 if beta0 is None else beta0, low=-1.0, high=1.0, unit="-")

    walton = friction is not None
    if out is not None and inp.single:
        raise CaromError("out= takes the result of a batch call; a single pair returns scalars")
    batch = _collide_rows(inp, rough=rough, spins=spins, walton=walton, q1=q1, q2=q2, out=out)
    if batch is None:  # a pair was refused: name it, with the checks that know every argument
        inp.check_values()
        _, a = inp.broadcast()
        check_not_both_static(a["m1"], a["m2"])
        _check_centres_apart(a["x1"], a["x2"])
        raise AssertionError("carom.laws.batch refused a pair that the argument checks accept")
    return batch.unbatched() if inp.single else batch


def _collide_rows(
    inp: PairInputs,
    *,
    rough: bool,
    spins: bool,
    walton: bool,
    q1: float,
    q2: float,
    out: CollisionResult | None,
) -> CollisionResult | None:
    """:func:`collide` in one compiled pass (:func:`carom.laws.batch.collide_rows`); ``None``
    when the pass refuses a pair, for the caller to name what is wrong."""
    assert inp.dim is not None
    n, dim = inp.length(), inp.dim
    law = LAW_WALTON if walton else LAW_ROUGH if rough else LAW_SMOOTH
    names = ["x1", "v1", "m1", "x2", "v2", "m2", "e"]
    if spins:
        names += ["w1", "w2", "radius1", "radius2"]
    inputs = {name: inp.rows(name) for name in names}
    if rough:
        inputs["beta"] = inp.rows("beta0" if walton else "beta")
    if walton:
        inputs["friction"] = inp.rows("friction")
    res = _result_arrays(n, dim, spins=spins, rough=rough, out=out, inputs=inputs)
    unused = np.zeros(1)
    no_spin = np.zeros((1, 1 if dim == 2 else 3))
    case = case_of(dim, law, spins) if n >= CASE_PAIRS else 0
    # results written over (out=) go past the caches when they are large, in a case's own
    # pass; fresh ones are not: their pages, zeroed by the system as the pass first touches
    # them, are in the cache then, and plain stores were faster there (0.86-0.91x streamed)
    stream = (
        case != 0
        and out is not None
        and streams([a for f in fields(CollisionResult) if (a := getattr(res, f.name)) is not None])
    )
    # a refused pair may divide by zero; compiled, that is IEEE arithmetic without a word, and
    # the same under NUMBA_DISABLE_JIT
    with np.errstate(all="ignore"):
        refused = collide_rows(
            case,
            inputs["x1"],
            inputs["v1"],
            inputs["m1"],
            inputs["x2"],
            inputs["v2"],
            inputs["m2"],
            inputs["e"],
            inputs.get("w1", no_spin),
            inputs.get("w2", no_spin),
            inputs.get("radius1", unused),
            inputs.get("radius2", unused),
            inputs.get("beta", unused),
            inputs.get("friction", unused),
            law,
            spins,
            q1,
            q2,
            stream,
            res.v1,
            res.v2,
            no_spin if res.w1 is None else res.w1.reshape(n, -1),
            no_spin if res.w2 is None else res.w2.reshape(n, -1),
            res.impulse,
            res.normal,
            res.approach_speed,
            res.separation_speed,
            res.relative_speed_after,
            res.ke_before,
            res.ke_after,
            res.ke_lost,
            unused if res.beta is None else res.beta,
            res.applied,
        )
    return None if refused >= 0 else res


def _result_arrays(
    n: int,
    dim: int,
    *,
    spins: bool,
    rough: bool,
    out: CollisionResult | None,
    inputs: dict[str, FloatArray],
) -> CollisionResult:
    """Fresh arrays for a batch's result, or ``out``'s once they are checked to fit."""
    spin_shape = (n,) if dim == 2 else (n, 3)
    shapes: dict[str, tuple[int, ...] | None] = {f.name: (n,) for f in fields(CollisionResult)}
    shapes.update(v1=(n, dim), v2=(n, dim), impulse=(n, dim), normal=(n, dim))
    shapes.update(w1=spin_shape if spins else None, w2=spin_shape if spins else None)
    shapes.update(beta=(n,) if rough else None)
    if out is None:
        made: dict[str, Any] = {
            name: None if shape is None else np.empty(shape, dtype=_dtype(name))
            for name, shape in shapes.items()
        }
        return CollisionResult(**made)
    if not isinstance(out, CollisionResult):
        raise CaromError(
            f"out must be the CollisionResult of an earlier batch call; got {type(out).__name__}"
        )
    taken: dict[str, FloatArray] = {}
    for name, shape in shapes.items():
        value = getattr(out, name)
        if shape is None and value is None:
            continue
        fits = (
            shape is not None
            and isinstance(value, np.ndarray)
            and value.shape == shape
            and value.dtype == _dtype(name)
            and value.flags.c_contiguous
            and value.flags.writeable
        )
        if not fits:
            need = (
                "no array"
                if shape is None
                else f"a writeable C-contiguous {np.dtype(_dtype(name))} array of shape {shape}"
            )
            got = f"shape {value.shape}" if isinstance(value, np.ndarray) else repr(value)
            raise CaromError(
                f"out.{name} does not fit this call: it needs {need}, got {got}; pass the "
                f"result of a batch call with the same length, dimension and law"
            )
        for other, arr in (*taken.items(), *inputs.items()):
            if np.may_share_memory(value, arr):
                where = f"out.{other}" if other in taken else other
                raise CaromError(f"out.{name} shares memory with {where}; give it its own array")
        taken[name] = value
    return out


def _dtype(name: str) -> type:
    """The dtype of a result field: bool for ``applied``, float64 otherwise."""
    return np.bool_ if name == "applied" else np.float64


def read_pair(
    x1: ArrayLike,
    v1: ArrayLike,
    m1: ArrayLike,
    x2: ArrayLike,
    v2: ArrayLike,
    m2: ArrayLike,
    *,
    e: ArrayLike,
    w1: ArrayLike | None,
    w2: ArrayLike | None,
    radius1: ArrayLike | None,
    radius2: ArrayLike | None,
    with_spins: bool,
    radii_for: str,
    defer_values: bool = False,
) -> PairInputs:
    """Check the arguments every two-body law shares and register them for broadcasting.

    With ``with_spins`` the spins default to zero and both radii are required
    (``radii_for`` says why, in the error). ``defer_values`` leaves the value checks to
    :meth:`PairInputs.check_values`.
    """
    inp = PairInputs(defer_values=defer_values)
    inp.vector("x1", x1, unit="m")
    inp.vector("v1", v1, unit="m/s")
    inp.vector("x2", x2, unit="m")
    inp.vector("v2", v2, unit="m/s")
    _register_masses(inp, m1, m2)
    inp.scalar("e", e, low=0.0, high=1.0, unit="-", hint="1 elastic, 0 perfectly plastic")
    assert inp.dim is not None
    if with_spins:
        zero_spin: float | list[float] = 0.0 if inp.dim == 2 else [0.0, 0.0, 0.0]
        inp.spin("w1", zero_spin if w1 is None else w1)
        inp.spin("w2", zero_spin if w2 is None else w2)
        for name, value in (("radius1", radius1), ("radius2", radius2)):
            if value is None:
                raise CaromError(
                    f"{name} is required with {radii_for}: the contact point lies one radius "
                    f"from the centre; pass radius1= and radius2= in metres"
                )
            inp.scalar(name, value, low=0.0, high=math.inf, low_open=True, unit="m")
    return inp


def _register_masses(inp: PairInputs, m1: ArrayLike, m2: ArrayLike) -> None:
    """Masses in (0, inf]; :func:`check_not_both_static` follows the broadcast."""
    hint = "use math.inf for a static body"
    for name, value in (("m1", m1), ("m2", m2)):
        inp.scalar(
            name, value, low=0.0, high=math.inf, low_open=True, allow_inf=True, unit="kg", hint=hint
        )


def inertia_factors(q: float | tuple[float, float] | None, dim: int) -> tuple[float, float]:
    """Validated (q1, q2) from the ``q`` argument."""
    if q is None:
        default = default_inertia_factor(dim)
        return default, default
    pair = [q, q] if np.ndim(q) == 0 else list(np.asarray(q, dtype=float).ravel())
    if len(pair) != 2:
        raise CaromError(f"q must be one inertia factor or a pair (q1, q2); got {q!r}")
    out = []
    for name, given in zip(("q1", "q2"), pair, strict=True):
        value = float(given)  # type: ignore[arg-type]
        if not 0.0 < value <= 1.0:
            raise CaromError(
                f"q must lie in (0, 1] (I = q m a^2: 2/5 solid sphere, 1/2 disk, 2/3 thin "
                f"shell); got {name} = {value!r}"
            )
        out.append(value)
    return out[0], out[1]


def _check_centres_apart(x1: FloatArray, x2: FloatArray) -> None:
    """Refuse a pair whose centres coincide: its line of centres is undefined."""
    r = x1 - x2
    coincident = dot(r, r) == 0.0
    if coincident.any():
        i = int(np.argmax(coincident))
        raise CaromError(
            f"x1 and x2 coincide at index {i} (both at {x1[i].tolist()}): the line of centres, "
            f"and so the contact normal, is undefined; give the centres at the instant of contact"
        )
