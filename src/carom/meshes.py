"""Triangle meshes in 3D: static terrain from OBJ/STL/PLY files, and concave dynamic bodies cut
into convex pieces.

:class:`Mesh` is a static body's surface (a bowl, a ramp, a room): any triangle soup, closed or
not, loaded by ``trimesh``. A concave *dynamic* body needs volume and convex pieces to collide
with: :func:`decompose` cuts a closed mesh with CoACD (Wei et al., "Approximate convex
decomposition for 3D meshes with collision-aware concavity and tree search", SIGGRAPH 2022)
into a :class:`carom.shapes3d.Compound` of hulls whose mass properties are the closed mesh's
own, exact. The cut takes seconds, so it is done once and kept beside the mesh file
(``NAME.carom-pieces.npz``), keyed by a hash of the mesh and the cut's settings: a changed
mesh or setting cuts again, and a file of that name that carom did not write is never
overwritten.

Needs ``pip install carom[rigid3d]`` (SciPy, trimesh, CoACD).
"""

from __future__ import annotations

import hashlib
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from carom.errors import CaromError
from carom.geometry.mass3d import SolidIntegrals, check_closed, polyhedron_integrals
from carom.limits import check_magnitude
from carom.shapes3d import Compound, ConvexPiece3D, Hull, Shape3D

__all__ = [
    "CACHE_SUFFIX",
    "Mesh",
    "bowl_mesh",
    "decompose",
    "load_mesh",
    "save_obj",
    "terrain_mesh",
    "torus_mesh",
]

FloatArray = NDArray[np.float64]

#: what a mesh file's pieces are kept in, beside it
CACHE_SUFFIX = ".carom-pieces.npz"
_CACHE_FORMAT = "carom-pieces 1"


@dataclass(frozen=True, eq=False)
class Mesh(Shape3D):
    """A static triangle mesh: terrain, a bowl, a room. Static only: it has no mass.

    Parameters
    ----------
    vertices : (V, 3) float64
        [m].
    triangles : (F, 3) int64
        Corner indices; counter-clockwise seen from the side bodies stay on.
    """

    vertices: ArrayLike
    triangles: ArrayLike
    kind = "mesh"

    def __post_init__(self) -> None:
        try:
            v = np.asarray(self.vertices, dtype=float)
            f = np.asarray(self.triangles)
        except (TypeError, ValueError):
            raise CaromError("Mesh needs vertices (V, 3) [m] and triangles (F, 3)") from None
        if v.ndim != 2 or v.shape[1] != 3 or v.shape[0] < 3:
            raise CaromError(f"Mesh vertices must be (V, 3) with V >= 3 [m]; got {v.shape}")
        if not np.all(np.isfinite(v)):
            i = int(np.flatnonzero(~np.all(np.isfinite(v), axis=1))[0])
            raise CaromError(f"Mesh vertex {i} = {v[i].tolist()} is not finite")
        v = check_magnitude("Mesh vertices", v, "m")
        if f.ndim != 2 or f.shape[1] != 3 or f.shape[0] < 1 or f.dtype.kind not in "iu":
            raise CaromError(f"Mesh triangles must be (F, 3) corner indices; got {f.shape}")
        if f.min() < 0 or f.max() >= v.shape[0]:
            raise CaromError(f"Mesh triangles name corners outside 0..{v.shape[0] - 1}")
        corners = v[f]
        area = np.linalg.norm(
            np.cross(corners[:, 1] - corners[:, 0], corners[:, 2] - corners[:, 0]), axis=1
        )
        if not np.all(area > 0.0):
            i = int(np.flatnonzero(~(area > 0.0))[0])
            raise CaromError(f"Mesh triangle {i} ({f[i].tolist()}) has no area")
        object.__setattr__(self, "vertices", v)
        object.__setattr__(self, "triangles", f.astype(np.int64))

    def pieces(self) -> tuple[ConvexPiece3D, ...]:
        raise CaromError(
            "a Mesh is a static surface with no pieces and no mass; for a dynamic concave "
            "body cut it into convex pieces: carom.meshes.decompose(path)"
        )

    def integrals(self) -> SolidIntegrals:
        raise CaromError(
            "a Mesh is a static surface and has no mass; make it static, or for a dynamic "
            "concave body use carom.meshes.decompose(path)"
        )

    def is_closed(self) -> bool:
        """Whether the triangles close a consistently oriented surface (a solid)."""
        try:
            check_closed(np.asarray(self.triangles), np.asarray(self.vertices).shape[0])
        except CaromError:
            return False
        return True


