"""The engine-neutral body table: shape, mass, inertia, material and pose of every body, as
structure-of-arrays, numbered as the caller added them.

A :class:`carom.World` keeps its bodies here; an engine is built from the table and hands the
bodies' state back in the same numbering. Static and kinematic bodies have infinite mass.
Spheres are described by their radius; other shapes (:mod:`carom.shapes`) by their rounded
convex pieces in the body's frame, centred on its centre of mass.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Protocol

import numpy as np
from numpy.typing import NDArray

from carom.laws.kinds import BODY_KINDS, KIND_DYNAMIC, KIND_KINEMATIC, KIND_STATIC
from carom.shape_base import SHAPE_CODES
from carom.shapes import ConvexPiece
from carom.shapes3d import ConvexPiece3D, TrianglePieces

__all__ = [
    "BODY_KINDS",
    "KIND_DYNAMIC",
    "KIND_KINEMATIC",
    "KIND_STATIC",
    "PIECE_ARRAYS",
    "Bodies",
    "Lender",
    "Pieces",
    "identity_orientations",
    "pieces_from_arrays",
    "pieces_to_arrays",
]

FloatArray = NDArray[np.float64]


#: the flat arrays that hold every body's pieces (checkpoints, trajectories)
PIECE_ARRAYS = ("owner", "radius", "corners", "vertices", "faces", "triangles")

#: a body's pieces: rounded convex polygons in 2D, rounded convex solids in 3D (a static
#: mesh's triangles as one block, :class:`carom.shapes3d.TrianglePieces`)
Pieces = tuple[ConvexPiece, ...] | tuple[ConvexPiece3D, ...] | TrianglePieces

#: every body's position, velocity, orientation and spin, as an engine samples them
Motion = tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]


class Lender(Protocol):
    """An engine that holds the bodies' motion while it runs (:meth:`Bodies.lend`)."""

    @property
    def spinning(self) -> bool:
        """False when every body stays unrotated and still for the engine's whole run."""
        ...

    def sample(self) -> Motion:
        """Every body's position, velocity, orientation and spin at the engine's clock, in
        the table's numbering."""
        ...

    def sample_motion(self) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
        """:meth:`sample`'s positions and velocities alone."""
        ...


def pieces_to_arrays(pieces: list[Pieces], dim: int = 2) -> dict[str, NDArray[Any]]:
    """Every body's convex pieces as flat arrays: per piece its ``owner`` body (P,) int64,
    ``radius`` (P,) [m], number of ``corners`` (P,) int64 and of triangles, ``faces`` (P,)
    int64 (0 in 2D); all ``vertices`` (V, dim) [m] in order, in the bodies' frames (spheres
    of the event-driven engine have none), and all ``triangles`` (T, 3) int64, each piece's
    counting from its own first corner."""
    owner: list[int] = []
    radius: list[float] = []
    corners: list[int] = []
    faces: list[int] = []
    vertices, triangles = [np.zeros((0, dim))], [np.zeros((0, 3), np.int64)]
    blocks: list[tuple[int, int, TrianglePieces]] = []  # (body, where its rows go, block)
    for i, body in enumerate(pieces):
        if isinstance(body, TrianglePieces):
            blocks.append((i, len(owner), body))
            continue
        for piece in body:
            owner.append(i)
            radius.append(piece.radius)
            corners.append(piece.vertices.shape[0])
            vertices.append(piece.vertices)
            own = piece.triangles if isinstance(piece, ConvexPiece3D) else triangles[0]
            faces.append(own.shape[0])
            triangles.append(np.asarray(own, np.int64).reshape(-1, 3))
    arrays = {
        "owner": np.array(owner, np.int64),
        "radius": np.array(radius, np.float64),
        "corners": np.array(corners, np.int64),
        "vertices": np.concatenate(vertices),
        "faces": np.array(faces, np.int64),
        "triangles": np.concatenate(triangles),
    }
    return _with_blocks(arrays, blocks) if blocks else arrays


