"""What a user gives for bodies, checked and turned into rows of the body table.

:class:`carom.World`'s ``add_*`` methods take positions, velocities, radii, masses, turns and
spins in the shapes a person writes them (one for all, or one per body; a quaternion or a
rotation matrix); the functions here check each against the world's dimension and carom's
limits, name what is wrong in a :class:`~carom.errors.CaromError`, and return float64 arrays of
one row per body. :func:`shaped_bodies` places rigid bodies of one shape, in 2D and 3D alike.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from typing import NamedTuple

import numpy as np
from numpy.typing import ArrayLike, NDArray

from carom._inputs import as_float_array
from carom.bodies import BODY_KINDS, KIND_DYNAMIC, Pieces
from carom.errors import CaromError
from carom.geometry.rotation import matrix_quaternion, rotation_matrices
from carom.limits import (
    LARGEST,
    MAX_BODIES,
    RESOLUTION,
    SMALLEST,
    check_magnitude,
    check_size,
)
from carom.meshes import Mesh
from carom.shape_base import SHAPE_CODES
from carom.shapes import Shape2D
from carom.shapes3d import ConvexPiece3D, Plane, Shape3D, TrianglePieces, rotation_matrix

__all__ = [
    "ShapedBodies",
    "angular_velocities",
    "dynamic_mass",
    "motion",
    "per_body",
    "per_value",
    "quaternions",
    "radii",
    "rows",
    "shaped_bodies",
    "vector",
]

FloatArray = NDArray[np.float64]


def vector(name: str, value: ArrayLike, dim: int, unit: str) -> FloatArray:
    """``value`` as ``dim`` finite numbers, or a CaromError naming ``name``."""
    try:
        arr = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise CaromError(f"{name} must be {dim} numbers [{unit}]; got {value!r}") from None
    if arr.shape != (dim,) or not np.all(np.isfinite(arr)):
        raise CaromError(f"{name} must be {dim} finite numbers [{unit}]; got {value!r}")
    return arr


def rows(name: str, value: ArrayLike, dim: int, n: int | None = None) -> FloatArray:
    """Positions or velocities, (n, d) [m] or [m/s]: ``(n, d)`` or one ``(d,)`` row for all
    (repeated to ``n`` when ``n`` is given), finite and within carom's limits."""
    unit = "m/s" if name in ("velocities", "velocity") else "m"
    arr = as_float_array(name, value)
    if arr.ndim == 1:
        arr = arr[None, :] if n is None or n == 1 or arr.shape[0] == dim else arr
    if arr.ndim != 2 or arr.shape[-1] != dim:
        raise CaromError(
            f"{name} must have shape (n, {dim}) or ({dim},) [{unit}]; got shape {arr.shape}"
        )
    if arr.shape[0] > MAX_BODIES:
        raise CaromError(
            f"{name} has {arr.shape[0]} rows; carom takes at most {MAX_BODIES:,} bodies "
            f"(docs/scenes.md, Limits)"
        )
    if n is not None:
        if arr.shape[0] == 1 and n > 1:
            arr = np.repeat(arr, n, axis=0)
        if arr.shape[0] != n:
            raise CaromError(f"{name} has {arr.shape[0]} rows; expected {n}")
    if not np.all(np.isfinite(arr)):
        bad = int(np.argmax(~np.all(np.isfinite(arr), axis=1)))
        raise CaromError(f"{name}[{bad}] = {arr[bad].tolist()} is not finite")
    return np.array(check_magnitude(name, arr, unit))


def motion(
    positions: ArrayLike, velocities: ArrayLike | None, dim: int, singular: bool = False
) -> tuple[FloatArray, FloatArray]:
    """Positions (n, d) [m] and velocities (n, d) [m/s] of ``n`` bodies (:func:`rows`; one
    velocity row for all is repeated; None: at rest); ``singular`` names them in the
    singular in errors (``position``, ``velocity``)."""
    names = ("position", "velocity") if singular else ("positions", "velocities")
    x = rows(names[0], positions, dim)
    v = np.zeros_like(x) if velocities is None else rows(names[1], velocities, dim, len(x))
    return x, v


def per_body(name: str, value: ArrayLike, n: int, unit: str) -> FloatArray:
    """One positive, finite number per body (a scalar for all), (n,)."""
    arr = as_float_array(name, value)
    try:
        arr = np.broadcast_to(arr, (n,))
    except ValueError:
        raise CaromError(
            f"{name} must be a scalar or have {n} values; got shape {arr.shape}"
        ) from None
    bad = ~(arr > 0.0) | ~np.isfinite(arr)
    if bad.any():
        i = int(np.argmax(bad))
        raise CaromError(
            f"{name} must be positive and finite [{unit}]; got {name}[{i}] = {float(arr[i])!r}"
        )
    return np.array(check_size(name, arr, unit))