def _trimesh() -> Any:
    try:
        import trimesh
    except ImportError:
        raise CaromError(
            "loading meshes needs trimesh: pip install 'carom[rigid3d]' (or trimesh)"
        ) from None
    return trimesh


def load_mesh(path: str | os.PathLike[str], *, scale: float = 1.0) -> Mesh:
    """A mesh file (OBJ, STL, PLY, or anything ``trimesh`` reads) as a :class:`Mesh`.

    Parameters
    ----------
    path : path
        The file.
    scale : float
        Multiplies every coordinate (e.g. 0.001 for a file in millimetres) [-].
    """
    trimesh = _trimesh()
    file = Path(path)
    if not file.is_file():
        raise CaromError(f"{file}: no such mesh file")
    if not (np.isfinite(scale) and scale > 0.0):
        raise CaromError(f"scale must be positive and finite; got {scale!r}")
    try:
        # as written (process=False): trimesh's processing drops a vertex that is not a
        # number, and the triangles that use it, without a word
        loaded = trimesh.load(file, force="mesh", process=False)
    except ImportError:  # (trimesh guessing a text file's encoding with a package it lacks)
        raise CaromError(
            f"{file}: cannot read it as a mesh: it is neither a binary mesh nor text in an "
            f"encoding trimesh reads (UTF-8); check the file, or export it again"
        ) from None
    except Exception as error:  # trimesh raises many kinds on a bad file
        raise CaromError(f"{file}: cannot read it as a mesh ({error})") from None
    vertices = np.asarray(loaded.vertices, float)
    bad = np.flatnonzero(~np.all(np.isfinite(vertices), axis=1))
    if bad.size:
        i = int(bad[0])
        raise CaromError(
            f"{file}: vertex {i + 1} = {vertices[i].tolist()} is not a number; fix it in the "
            f"file (carom does not drop it and its triangles)"
        )
    processed = trimesh.Trimesh(vertices, np.asarray(loaded.faces, np.int64), process=True)
    triangles = np.asarray(processed.faces, np.int64)
    if triangles.size == 0:
        raise CaromError(f"{file}: holds no triangles")
    return Mesh(np.asarray(processed.vertices, float) * scale, triangles)


def _key(mesh: Mesh, threshold: float, seed: int) -> str:
    """A hash of the mesh and the cut's settings: a cache made for them, and only them."""
    digest = hashlib.sha256()
    digest.update(_CACHE_FORMAT.encode())
    digest.update(np.ascontiguousarray(mesh.vertices, np.float64).tobytes())
    digest.update(np.ascontiguousarray(mesh.triangles, np.int64).tobytes())
    digest.update(repr((float(threshold), int(seed))).encode())
    return digest.hexdigest()


def _read_cache(file: Path, key: str) -> list[FloatArray] | None:
    """The pieces kept in ``file`` for ``key``; None if absent or made for another mesh; a
    CaromError if the file is not carom's."""
    if not file.exists():
        return None
    try:
        with np.load(file, allow_pickle=False) as data:
            if str(data["format"]) != _CACHE_FORMAT:
                raise KeyError("format")
            if str(data["key"]) != key:
                return None
            points, counts = data["points"], data["counts"]
    except (OSError, KeyError, ValueError):
        raise CaromError(
            f"{file} exists and is not carom's pieces file; carom will not overwrite it: move "
            "it, or pass cache=False"
        ) from None
    return np.split(np.asarray(points, float), np.cumsum(counts)[:-1])


def _write_cache(file: Path, key: str, pieces: list[FloatArray]) -> bool:
    """Keep ``pieces`` in ``file`` (written whole to a temporary file, then renamed); False
    when the folder cannot be written (a mesh shipped in a read-only install)."""
    partial = file.with_name(file.name + ".partial.npz")
    counts = np.array([p.shape[0] for p in pieces], np.int64)
    try:
        file.parent.mkdir(parents=True, exist_ok=True)
        np.savez_compressed(
            partial, format=_CACHE_FORMAT, key=key, points=np.concatenate(pieces), counts=counts
        )
        os.replace(partial, file)
    except OSError:
        if partial.is_file():
            partial.unlink()
        return False
    return True


