"""The 3D rigid-body engine's constants (Model3D) and changing arrays (State3D), as flat arrays.

Bodies are numbered as the caller added them. Each body has one or more pieces, stored in the
body's frame (centred on its centre of mass, the shape's axes): a *round* piece is a core of one
point (a ball) or two (a capsule) with a radius; a *polytope* piece is a convex polyhedron (a
box, a hull, a mesh triangle as a flat one) with its faces and edges
(:func:`carom.geometry.polyhedron.polyhedron_features`); a *plane* piece is static ground.

Piece ``p``'s rows in each flat array run from its ``*_start`` for its ``*_count``: corners in
``local_vertices`` (V, 3), faces in ``local_normals`` (F, 3) with ``face_first`` and
``face_size`` (F,) pointing into its corner indices ``corners`` (C,), and ``edges`` (E, 4)
(two corners, two faces).
Indices inside a piece's slices count from the piece's own first row, so a contact kernel
takes the slices as they are.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, NamedTuple

import numpy as np
from numpy.typing import NDArray

from carom.geometry.manifold3d import MAX_POINTS
from carom.geometry.polyhedron import polyhedron_features, triangle_features
from carom.laws.kinds import KIND_DYNAMIC
from carom.shapes3d import ConvexPiece3D, TrianglePieces

__all__ = [
    "MANIFOLD_FLOATS",
    "MANIFOLD_INTS",
    "PIECE_PLANE",
    "PIECE_POLYTOPE",
    "PIECE_ROUND",
    "Model3D",
    "Piece3D",
    "State3D",
    "build_model",
    "empty_manifolds",
    "engine_pieces",
    "new_state",
    "plane_piece",
    "triangle_piece",
]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]

#: a ball (one core point) or a capsule (two), with a radius
PIECE_ROUND = 0
#: a convex polyhedron, or a mesh triangle as a flat one
PIECE_POLYTOPE = 1
#: static ground: the half-space below a plane
PIECE_PLANE = 2


class Piece3D(NamedTuple):
    """One piece as the engine stores it, in the body's frame.

    ``vertices`` (k, 3) [m]; for a polytope its faces (``normals`` (F, 3), ``face_first`` and
    ``face_size`` (F,) into ``corners``) and ``edges`` (E, 4: two corners, the two faces that
    meet there); for a plane its outward
    normal as the one face and a point of it as the one vertex.
    """

    kind: int
    vertices: FloatArray
    radius: float
    normals: FloatArray
    face_first: IntArray
    face_size: IntArray
    corners: IntArray
    edges: IntArray


_NO_INTS = np.zeros(0, np.int64)


def piece_of(piece: ConvexPiece3D, offset: FloatArray) -> Piece3D:
    """A shape's piece moved by ``offset`` (3,) [m] (from the shape's origin to its centre of
    mass), with its faces and edges if it is a polytope."""
    v = np.asarray(piece.vertices, float) + offset
    if v.shape[0] < 4:
        return Piece3D(
            PIECE_ROUND,
            v,
            float(piece.radius),
            np.zeros((0, 3)),
            _NO_INTS,
            _NO_INTS,
            _NO_INTS,
            np.zeros((0, 4), np.int64),
        )
    f = polyhedron_features(v, np.asarray(piece.triangles, np.int64))
    return Piece3D(
        PIECE_POLYTOPE, v, 0.0, f.normals, f.face_start, f.face_count, f.corners, f.edges
    )


def triangle_piece(corners: FloatArray) -> Piece3D:
    """A mesh triangle (3, 3) [m] as a flat polytope piece."""
    v, n, first, count, cor, edges = triangle_features(corners)
    return Piece3D(PIECE_POLYTOPE, v, 0.0, n, first, count, cor, edges)


def plane_piece(normal: FloatArray, offset: float) -> Piece3D:
    """The plane ``normal . x = offset`` (solid below) as a piece."""
    n = np.asarray(normal, float).reshape(1, 3)
    return Piece3D(
        PIECE_PLANE,
        n * float(offset),
        0.0,
        n.copy(),
        np.zeros(1, np.int64),
        np.zeros(1, np.int64),
        _NO_INTS,
        np.zeros((0, 4), np.int64),
    )


class Model3D(NamedTuple):
    """What does not change while the engine runs.

    Attributes
    ----------
    kind : (N,) int64
        KIND_DYNAMIC, KIND_STATIC or KIND_KINEMATIC.
    mass : (N,) float64
        [kg]; inf for static and kinematic bodies.
    inv_mass : (N,) float64
        [1/kg]; 0 for static and kinematic bodies.
    inertia, inv_inertia : (N, 3, 3) float64
        Inertia tensor about the centre of mass in the body's frame [kg m^2], and its inverse
        (zero for static and kinematic bodies).
    min_moment : (N,) float64
        The least principal moment [kg m^2] (inf for static and kinematic bodies): a free
        body's spin is at most ``sqrt(2 E / min_moment)`` for rotational energy ``E``.
    material : (N,) int64
        Index into the pair tables.
    reach : (N,) float64
        Farthest point of the body from its centre of mass [m] (inf for a plane).
    body_pieces : (N + 1,) int64
        Body i has pieces ``body_pieces[i]`` to ``body_pieces[i + 1]``.
    piece_body, piece_kind : (P,) int64
        Each piece's body, and PIECE_ROUND, PIECE_POLYTOPE or PIECE_PLANE.
    piece_radius, piece_reach : (P,) float64
        Rounding radius [m]; farthest point from the body's centre of mass [m].
    piece_vstart, piece_vcount, piece_fstart, piece_fcount, piece_cstart, piece_ccount,
    piece_estart, piece_ecount : (P,) int64
        Each piece's rows in the flat arrays below.
    local_vertices : (V, 3) float64
        Corners [m], body frame.
    local_normals : (F, 3) float64
        Face normals, body frame.
    face_first, face_size : (F,) int64
        Each face's first corner and its count, in its piece's ``corners``.
    corners : (C,) int64
        Faces' corners, counter-clockwise from outside, as indices into the piece's vertices.
    edges : (E, 4) int64
        Each edge's two corners, as indices into the piece's vertices, and the two faces that
        meet at it, as indices into the piece's faces.
    e_table, mu_table, rolling_table : (M, M) float64
        Restitution [-], friction [-] and rolling resistance [m] of each pair of materials.
    gravity : (3,) float64
        [m/s^2]; acts on dynamic bodies.
    """

    kind: IntArray
    mass: FloatArray
    inv_mass: FloatArray
    inertia: FloatArray
    inv_inertia: FloatArray
    min_moment: FloatArray
    material: IntArray
    reach: FloatArray
    body_pieces: IntArray
    piece_body: IntArray
    piece_kind: IntArray
    piece_radius: FloatArray
    piece_reach: FloatArray
    piece_vstart: IntArray
    piece_vcount: IntArray
    piece_fstart: IntArray
    piece_fcount: IntArray
    piece_cstart: IntArray
    piece_ccount: IntArray
    piece_estart: IntArray
    piece_ecount: IntArray
    local_vertices: FloatArray
    local_normals: FloatArray
    face_first: IntArray
    face_size: IntArray
    corners: IntArray
    edges: IntArray
    e_table: FloatArray
    mu_table: FloatArray
    rolling_table: FloatArray
    gravity: FloatArray


# float columns of a kept manifold (one row per candidate pair, :mod:`.contacts`); "frame":
# the body of the piece that reaches further (a plane's, a mesh's), "other": the other's body
M_T = 0  # the other body's centre in the frame body's frame (3) [m]
M_R = 3  # the other body's rotation in the frame body's frame, row-major (9)
M_GAP = 12  # no points: a lower bound of the gap [m] (-inf: none known)
M_N = 13  # the normal, from A to B, in the frame body's frame (3)
M_SEP = 16  # each point's separation when made (4) [m]
M_POINT = 20  # point j: on A in A's frame (3), on B in B's frame (3), from M_POINT + 6 j [m]
MANIFOLD_FLOATS = M_POINT + 6 * MAX_POINTS
# int columns of a kept manifold
M_COUNT = 0  # points, 0 to 4
M_ID0 = 1  # feature ids: M_ID0 + j
MANIFOLD_INTS = M_ID0 + MAX_POINTS


class State3D(NamedTuple):
    """What changes: pose and motion, the pieces placed and the manifolds kept (sleep and the
    warm-start cache are the engine\'s :class:`carom.engines.stepped.memory.StepMemory`).

    Attributes
    ----------
    x, v : (N, 3) float64
        Centre of mass [m], velocity [m/s].
    q : (N, 4) float64
        Orientation, unit quaternion ``(w, x, y, z)`` body to world.
    w : (N, 3) float64
        Angular velocity, world frame [rad/s].
    vertices : (V, 3) float64
        Corners placed in the world at the start of the next step [m].
    normals : (F, 3) float64
        Face normals placed in the world.
    manifold_keys : (M,) int64
        The candidate pairs of the last step (``a * P + b``), sorted, with their manifolds as
        made (:mod:`.contacts`: ``manifold_ints`` (M, MANIFOLD_INTS) int64 the point count and
        feature ids, ``manifold_floats`` (M, MANIFOLD_FLOATS) the pose they were made at and
        the points on each body [m]); ``manifold_count`` (1,) int64 rows used.
    """

    x: FloatArray
    v: FloatArray
    q: FloatArray
    w: FloatArray
    vertices: FloatArray
    normals: FloatArray
    manifold_keys: IntArray
    manifold_ints: IntArray
    manifold_floats: FloatArray
    manifold_count: IntArray


#: a flat triangle's two faces (front, back) into its corners, and its three edges (two
#: corners, the two faces that meet there), the same for every triangle
_TRIANGLE_FIRST = np.array([0, 3], np.int64)
_TRIANGLE_SIZE = np.array([3, 3], np.int64)
_TRIANGLE_CORNERS = np.array([0, 1, 2, 0, 2, 1], np.int64)
_TRIANGLE_EDGES = np.array([[0, 1, 0, 1], [1, 2, 0, 1], [0, 2, 0, 1]], np.int64)


class _Layout:
    """The flat arrays of :class:`Model3D` made piece by piece, or a mesh's triangles at
    once: each column a list of chunks, joined at the end."""

    #: per piece: its body, kind, radius, reach, and where its vertices, faces, corners and
    #: edges start and how many it has
    PER_PIECE = ("body", "kind", "radius", "reach", "vs", "vc", "fs", "fc", "cs", "cc", "es", "ec")
    ROWS = ("vertices", "normals", "face_first", "face_size", "corners", "edges")

    def __init__(self) -> None:
        self.scalars: dict[str, list[float]] = {key: [] for key in self.PER_PIECE}
        self.chunks: dict[str, list[NDArray[Any]]] = {key: [] for key in self.PER_PIECE}
        self.rows: dict[str, list[NDArray[Any]]] = {
            "vertices": [np.zeros((0, 3))],
            "normals": [np.zeros((0, 3))],
            "face_first": [_NO_INTS],
            "face_size": [_NO_INTS],
            "corners": [_NO_INTS],
            "edges": [np.zeros((0, 4), np.int64)],
        }
        self.at = {"v": 0, "f": 0, "c": 0, "e": 0}
        self.pieces = 0

    def add(self, body: int, piece: Piece3D) -> float:
        """One piece of ``body``; return its reach [m]."""
        if piece.kind == PIECE_PLANE:
            far = np.inf
        else:
            far = float(np.max(np.linalg.norm(piece.vertices, axis=1))) + piece.radius
        at = self.at
        values = (
            body, piece.kind, piece.radius, far, at["v"], piece.vertices.shape[0], at["f"],
            piece.normals.shape[0], at["c"], piece.corners.shape[0], at["e"],
            piece.edges.shape[0],
        )  # fmt: skip
        for key, value in zip(self.PER_PIECE, values, strict=True):
            self.scalars[key].append(value)
        at["v"] += piece.vertices.shape[0]
        at["f"] += piece.normals.shape[0]
        at["c"] += piece.corners.shape[0]
        at["e"] += piece.edges.shape[0]
        rows = self.rows
        rows["vertices"].append(np.asarray(piece.vertices, float))
        rows["normals"].append(np.asarray(piece.normals, float))
        rows["face_first"].append(np.asarray(piece.face_first, np.int64))
        rows["face_size"].append(np.asarray(piece.face_size, np.int64))
        rows["corners"].append(np.asarray(piece.corners, np.int64))
        rows["edges"].append(np.asarray(piece.edges, np.int64).reshape(-1, 4))
        self.pieces += 1
        return far

    def _flush(self) -> None:
        """The pieces added one by one so far, as chunks."""
        for key, values in self.scalars.items():
            if values:
                self.chunks[key].append(np.array(values, float))
                values.clear()

    def add_triangles(self, body: int, block: TrianglePieces) -> FloatArray:
        """A mesh's triangles, each a flat polytope (as :func:`triangle_piece`), at once;
        return their reaches [m] (T,)."""
        self._flush()
        v = block.corners()  # (T, 3, 3)
        t = v.shape[0]
        normal = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
        normal /= np.linalg.norm(normal, axis=1)[:, None]
        far: FloatArray = np.max(np.linalg.norm(v.reshape(-1, 3), axis=1).reshape(t, 3), axis=1)
        step = np.arange(t, dtype=float)
        at = self.at
        for key, value in (
            ("body", np.full(t, float(body))), ("kind", np.full(t, float(PIECE_POLYTOPE))),
            ("radius", np.zeros(t)), ("reach", far), ("vs", at["v"] + 3.0 * step),
            ("vc", np.full(t, 3.0)), ("fs", at["f"] + 2.0 * step), ("fc", np.full(t, 2.0)),
            ("cs", at["c"] + 6.0 * step), ("cc", np.full(t, 6.0)),
            ("es", at["e"] + 3.0 * step), ("ec", np.full(t, 3.0)),
        ):  # fmt: skip
            self.chunks[key].append(value)
        rows = self.rows
        rows["vertices"].append(v.reshape(-1, 3).copy())
        rows["normals"].append(np.stack([normal, -normal], axis=1).reshape(-1, 3))
        rows["face_first"].append(np.tile(_TRIANGLE_FIRST, t))
        rows["face_size"].append(np.tile(_TRIANGLE_SIZE, t))
        rows["corners"].append(np.tile(_TRIANGLE_CORNERS, t))
        rows["edges"].append(np.tile(_TRIANGLE_EDGES, (t, 1)))
        at["v"] += 3 * t
        at["f"] += 2 * t
        at["c"] += 6 * t
        at["e"] += 3 * t
        self.pieces += t
        return far

    def columns(self) -> dict[str, NDArray[Any]]:
        """Every column joined: the per-piece ones (float; the caller casts the counts) and
        the rows."""
        self._flush()
        out: dict[str, NDArray[Any]] = {}
        for key in self.PER_PIECE:
            out[key] = np.concatenate(self.chunks[key]) if self.chunks[key] else np.zeros(0)
        for key in self.ROWS:
            out[key] = np.concatenate(self.rows[key])
        return out


def build_model(
    pieces: Sequence[Sequence[Piece3D] | TrianglePieces], kind: IntArray, mass: FloatArray,
    inertia: FloatArray, material: IntArray, e_table: FloatArray, mu_table: FloatArray,
    rolling_table: FloatArray, gravity: FloatArray,
) -> Model3D:  # fmt: skip
    """The Model of N bodies whose ``pieces`` are given in each body's frame (centred on its
    centre of mass); a static mesh's triangles as one block (:class:`TrianglePieces`), laid
    out in whole arrays. Static and kinematic bodies must have infinite mass; ``inertia``
    (N, 3, 3) [kg m^2] is ignored for them."""
    n = len(pieces)
    kind = np.asarray(kind, np.int64)
    mass = np.asarray(mass, float)
    inertia = np.asarray(inertia, float).reshape(n, 3, 3)
    body_pieces = np.zeros(n + 1, np.int64)
    layout = _Layout()
    reach = np.zeros(n)
    for i, body in enumerate(pieces):
        if isinstance(body, TrianglePieces):
            far = layout.add_triangles(i, body)
            reach[i] = float(np.max(far)) if far.size else 0.0
        else:
            for piece in body:
                reach[i] = max(reach[i], layout.add(i, piece))
        body_pieces[i + 1] = layout.pieces
    columns = layout.columns()
    dynamic = kind == KIND_DYNAMIC
    inv_mass = np.zeros(n)
    inv_mass[dynamic] = 1.0 / mass[dynamic]
    inv_inertia = np.zeros((n, 3, 3))
    min_moment = np.full(n, np.inf)
    if dynamic.any():
        inv_inertia[dynamic] = np.linalg.inv(inertia[dynamic])
        min_moment[dynamic] = np.linalg.eigvalsh(inertia[dynamic])[:, 0]
    inertia = np.where(dynamic[:, None, None], inertia, np.inf)

    def ints(key: str) -> IntArray:
        return columns[key].astype(np.int64)

    return Model3D(
        kind=kind,
        mass=mass,
        inv_mass=inv_mass,
        inertia=inertia,
        inv_inertia=inv_inertia,
        min_moment=min_moment,
        material=np.asarray(material, np.int64),
        reach=reach,
        body_pieces=body_pieces,
        piece_body=ints("body"),
        piece_kind=ints("kind"),
        piece_radius=columns["radius"].astype(float),
        piece_reach=columns["reach"].astype(float),
        piece_vstart=ints("vs"),
        piece_vcount=ints("vc"),
        piece_fstart=ints("fs"),
        piece_fcount=ints("fc"),
        piece_cstart=ints("cs"),
        piece_ccount=ints("cc"),
        piece_estart=ints("es"),
        piece_ecount=ints("ec"),
        local_vertices=columns["vertices"],
        local_normals=columns["normals"],
        face_first=columns["face_first"].astype(np.int64),
        face_size=columns["face_size"].astype(np.int64),
        corners=columns["corners"].astype(np.int64),
        edges=columns["edges"].astype(np.int64).reshape(-1, 4),
        e_table=np.asarray(e_table, float),
        mu_table=np.asarray(mu_table, float),
        rolling_table=np.asarray(rolling_table, float),
        gravity=np.asarray(gravity, float).reshape(3),
    )


def new_state(
    model: Model3D, x: FloatArray, v: FloatArray, q: FloatArray, w: FloatArray
) -> State3D:
    """The State at the start, no manifold kept; quaternions are normalised, but for those
    of unit length to round-off (within 4 ulp), taken bit for bit: a running engine's, handed
    to the engine a world builds in its place, which then goes on with the same bits."""
    n = model.kind.shape[0]
    q = np.array(q, float).reshape(n, 4)
    norm = np.linalg.norm(q, axis=1, keepdims=True)
    off = np.abs(norm - 1.0) > 4.0 * np.finfo(float).eps
    q = np.where(off, q / norm, q)
    return State3D(
        x=np.array(x, float).reshape(n, 3),
        v=np.array(v, float).reshape(n, 3),
        q=q,
        w=np.array(w, float).reshape(n, 3),
        vertices=np.zeros_like(model.local_vertices),
        normals=np.zeros_like(model.local_normals),
        **empty_manifolds(0),
    )


def empty_manifolds(rows: int) -> dict[str, NDArray[Any]]:
    """Room for ``rows`` kept manifolds, none used (the ``manifold_*`` fields of
    :class:`State3D`)."""
    return {
        "manifold_keys": np.zeros(rows, np.int64),
        "manifold_ints": np.zeros((rows, MANIFOLD_INTS), np.int64),
        "manifold_floats": np.zeros((rows, MANIFOLD_FLOATS)),
        "manifold_count": np.zeros(1, np.int64),
    }


def engine_pieces(pieces: Sequence[ConvexPiece3D], radius: float) -> list[Piece3D] | TrianglePieces:
    """A body's pieces as the engine stores them: a mesh triangle (three corners) as a flat
    polytope, the others by :func:`.model.piece_of`; no pieces is a ball of ``radius``; a
    mesh's triangles held as one block stay one (:func:`build_model` lays them out)."""
    if isinstance(pieces, TrianglePieces):
        return pieces
    if not pieces:
        return [piece_of(ConvexPiece3D(np.zeros((1, 3)), np.zeros((0, 3), np.int64), radius),
                         np.zeros(3))]  # fmt: skip
    out = []
    for piece in pieces:
        if piece.vertices.shape[0] == 3:
            out.append(triangle_piece(piece.vertices))
        else:
            out.append(piece_of(piece, np.zeros(3)))
    return out