def per_value(name: str, value: ArrayLike, n: int, unit: str) -> FloatArray:
    """One finite number per body (a scalar for all), (n,), or a CaromError naming ``name``."""
    arr = as_float_array(name, value)
    try:
        arr = np.array(np.broadcast_to(arr.reshape(-1) if arr.ndim else arr, (n,)))
    except ValueError:
        raise CaromError(
            f"{name} must be one number or {n} of them [{unit}]; got shape {arr.shape}"
        ) from None
    if not np.all(np.isfinite(arr)):
        i = int(np.argmax(~np.isfinite(arr)))
        raise CaromError(f"{name} must be finite [{unit}]; got {name}[{i}] = {arr[i]!r}")
    return check_magnitude(name, arr, unit)


def radii(value: ArrayLike, n: int, box: FloatArray) -> FloatArray:
    """Radii (n,) [m], none below carom's resolution of the ``box`` (d,) [m]."""
    radius = per_body("radius", value, n, "m")
    smallest = RESOLUTION * float(box.max())
    if np.any(radius < smallest):
        i = int(np.argmax(radius < smallest))
        raise CaromError(
            f"radius[{i}] = {float(radius[i])!r} m is below {RESOLUTION:g} of the box "
            f"({smallest:g} m): positions are rounded to 1e-16 of the box, so its contacts "
            f"would be round-off; make it larger or the box smaller"
        )
    return radius


def angular_velocities(value: ArrayLike | None, n: int, dim: int) -> FloatArray:
    """Angular velocities (n, 3) [rad/s]: in 2D one number per body (about z, column 2), in
    3D a vector per body; None: zeros."""
    w = np.zeros((n, 3))
    if value is None:
        return w
    s = as_float_array("angular_velocities", value)
    if dim == 3 and s.ndim == 0:
        if s == 0.0:  # (the default: no spin)
            return w
        raise CaromError(
            f"angular_velocities is a vector [wx, wy, wz] [rad/s] in 3D, about the world's "
            f"axes; got the number {float(s)!r}: for a spin about z write [0, 0, {float(s)!r}]"
        )
    try:
        if dim == 2:
            w[:, 2] = np.broadcast_to(s.reshape(-1) if s.ndim else s, (n,))
        else:
            w[:] = np.broadcast_to(s, (n, 3))
    except ValueError:
        want = f"({n},) or one number" if dim == 2 else f"({n}, 3) or (3,)"
        raise CaromError(
            f"angular_velocities must have shape {want} [rad/s]; got {s.shape}"
        ) from None
    if not np.all(np.isfinite(w)):
        bad = int(np.argmax(~np.all(np.isfinite(w), axis=1)))
        raise CaromError(f"angular_velocities[{bad}] = {w[bad].tolist()} is not finite")
    return check_magnitude("angular_velocities", w, "rad/s")


def quaternions(value: ArrayLike | None, n: int) -> FloatArray:
    """``n`` unit quaternions (n, 4) from quaternions or rotation matrices (one for all, or
    one each); None: unturned."""
    q = np.zeros((n, 4))
    q[:, 0] = 1.0
    if value is None:
        return q
    arr = as_float_array("orientations", value)
    if arr.shape in ((4,), (3, 3)):
        arr = arr[None]
    if arr.ndim not in (2, 3) or arr.shape[1:] not in ((4,), (3, 3)) or arr.shape[0] not in (1, n):
        raise CaromError(
            f"orientations must be quaternions (n, 4) or (4,), or rotation matrices "
            f"(n, 3, 3) or (3, 3); got shape {arr.shape} for {n} bodies"
        )
    for i in range(n):
        each = arr[i if arr.shape[0] == n else 0]
        q[i] = matrix_quaternion(rotation_matrix(each, f"orientations[{i}]"))
    return q


class ShapedBodies(NamedTuple):
    """Rigid bodies of one shape, as rows of the body table
    (:meth:`carom.bodies.Bodies.append_bodies` takes them in this order).

    Attributes
    ----------
    centre, velocity : (n, d) float64
        Centres of mass [m], their velocities [m/s].
    turn : (n,) float64 (2D) or (n, 4) float64 (3D)
        Angles [rad] or unit quaternions.
    spin : (n,) float64 (2D) or (n, 3) float64 (3D)
        [rad/s].
    pieces : tuple
        The shape's convex pieces about its centre of mass.
    shape : int
        Its code (:data:`carom.shape_base.SHAPE_CODES`).
    mass : float
        [kg] (inf: static or kinematic).
    inertia : float or (3, 3) float64
        About the centre of mass [kg m^2] (2D: about z).
    kind : int
        :data:`carom.bodies.BODY_KINDS`' code.
    """

    centre: FloatArray
    velocity: FloatArray
    turn: FloatArray
    spin: FloatArray
    pieces: Pieces
    shape: int
    mass: float
    inertia: float | FloatArray
    kind: int