def _user_cache(key: str) -> Path:
    """Where pieces are kept when the mesh's own folder cannot be written, or the mesh has
    no file: ``$XDG_CACHE_HOME/carom/pieces/KEY.npz`` (default ``~/.cache``)."""
    home = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(home) / "carom" / "pieces" / f"{key[:32]}{CACHE_SUFFIX}"


def decompose(
    source: str | os.PathLike[str] | Mesh,
    *,
    threshold: float = 0.05,
    seed: int = 0,
    cache: bool = True,
) -> Compound:
    """A closed mesh as a dynamic concave body: convex pieces (CoACD) with the mesh's exact
    mass properties.

    Parameters
    ----------
    source : path or Mesh
        A closed, consistently oriented mesh (a solid), or its file.
    threshold : float
        CoACD's concavity threshold [-]: smaller cuts into more, tighter pieces.
    seed : int
        CoACD's random seed: the same mesh, threshold and seed give the same pieces.
    cache : bool
        Keep the pieces and reuse them: beside the mesh's file (``NAME`` +
        :data:`CACHE_SUFFIX`), or in the user's cache (``~/.cache/carom/pieces``, by a hash of
        the mesh and the settings) when the mesh has no file or its folder cannot be written.

    Returns
    -------
    Compound
        Hulls of the pieces; ``solid`` the closed mesh's integrals (Mirtich), so the mass,
        centre of mass and inertia are the mesh's, however the pieces overlap.
    """
    file = None if isinstance(source, Mesh) else Path(source)
    mesh = source if isinstance(source, Mesh) else load_mesh(source)
    vertices = np.asarray(mesh.vertices, float)
    triangles = np.asarray(mesh.triangles, np.int64)
    name = str(file) if file is not None else "mesh"
    check_closed(triangles, vertices.shape[0], name)
    solid = polyhedron_integrals(vertices, triangles)
    if not solid.volume > 0.0:
        raise CaromError(f"{name}: its faces turn inward (negative volume); flip them")
    if not (np.isfinite(threshold) and 0.0 < threshold < 1.0):
        raise CaromError(f"threshold must be in (0, 1); got {threshold!r}")
    if isinstance(seed, bool) or not isinstance(seed, int | np.integer) or not 0 <= seed < 2**31:
        raise CaromError(
            f"seed must be a whole number from 0 to {2**31 - 1} (CoACD's seed); got {seed!r}"
        )
    key = _key(mesh, threshold, seed)
    places = [] if not cache else [_user_cache(key)]
    if cache and file is not None:
        places.insert(0, file.with_name(file.name + CACHE_SUFFIX))
    pieces = None
    for kept in places:
        pieces = _read_cache(kept, key)
        if pieces is not None:
            break
    if pieces is not None:
        return Compound([Hull(points) for points in pieces], solid=solid)
    pieces = _run_coacd(vertices, triangles, threshold, seed)
    # the pieces are made (and so checked) before anything is kept beside the mesh
    hulls = []
    for k, points in enumerate(pieces):
        try:
            hulls.append(Hull(points))
        except (CaromError, ValueError) as error:
            raise CaromError(
                f"{name}: CoACD cut piece {k} of {len(pieces)} too thin to be a solid "
                f"({error}); try another threshold or seed, or pass the mesh as one Hull if "
                "it is convex"
            ) from None
    for kept in places:  # beside the file if its folder can be written, else the user's
        if _write_cache(kept, key, pieces):
            break
    return Compound(hulls, solid=solid)


def _run_coacd(
    vertices: FloatArray, triangles: NDArray[np.int64], threshold: float, seed: int
) -> list[FloatArray]:
    """The corners of each convex piece CoACD cuts the mesh into."""
    try:
        import coacd
    except ImportError:
        raise CaromError(
            "cutting a mesh into convex pieces needs CoACD: pip install 'carom[rigid3d]'"
        ) from None
    coacd.set_log_level("error")
    parts = coacd.run_coacd(coacd.Mesh(vertices, triangles), threshold=threshold, seed=seed)
    return [np.asarray(points, float) for points, _faces in parts]