def _with_blocks(
    arrays: dict[str, NDArray[Any]], blocks: list[tuple[int, int, TrianglePieces]]
) -> dict[str, NDArray[Any]]:
    """:func:`pieces_to_arrays`' ``arrays`` with each mesh's triangles (a piece each: three
    corners, one triangle) put in at their body's place, in whole arrays."""
    piece_rows = np.cumsum(np.concatenate([[0], arrays["corners"]]))
    face_rows = np.cumsum(np.concatenate([[0], arrays["faces"]]))
    parts: dict[str, list[NDArray[Any]]] = {name: [] for name in arrays}
    done = 0
    for body, at, block in blocks:
        for name in ("owner", "radius", "corners", "faces"):
            parts[name].append(arrays[name][done:at])
        parts["vertices"].append(arrays["vertices"][piece_rows[done] : piece_rows[at]])
        parts["triangles"].append(arrays["triangles"][face_rows[done] : face_rows[at]])
        t = len(block)
        parts["owner"].append(np.full(t, body, np.int64))
        parts["radius"].append(np.zeros(t))
        parts["corners"].append(np.full(t, 3, np.int64))
        parts["faces"].append(np.ones(t, np.int64))
        parts["vertices"].append(block.corners().reshape(-1, 3))
        parts["triangles"].append(np.tile(np.arange(3, dtype=np.int64), (t, 1)))
        done = at
    for name in ("owner", "radius", "corners", "faces"):
        parts[name].append(arrays[name][done:])
    parts["vertices"].append(arrays["vertices"][piece_rows[done] :])
    parts["triangles"].append(arrays["triangles"][face_rows[done] :])
    return {name: np.concatenate(chunks) for name, chunks in parts.items()}


def pieces_from_arrays(arrays: Mapping[str, Any], n: int) -> list[Pieces]:
    """The ``n`` bodies' pieces from the arrays :func:`pieces_to_arrays` wrote (a mesh's
    triangles, the only pieces of three corners, come back as one block)."""
    # (only the bodies that have pieces get a list: 10^6 spheres took 0.35 s of lists)
    bodies: dict[int, list[Any]] = {}
    vertices = np.asarray(arrays["vertices"], np.float64)
    three = vertices.ndim == 2 and vertices.shape[1] == 3 and "triangles" in arrays
    triangles = np.asarray(arrays["triangles"], np.int64) if three else None
    owners = np.asarray(arrays["owner"], np.int64)
    counts = np.asarray(arrays["corners"], np.int64)
    result: list[Pieces] = [()] * n
    flat = counts == 3 if three else np.zeros(counts.shape[0], np.bool_)
    starts = np.concatenate([[0], np.cumsum(counts)[:-1]]).astype(np.int64)
    if flat.any():
        for owner in np.unique(owners[flat]).tolist():
            rows = starts[flat & (owners == owner)]
            corners = vertices[rows[:, None] + np.arange(3)].reshape(-1, 3)
            result[owner] = TrianglePieces(corners, np.arange(corners.shape[0]).reshape(-1, 3))
    faces = np.asarray(arrays["faces"], np.int64) if triangles is not None else counts * 0
    firsts = np.concatenate([[0], np.cumsum(faces)[:-1]]).astype(np.int64)
    radii = np.asarray(arrays["radius"], np.float64)
    for k in np.flatnonzero(~flat).tolist():
        row, count = int(starts[k]), int(counts[k])
        corners = vertices[row : row + count]
        if triangles is not None:
            own = triangles[firsts[k] : firsts[k] + faces[k]]
            piece: Any = ConvexPiece3D(corners, own, float(radii[k]))
        else:
            piece = ConvexPiece(corners, float(radii[k]))
        bodies.setdefault(int(owners[k]), []).append(piece)
    for owner, body in bodies.items():
        result[owner] = tuple(body)
    return result


def identity_orientations(n: int, dim: int) -> FloatArray:
    """``n`` bodies unrotated: angle 0 in 2D, (n, 1); quaternion ``(1, 0, 0, 0)`` in 3D, (n, 4)."""
    if dim == 2:
        return np.zeros((n, 1))
    q = np.zeros((n, 4))
    q[:, 0] = 1.0
    return q


def all_unrotated(orientation: FloatArray, dim: int) -> bool:
    """Whether every row of ``orientation`` ((n, 1) angles in 2D, (n, 4) quaternions in 3D)
    is the identity, bit for bit (an angle of -0.0 is not: it is given back as it was)."""
    if dim == 3:
        if np.any(orientation[:, 0] != 1.0):  # (1.0 has one bit pattern)
            return False
        orientation = orientation[:, 1:]
    return not np.any(orientation.view(np.int64))