def _check_shape(shape: object, dim: int) -> None:
    """Refuse a shape of the other dimension, a plane, or what is not a carom shape."""
    if dim == 3 and isinstance(shape, Plane):
        raise CaromError(
            "a Plane is static ground: add it with World.add_plane(point, normal) "
            f"(here point {(shape.offset * np.asarray(shape.normal)).tolist()}, normal "
            f"{np.asarray(shape.normal).tolist()})"
        )
    mine, other = (Shape2D, Shape3D) if dim == 2 else (Shape3D, Shape2D)
    if isinstance(shape, other):
        theirs, ours = (
            ("carom.shapes3d", "carom.shapes") if dim == 2 else ("carom.shapes", "carom.shapes3d")
        )
        raise CaromError(
            f"{type(shape).__name__} is a {5 - dim}D shape ({theirs}) and this world is "
            f"{dim}D; use {ours}, or World({5 - dim}, ...)"
        )
    if not isinstance(shape, mine):
        listed = (
            "carom.shapes shape (Circle, Capsule, Box, Polygon, Compound, Segment, Chain)"
            if dim == 2
            else "carom.shapes3d shape (Sphere, Capsule, Box, Hull, Compound) or a "
            "carom.meshes.Mesh in a 3D world"
        )
        raise CaromError(f"shape must be a {listed}; got {shape!r}")


def shaped_bodies(
    dim: int,
    shape: Shape2D | Shape3D,
    positions: ArrayLike,
    velocities: ArrayLike | None,
    *,
    angles: ArrayLike,
    orientations: ArrayLike | None,
    spins: ArrayLike,
    density: float | None,
    mass: float | None,
    kind: str,
) -> ShapedBodies:
    """Bodies of one ``shape`` with their shape origins at ``positions`` (n, d) [m], moving
    at ``velocities`` (n, d) [m/s] (None: at rest), turned by ``angles`` (2D: [rad], one or n) or
    ``orientations`` (3D: quaternions or rotation matrices, one or n; None: unturned) and
    spinning at ``spins`` [rad/s]; a dynamic body's mass from ``density`` or ``mass``
    (default density 1), none for a static or kinematic one. The centre of mass is where the
    body is reported."""
    _check_shape(shape, dim)
    if dim == 2 and orientations is not None:
        raise CaromError("orientations= is for 3D bodies; a 2D body takes angles= [rad]")
    if dim == 3 and np.any(as_float_array("angles", angles) != 0.0):
        raise CaromError("angles= is for 2D bodies; a 3D body takes orientations=")
    if kind not in BODY_KINDS:
        raise CaromError(f"kind must be one of {tuple(BODY_KINDS)}; got {kind!r}")
    code = BODY_KINDS[kind]
    origin, velocity = motion(positions, velocities, dim, singular=True)
    n = origin.shape[0]
    if not isinstance(shape, Mesh):
        _check_extent(shape, shape.pieces())
    if dim == 2:
        assert isinstance(shape, Shape2D)
        turn = per_value("angle", angles, n, "rad")
        spin = per_value("angular_velocity", spins, n, "rad/s")
        pieces3d: Sequence[ConvexPiece3D] = ()
        with _in_float64(shape):
            centroid = shape.centroid
    else:
        assert isinstance(shape, Shape3D)
        turn = quaternions(orientations, n)
        spin = angular_velocities(spins, n, 3)
        if isinstance(shape, Mesh):
            if kind != "static":
                raise CaromError(
                    "a Mesh is a static surface; add it with kind='static', or cut a closed "
                    "mesh into convex pieces for a dynamic body: carom.meshes.decompose(path)"
                )
            pieces3d = TrianglePieces(shape.vertices, shape.triangles)
            centroid = np.zeros(3)
        else:
            pieces3d = shape.pieces()
            with _in_float64(shape):
                centroid = shape.centroid
    if code == KIND_DYNAMIC:
        body_mass, inertia, centroid = dynamic_mass(shape, density, mass)
    else:
        _check_still(kind, density, mass, velocity, spin)
        body_mass = math.inf
        inertia = math.inf if dim == 2 else np.diag([math.inf] * 3)
    moved: Pieces
    if isinstance(shape, Shape2D):
        c, s = np.cos(turn), np.sin(turn)
        centre = origin + np.stack(
            [c * centroid[0] - s * centroid[1], s * centroid[0] + c * centroid[1]], axis=1
        )
        moved = tuple(piece.moved(-centroid, 0.0) for piece in shape.pieces())
        name = shape.kind
    else:
        centre = origin + rotation_matrices(turn) @ centroid
        # (a mesh's triangles stay one block: its frame is the world's, nothing to move)
        moved = (
            pieces3d
            if isinstance(pieces3d, TrianglePieces)
            else tuple(piece.moved(np.eye(3), -centroid) for piece in pieces3d)
        )
        name = "ball" if shape.kind == "sphere" else shape.kind
    return ShapedBodies(
        centre, velocity, turn, spin, moved, SHAPE_CODES[name], body_mass, inertia, code
    )


