"""The rigid-body engine's constants (Model) and changing arrays (State), as plain arrays.

Bodies are numbered as the caller added them. Each body has one or more pieces (rounded
convex polygons, :class:`carom.shapes.ConvexPiece`) stored in the body's frame, centred on
its centre of mass; the pieces' corners and edge normals sit in two flat (V, 2) arrays, piece
``p`` at rows ``piece_start[p]`` to ``piece_start[p] + piece_count[p]``.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import NamedTuple

import numpy as np
from numpy.typing import NDArray

from carom.shapes import ConvexPiece

__all__ = ["RigidModel", "RigidState", "build_model", "new_state"]

FloatArray = NDArray[np.float64]
IntArray = NDArray[np.int64]


class RigidModel(NamedTuple):
    """What does not change while the engine runs.

    Attributes
    ----------
    kind : (N,) int64
        KIND_DYNAMIC, KIND_STATIC or KIND_KINEMATIC.
    mass, inertia : (N,) float64
        [kg], [kg m^2] about the centre of mass; inf for static and kinematic bodies.
    inv_mass, inv_inertia : (N,) float64
        Their inverses; 0 for static and kinematic bodies.
    material : (N,) int64
        Index into the pair tables.
    reach : (N,) float64
        Farthest point of the body from its centre of mass [m].
    body_pieces : (N + 1,) int64
        Body i has pieces ``body_pieces[i]`` to ``body_pieces[i + 1]``.
    piece_body, piece_start, piece_count : (P,) int64
        Each piece's body, first corner row and number of corners.
    piece_radius, piece_reach : (P,) float64
        Rounding radius [m]; farthest point from the body's centre of mass [m].
    local_vertices, local_normals : (V, 2) float64
        Corners [m] and edge normals in the body's frame.
    e_table, mu_table : (M, M) float64
        Restitution and friction of each pair of materials [-].
    gravity : (2,) float64
        [m/s^2]; acts on dynamic bodies.
    """

    kind: IntArray
    mass: FloatArray
    inertia: FloatArray
    inv_mass: FloatArray
    inv_inertia: FloatArray
    material: IntArray
    reach: FloatArray
    body_pieces: IntArray
    piece_body: IntArray
    piece_start: IntArray
    piece_count: IntArray
    piece_radius: FloatArray
    piece_reach: FloatArray
    local_vertices: FloatArray
    local_normals: FloatArray
    e_table: FloatArray
    mu_table: FloatArray
    gravity: FloatArray


class RigidState(NamedTuple):
    """What changes: pose and motion, and the pieces placed (sleep and the warm-start cache are
    the engine's :class:`carom.engines.stepped.memory.StepMemory`).

    Attributes
    ----------
    x, v : (N, 2) float64
        Centre of mass [m], velocity [m/s].
    angle, omega : (N,) float64
        [rad], [rad/s].
    vertices, normals : (V, 2) float64
        Pieces placed in the world at the start of the next step.
    """

    x: FloatArray
    v: FloatArray
    angle: FloatArray
    omega: FloatArray
    vertices: FloatArray
    normals: FloatArray


def build_model(
    pieces: Sequence[Sequence[ConvexPiece]],
    kind: IntArray,
    mass: FloatArray,
    inertia: FloatArray,
    material: IntArray,
    e_table: FloatArray,
    mu_table: FloatArray,
    gravity: FloatArray,
) -> RigidModel:
    """The Model of N bodies whose ``pieces`` are given in each body's frame (centred on its
    centre of mass). Static and kinematic bodies must have infinite mass and inertia."""
    n = len(pieces)
    body_pieces = np.zeros(n + 1, np.int64)
    starts: list[int] = []
    counts: list[int] = []
    radii: list[float] = []
    reaches: list[float] = []
    owners: list[int] = []
    vertices: list[FloatArray] = []
    normals: list[FloatArray] = []
    row = 0
    reach = np.zeros(n)
    for i, body in enumerate(pieces):
        for piece in body:
            k = piece.vertices.shape[0]
            starts.append(row)
            counts.append(k)
            radii.append(piece.radius)
            far = piece.reach
            reaches.append(far)
            reach[i] = max(reach[i], far)
            owners.append(i)
            vertices.append(piece.vertices)
            normals.append(piece.normals if k > 1 else np.zeros((1, 2)))
            row += k
        body_pieces[i + 1] = len(starts)
    with np.errstate(divide="ignore"):
        inv_mass = np.where(np.isfinite(mass), 1.0 / mass, 0.0)
        inv_inertia = np.where(np.isfinite(inertia), 1.0 / inertia, 0.0)
    return RigidModel(
        kind=np.asarray(kind, np.int64),
        mass=np.asarray(mass, float),
        inertia=np.asarray(inertia, float),
        inv_mass=inv_mass,
        inv_inertia=inv_inertia,
        material=np.asarray(material, np.int64),
        reach=reach,
        body_pieces=body_pieces,
        piece_body=np.array(owners, np.int64),
        piece_start=np.array(starts, np.int64),
        piece_count=np.array(counts, np.int64),
        piece_radius=np.array(radii, float),
        piece_reach=np.array(reaches, float),
        local_vertices=np.concatenate(vertices).astype(float) if vertices else np.zeros((0, 2)),
        local_normals=np.concatenate(normals).astype(float) if normals else np.zeros((0, 2)),
        e_table=np.asarray(e_table, float),
        mu_table=np.asarray(mu_table, float),
        gravity=np.asarray(gravity, float),
    )


def new_state(
    model: RigidModel, x: FloatArray, v: FloatArray, angle: FloatArray, omega: FloatArray
) -> RigidState:
    """The State at the start."""
    n = model.kind.shape[0]
    rows = model.local_vertices.shape[0]
    return RigidState(
        x=np.array(x, float).reshape(n, 2),
        v=np.array(v, float).reshape(n, 2),
        angle=np.array(angle, float).reshape(n),
        omega=np.array(omega, float).reshape(n),
        vertices=np.zeros((rows, 2)),
        normals=np.zeros((rows, 2)),
    )