def all_still(angular_velocity: FloatArray) -> bool:
    """Whether every spin in ``angular_velocity`` (n, 3) [rad/s] is +0.0, bit for bit."""
    return not np.any(angular_velocity.view(np.int64))


def _sphere_tensors(
    dim: int, mass: FloatArray, radius: FloatArray, inertia_factor: FloatArray
) -> FloatArray:
    """Spheres' inertia tensors, (n, 3, 3) [kg m^2]: ``q m a^2`` on the diagonal in 3D
    (inf for a static sphere, zeros off the diagonal), zero in 2D; from their masses [kg],
    radii [m] and factors ``q`` [-], (n,) each."""
    tensor = np.zeros((mass.shape[0], 3, 3))
    if dim == 3:
        with np.errstate(invalid="ignore"):  # static spheres: inf times 0 off the diagonal
            moment = np.where(np.isfinite(mass), inertia_factor * mass * radius**2, np.inf)
        tensor[:, [0, 1, 2], [0, 1, 2]] = moment[:, None]
    return tensor


class Bodies:
    """N bodies in ``dim`` dimensions.

    Attributes
    ----------
    position : (N, d) float64
        Centre of mass [m].
    velocity : (N, d) float64
        [m/s].
    orientation : (N, 1) float64 in 2D, (N, 4) in 3D
        Angle about z [rad]; unit quaternion ``w, x, y, z`` (body to world). While every
        body is unrotated it is not stored but made on each read (:attr:`unrotated`).
    angular_velocity : (N, 3) float64
        [rad/s], world frame (2D: about z, column 2). While no body spins it is not stored
        but made on each read (:attr:`still`). Together with the orientations, 56 bytes a
        sphere in 3D that a gas of smooth spheres does not keep.
    shape : (N,) int8
        Shape code (:data:`carom.shape_base.SHAPE_CODES`).
    radius : (N,) float64
        Sphere radius; for other shapes the farthest reach of the body from its centre of
        mass [m].
    mass : (N,) float64
        [kg]; inf for static and kinematic bodies.
    inertia_factor : (N,) float64
        ``q`` in ``I = q m a^2`` [-] (other shapes: their exact inertia over ``m a^2``; 3D
        bodies: a third of the trace of their inertia tensor over ``m a^2``).
    inertia_tensor : (N, 3, 3) float64
        3D: the inertia tensor about the centre of mass in the body's frame [kg m^2] (inf for
        static and kinematic bodies); 2D: unused, zero. While every body is a sphere it is
        not stored but made on each read from ``inertia_factor``, ``mass`` and ``radius``
        (72 bytes a sphere saved: 720 MB for 10^7 spheres).
    material : (N,) int64
        Index of the body's material in the World's list.
    kind : (N,) int8
        ``KIND_DYNAMIC``, ``KIND_STATIC`` or ``KIND_KINEMATIC``.
    pieces : list of N tuples of ConvexPiece (2D) or ConvexPiece3D (3D)
        Each body's pieces in its frame, centred on its centre of mass [m] (spheres of the
        event-driven engine: none).

    While an engine runs the bodies, the table may lend it their motion (:meth:`lend`):
    it then stores no positions, velocities, orientations or spins, and reads them from the
    engine, at its clock; :meth:`set_state` stores them again. An engine holds its own copy
    of the motion in its own layout, so the table's would only be a stale duplicate (48 MB
    for 10^6 spheres in 3D, at the peak of the engine's build). A read of the positions or
    velocities then samples those two alone, and an engine whose bodies never turn or spin
    is not asked for orientations or spins (104 MB a sample of 10^6 spheres in 3D, 48 of it
    the positions and velocities).
    """

    def __init__(self, dim: int) -> None:
        self.dim = dim
        self._lender: Lender | None = None  # the engine that holds the motion (lend)
        self._position: FloatArray | None = np.zeros((0, dim))
        self._velocity: FloatArray | None = np.zeros((0, dim))
        self._orientation: FloatArray | None = None  # None: every body unrotated
        self._angular_velocity: FloatArray | None = None  # None: no body spins
        self.shape = np.zeros(0, np.int8)
        self.radius = np.zeros(0)
        self.mass = np.zeros(0)
        self.inertia_factor = np.zeros(0)
        self._tensor: FloatArray | None = None  # None: every body a sphere (inertia_tensor)
        self.material = np.zeros(0, np.int64)
        self.kind = np.zeros(0, np.int8)
        self.pieces: list[Pieces] = []

    @property
    def n(self) -> int:
        return int(self.radius.shape[0])

    def lend(self, engine: Lender) -> None:
        """Hand the bodies' motion to ``engine``, which gives every body's position,
        velocity, orientation and spin at its clock, in this table's numbering: the table
        drops its own, and each read of one of them samples the engine (a new array) until
        :meth:`set_state` stores them again."""
        self._lender = engine
        self._position = self._velocity = self._orientation = self._angular_velocity = None

    @property
    def lent(self) -> bool:
        """True while an engine holds the bodies' motion (:meth:`lend`)."""
        return self._lender is not None

    def _stored(self) -> None:
        """Refuse a change to the table while its motion is lent (the World takes it back
        first: ``World._invalidate``)."""
        if self._lender is not None:
            raise RuntimeError("the bodies' motion is lent to an engine: set_state it first")

    @property
    def position(self) -> FloatArray:
        """Every body's centre of mass [m], (N, d) (see the class docstring)."""
        if self._lender is not None:
            return self._lender.sample_motion()[0]
        assert self._position is not None
        return self._position

    @position.setter
    def position(self, value: FloatArray) -> None:
        self._stored()
        self._position = value

    @property
    def velocity(self) -> FloatArray:
        """Every body's velocity [m/s], (N, d) (see the class docstring)."""
        if self._lender is not None:
            return self._lender.sample_motion()[1]
        assert self._velocity is not None
        return self._velocity

    @velocity.setter
    def velocity(self, value: FloatArray) -> None:
        self._stored()
        self._velocity = value

    @property
    def orientation(self) -> FloatArray:
        """Every body's orientation (see the class docstring); a new array of identities
        while :attr:`unrotated`, so write a whole new array rather than into this one."""
        if self._lender is not None and self._lender.spinning:
            return self._lender.sample()[2]
        return self._orientations(self.n)

    @orientation.setter
    def orientation(self, value: FloatArray) -> None:
        self._stored()
        value = np.asarray(value, np.float64)
        self._orientation = None if all_unrotated(value, self.dim) else value

    @property
    def angular_velocity(self) -> FloatArray:
        """Every body's spin [rad/s], (N, 3); a new array of zeros while :attr:`still`, so
        write a whole new array rather than into this one."""
        if self._lender is not None and self._lender.spinning:
            return self._lender.sample()[3]
        return self._spins(self.n)

    @angular_velocity.setter
    def angular_velocity(self, value: FloatArray) -> None:
        self._stored()
        value = np.asarray(value, np.float64)
        self._angular_velocity = None if all_still(value) else value

    def _orientations(self, n: int) -> FloatArray:
        """The first ``n`` orientations (stored, or identities)."""
        if self._orientation is not None:
            return self._orientation[:n]
        return identity_orientations(n, self.dim)

    def _spins(self, n: int) -> FloatArray:
        """The first ``n`` spins (stored, or zeros) [rad/s], (n, 3)."""
        if self._angular_velocity is not None:
            return self._angular_velocity[:n]
        return np.zeros((n, 3))

    def stored_motion(
        self,
    ) -> tuple[FloatArray, FloatArray, FloatArray | None, FloatArray | None]:
        """Positions (N, d) [m] and velocities (N, d) [m/s], with the orientations and spins
        [rad/s] only where the table would store them: None while every body is unrotated,
        or while none spins. A lending engine is sampled once."""
        if self._lender is None:
            return self.position, self.velocity, self._orientation, self._angular_velocity
        if not self._lender.spinning:
            return *self._lender.sample_motion(), None, None
        position, velocity, orientation, spin = self._lender.sample()
        return (
            position,
            velocity,
            None if all_unrotated(orientation, self.dim) else orientation,
            None if all_still(spin) else spin,
        )

    @property
    def stored_tensors(self) -> FloatArray | None:
        """The inertia tensors the table stores, (N, 3, 3) [kg m^2]; None while every body is
        a sphere (:attr:`inertia_tensor` then makes them on each read)."""
        return self._tensor

    @property
    def unrotated(self) -> bool:
        """True when every body's orientation is the identity (then none is stored)."""
        if self._lender is not None:
            return not self._lender.spinning or all_unrotated(self.orientation, self.dim)
        return self._orientation is None

    @property
    def still(self) -> bool:
        """True when no body spins, every spin +0.0 (then none is stored)."""
        if self._lender is not None:
            return not self._lender.spinning or all_still(self.angular_velocity)
        return self._angular_velocity is None

    @property
    def mobile(self) -> NDArray[np.bool_]:
        """False for static bodies (infinite mass), (N,)."""
        return np.isfinite(self.mass)

    @property
    def inertia(self) -> FloatArray:
        """Moment of inertia about the centre of mass [kg m^2] (2D: about z), (N,); inf for
        static and kinematic bodies."""
        with np.errstate(invalid="ignore"):
            moment = self.inertia_factor * self.mass * self.radius**2
        result: FloatArray = np.where(self.mobile, moment, np.inf)
        return result

    @property
    def inertia_tensor(self) -> FloatArray:
        """The body-frame inertia tensors, (N, 3, 3) [kg m^2] (see the class docstring)."""
        if self._tensor is not None:
            return self._tensor
        return _sphere_tensors(self.dim, self.mass, self.radius, self.inertia_factor)

    @inertia_tensor.setter
    def inertia_tensor(self, value: FloatArray) -> None:
        self._tensor = np.asarray(value, np.float64)

    @property
    def spheres_only(self) -> bool:
        """True when every body is a sphere (disk in 2D): the event-driven engine's world."""
        return bool(np.all(self.shape == SHAPE_CODES["sphere"]))

    def kinds_kept(self) -> tuple[Any, ...]:
        """What :meth:`switch_kind` changes (kinds, masses, inertias), for
        :meth:`restore_kinds` (the arrays themselves: a switch replaces them)."""
        return self.kind, self.mass, self.inertia_factor, self._tensor

    def restore_kinds(self, kept: tuple[Any, ...]) -> None:
        """Take back the kinds, masses and inertias :meth:`kinds_kept` gave."""
        self.kind, self.mass, self.inertia_factor, self._tensor = kept

    def switch_kind(
        self, rows: NDArray[np.int64], kind: int, mass: FloatArray, inertia: FloatArray
    ) -> None:
        """Make bodies ``rows`` (k,) of ``kind`` with masses ``mass`` (k,) [kg] and inertias
        about their centres of mass ``inertia``: (k,) [kg m^2] in 2D, body-frame tensors
        (k, 3, 3) in 3D (inf for a static or kinematic body, as :meth:`append_bodies` stores
        them). Their pieces stay: a body's pieces are about its centroid, its centre of mass
        at any uniform density."""
        self._stored()
        if self._tensor is None and self.dim == 3 and not self.spheres_only:
            self._tensor = self.inertia_tensor
        self.kind = self.kind.copy()
        self.kind[rows] = kind
        self.mass = self.mass.copy()
        self.mass[rows] = mass
        reach = self.radius[rows]
        moment = inertia if self.dim == 2 else np.trace(inertia, axis1=1, axis2=2) / 3.0
        with np.errstate(invalid="ignore", divide="ignore"):
            q = np.where(np.isfinite(mass) & (reach > 0.0), moment / (mass * reach**2), 0.0)
        # a sphere keeps its factor whatever its kind (its inertia is made from it)
        q = np.where(self.shape[rows] == SHAPE_CODES["sphere"], self.inertia_factor[rows], q)
        self.inertia_factor = self.inertia_factor.copy()
        self.inertia_factor[rows] = q
        if self._tensor is not None:
            self._tensor = self._tensor.copy()
            self._tensor[rows] = inertia if self.dim == 3 else 0.0

    def append_spheres(
        self,
        position: FloatArray,
        velocity: FloatArray,
        angular_velocity: FloatArray,
        radius: FloatArray,
        mass: FloatArray,
        inertia_factor: float,
        material: int,
    ) -> NDArray[np.int64]:
        """Add spheres (checked by the caller); return their indices."""
        self._stored()
        start, n = self.n, position.shape[0]
        self.position = np.concatenate([self.position, position])
        self.velocity = np.concatenate([self.velocity, velocity])
        if self._orientation is not None:  # (spheres are added unrotated)
            self.orientation = np.concatenate(
                [self._orientations(start), identity_orientations(n, self.dim)]
            )
        if self._angular_velocity is not None or not all_still(angular_velocity):
            self.angular_velocity = np.concatenate([self._spins(start), angular_velocity])
        self.shape = np.concatenate([self.shape, np.full(n, SHAPE_CODES["sphere"], np.int8)])
        self.radius = np.concatenate([self.radius, radius])
        self.mass = np.concatenate([self.mass, mass])
        q = np.full(n, inertia_factor)
        self.inertia_factor = np.concatenate([self.inertia_factor, q])
        if self._tensor is not None:  # other shapes too: every tensor is stored
            self._tensor = np.concatenate(
                [self._tensor, _sphere_tensors(self.dim, mass, radius, q)]
            )
        self.material = np.concatenate([self.material, np.full(n, material, np.int64)])
        kind = np.where(np.isfinite(mass), KIND_DYNAMIC, KIND_STATIC).astype(np.int8)
        self.kind = np.concatenate([self.kind, kind])
        self.pieces.extend([()] * n)  # one shared empty tuple: a list of n in one step
        return np.arange(start, self.n)

    def append_bodies(
        self,
        position: FloatArray,
        velocity: FloatArray,
        orientation: FloatArray,
        angular_velocity: FloatArray,
        pieces: Pieces,
        shape: int,
        mass: float,
        inertia: float | FloatArray,
        kind: int,
        material: int,
    ) -> NDArray[np.int64]:
        """Add n bodies of one shape (checked by the caller): centres of mass ``position``
        (n, d) [m], velocities (n, d) [m/s]; in 2D ``orientation`` and ``angular_velocity``
        (n,) [rad], [rad/s] and a moment ``inertia`` [kg m^2]; in 3D quaternions (n, 4),
        angular velocities (n, 3) [rad/s] and the body-frame tensor ``inertia`` (3, 3);
        ``pieces`` about the centre of mass; infinite ``mass`` and ``inertia`` unless
        dynamic. Return their indices."""
        self._stored()
        n = position.shape[0]
        start = self.n
        stored = self.inertia_tensor  # every tensor is stored from now on, the spheres' too
        if isinstance(pieces, TrianglePieces):  # (a mesh: its triangles in one block)
            reach = pieces.reach
        else:
            reach = max(piece.reach for piece in pieces) if pieces else 0.0
        tensor = np.zeros((n, 3, 3))
        if self.dim == 2:
            w = np.zeros((n, 3))
            w[:, 2] = angular_velocity
            orient = orientation.reshape(n, 1)
            moment = float(np.asarray(inertia))
        else:
            w = angular_velocity.reshape(n, 3)
            orient = orientation.reshape(n, 4)
            full = np.asarray(inertia, float) * np.ones((3, 3))
            tensor[:] = full
            moment = float(np.trace(full)) / 3.0
        self.position = np.concatenate([self.position, position])
        self.velocity = np.concatenate([self.velocity, velocity])
        self.orientation = np.concatenate([self._orientations(start), orient])
        self.angular_velocity = np.concatenate([self._spins(start), w])
        self.shape = np.concatenate([self.shape, np.full(n, shape, np.int8)])
        self.radius = np.concatenate([self.radius, np.full(n, reach)])
        self.mass = np.concatenate([self.mass, np.full(n, mass)])
        q = moment / (mass * reach**2) if math.isfinite(mass) and reach > 0.0 else 0.0
        self.inertia_factor = np.concatenate([self.inertia_factor, np.full(n, q)])
        self._tensor = np.concatenate([stored, tensor])
        self.material = np.concatenate([self.material, np.full(n, material, np.int64)])
        self.kind = np.concatenate([self.kind, np.full(n, kind, np.int8)])
        self.pieces.extend([pieces] * n)
        return np.arange(start, self.n)

    def set_state(
        self,
        position: FloatArray,
        velocity: FloatArray,
        orientation: FloatArray,
        angular_velocity: FloatArray,
    ) -> None:
        """Replace the pose and motion of every body (from an engine, at its clock); a table
        that lent them (:meth:`lend`) stores them again."""
        self._lender = None
        self.position = position
        self.velocity = velocity
        self.orientation = orientation
        self.angular_velocity = angular_velocity