def _check_extent(shape: Shape2D | Shape3D, pieces: Pieces) -> None:
    """Refuse a shape whose farthest point from its origin lies outside carom's sizes
    (:data:`carom.limits.SMALLEST` to :data:`carom.limits.LARGEST` metres)."""
    extent = 0.0
    for piece in pieces:
        corners = np.abs(np.asarray(piece.vertices, dtype=np.float64))
        far = float(np.max(corners)) if corners.size else 0.0
        extent = max(extent, far + float(piece.radius))
    if not SMALLEST <= extent <= LARGEST:
        raise CaromError(
            f"the {shape.kind} reaches {extent:.3g} m from its origin; carom takes shapes from "
            f"{SMALLEST:g} to {LARGEST:g} m across (docs/scenes.md, Limits): scale it"
        )


@contextmanager
def _in_float64(shape: Shape2D | Shape3D) -> Iterator[None]:
    """Compute a shape's area or volume moments with float64's overflow and division by zero
    refused: a shape large enough that its moments (up to the size's fourth or fifth power)
    overflow is refused with what to do, not run on infinities."""
    try:
        with np.errstate(over="raise", under="ignore", invalid="raise", divide="raise"):
            yield
    except (OverflowError, ZeroDivisionError, FloatingPointError, np.linalg.LinAlgError):
        raise CaromError(
            f"the {shape.kind}'s mass and inertia overflow float64 at this size (its moments "
            f"grow as the size to the fourth power); scale the shape (carom takes magnitudes "
            f"up to {LARGEST:g} in SI units, docs/scenes.md, Limits)"
        ) from None


def dynamic_mass(
    shape: Shape2D | Shape3D, density: float | None, mass: float | None
) -> tuple[float, FloatArray | float, FloatArray]:
    """A dynamic body's mass [kg], inertia about its centroid and centroid, refused when the
    mass lies outside carom's range or the inertia is not finite and positive (a shape too
    small or too large for its mass: its integrals underflow or overflow in float64)."""
    given = 1.0 if density is None and mass is None else density
    what = f"the {shape.kind}"
    with _in_float64(shape):
        props = shape.mass_properties(given, mass=mass)
    body_mass = float(props.mass)
    if not SMALLEST <= body_mass <= LARGEST:
        raise CaromError(
            f"{what} weighs {body_mass:.3g} kg; carom takes masses from {SMALLEST:g} to "
            f"{LARGEST:g} kg (docs/scenes.md, Limits): change its size, density or mass"
        )
    inertia = np.asarray(props.inertia, dtype=np.float64)
    moments = inertia if inertia.ndim == 0 else np.linalg.eigvalsh(inertia)
    if not (np.all(np.isfinite(moments)) and np.all(moments > 0.0)):
        raise CaromError(
            f"{what}'s moment of inertia ({np.min(moments):.3g} kg m^2) is not a finite, "
            f"positive number in float64: its size and mass ({body_mass:.3g} kg) are too far "
            f"apart; scale the shape or its mass"
        )
    return body_mass, props.inertia, props.centroid


def _check_still(
    kind: str, density: float | None, mass: float | None, v: FloatArray, spin: FloatArray
) -> None:
    """Refuse a mass for a static or kinematic body, and motion for a static one."""
    if density is not None or mass is not None:
        raise CaromError(
            f"a {kind} body is not moved by impacts and has no mass; drop density= and mass=, "
            f"or make it dynamic"
        )
    if kind == "static" and (np.any(v) or np.any(spin)):
        raise CaromError(
            "a static body never moves; drop velocity= and angular_velocity=, or make it "
            'kind="kinematic"'
        )