def torus_mesh(major: float, minor: float, around: int = 24, across: int = 12) -> Mesh:
    """A closed polyhedral torus about the z axis: ``around`` sections of the ring, each a
    regular ``across``-gon of circumradius ``minor`` [m] centred ``major`` [m] from the axis;
    triangles outward. Its volume is ``2 pi^2 R r^2`` times the polygons' shortfalls
    ``(n sin(2 pi/n) / 2 pi)`` for each (tests/test_meshes.py)."""
    if not (0.0 < minor < major) or around < 3 or across < 3:
        raise CaromError(
            f"a torus needs 0 < minor < major and at least 3 sections each way; got major "
            f"{major!r}, minor {minor!r}, {around} x {across}"
        )
    u = 2.0 * np.pi * np.arange(around) / around
    v = 2.0 * np.pi * np.arange(across) / across
    ring = major + minor * np.cos(v)
    vertices = np.stack(
        [
            np.outer(np.cos(u), ring).ravel(),
            np.outer(np.sin(u), ring).ravel(),
            np.tile(minor * np.sin(v), around),
        ],
        axis=1,
    )
    triangles = []
    for i in range(around):
        for j in range(across):
            a = i * across + j
            b = ((i + 1) % around) * across + j
            c = ((i + 1) % around) * across + (j + 1) % across
            d = i * across + (j + 1) % across
            triangles += [[a, b, c], [a, c, d]]
    return Mesh(vertices, np.array(triangles, np.int64))


def terrain_mesh(k: int, square: float) -> Mesh:
    """A square heightfield of ``k`` x ``k`` squares of side ``square`` [m], two triangles
    each (2 k^2 in all, facing up), in gentle waves ``z = 1 + 0.2 sin(x / 3) cos(y / 4)``
    [m] over ``0 <= x, y <= k square``: the same surface at the same place whatever ``k``.
    Static only (it has no volume)."""
    if k < 1 or not square > 0.0:
        raise CaromError(f"a terrain needs k >= 1 squares of a positive side; got {k}, {square!r}")
    edge = np.arange(k + 1) * square
    x, y = np.meshgrid(edge, edge, indexing="ij")
    z = 1.0 + 0.2 * np.sin(x / 3.0) * np.cos(y / 4.0)
    vertices = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    i, j = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
    a = (i * (k + 1) + j).ravel()
    b, c, d = a + (k + 1), a + 1, a + (k + 1) + 1
    return Mesh(vertices, np.concatenate([np.stack([a, b, c], 1), np.stack([c, b, d], 1)]))


def bowl_mesh(radius: float, around: int = 32, down: int = 8) -> Mesh:
    """An open hemispherical bowl of ``radius`` [m], rim at z = 0 and bottom at ``-radius``:
    ``down`` rings of ``around`` corners and the bottom point, triangles facing the inside
    (where bodies stay, counter-clockwise seen from there). Static only (it has no
    volume)."""
    if not radius > 0.0 or around < 3 or down < 1:
        raise CaromError(
            f"a bowl needs a positive radius and at least 3 x 1 sections; got {radius!r}, "
            f"{around} x {down}"
        )
    rows = []
    for k in range(down):
        polar = 0.5 * np.pi * (1.0 - k / down)  # from the rim (pi/2 from the bottom) down
        u = 2.0 * np.pi * np.arange(around) / around
        rows.append(
            np.stack(
                [
                    radius * np.sin(polar) * np.cos(u),
                    radius * np.sin(polar) * np.sin(u),
                    np.full(around, -radius * np.cos(polar)),
                ],
                axis=1,
            )
        )
    vertices = np.concatenate([*rows, [[0.0, 0.0, -radius]]])
    bottom = vertices.shape[0] - 1
    triangles = []
    for k in range(down - 1):
        for i in range(around):
            a = k * around + i
            b = k * around + (i + 1) % around
            c = (k + 1) * around + (i + 1) % around
            d = (k + 1) * around + i
            triangles += [[a, b, c], [a, c, d]]
    last = (down - 1) * around
    for i in range(around):
        triangles.append([last + i, last + (i + 1) % around, bottom])
    return Mesh(vertices, np.array(triangles, np.int64))


def save_obj(mesh: Mesh, path: str | os.PathLike[str]) -> None:
    """Write ``mesh`` as a Wavefront OBJ file (vertices to 12 significant digits), whole or
    not at all."""
    file = Path(path)
    lines = [f"v {x:.12g} {y:.12g} {z:.12g}" for x, y, z in np.asarray(mesh.vertices)]
    lines += [f"f {a + 1} {b + 1} {c + 1}" for a, b, c in np.asarray(mesh.triangles)]
    partial = file.with_name(file.name + ".partial")
    partial.write_text("\n".join(lines) + "\n")
    os.replace(partial, file)
