"""The World: bodies, materials and boundaries, advanced by an engine.

A World holds what a simulation is made of, engine-neutral: the body table
(:class:`carom.bodies.Bodies`), materials (:mod:`carom.materials`), the box, its walls and
planes, gravity. Running it builds an engine and advances it: the exact event-driven one
(:mod:`carom.engines.edmd`) for spheres and disks, the time-stepped rigid-body one
(:mod:`carom.engines.rigid`) once a body of another shape is added with :meth:`World.add_body`.
Frames, collisions and observables read the engine's state in the caller's numbering of
bodies.

>>> import carom
>>> world = carom.World(2, box=[1.0, 1.0])
>>> _ = world.add_spheres([[0.3, 0.5], [0.7, 0.5]], [[1.0, 0.0], [-1.0, 0.0]], radius=0.05)
>>> world.run(until=0.2, log=True)  # the gap of 0.3 m closes at 2 m/s: impact at 0.15 s
>>> round(float(world.collisions[0]["time"]), 12)
0.15
>>> world.velocities.tolist()        # equal masses, elastic: velocities exchanged
[[-1.0, 0.0], [1.0, 0.0]]
"""

from __future__ import annotations

import math
import warnings
from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal, NoReturn

import numpy as np
from numpy.typing import ArrayLike, NDArray

from carom._inputs import as_float_array
from carom.bodies import BODY_KINDS, KIND_DYNAMIC, Bodies
from carom.engines.base import COLLISION_DTYPE, KIND_PAIR, KIND_WALL, Counters, FrameArrays
from carom.engines.edmd.driver import OVERLAP_TOLERANCE, EdmdEngine, Environment
from carom.engines.edmd.settings import EdmdSettings
from carom.engines.rigid.assemble import Partners, assemble
from carom.engines.rigid.driver import RigidEngine
from carom.engines.rigid.model import RigidModel, RigidState
from carom.engines.rigid.settings import RigidSettings
from carom.engines.rigid3d.assemble import assemble3d
from carom.engines.rigid3d.driver import RigidEngine3D
from carom.engines.rigid3d.model import Model3D, State3D
from carom.errors import CaromError, CaromWarning
from carom.limits import (
    MAX_BODIES,
    MAX_FRAMES,
    RESOLUTION,
    check_body_count,
    check_magnitude,
    check_size,
)
from carom.materials import COMBINE_RULES, CombineRule, Material, pair_table
from carom.meshes import Mesh
from carom.observables import Stats
from carom.shapes import SHAPE_CODES, Shape2D, check_inertia_factor, default_inertia_factor
from carom.shapes3d import (
    ConvexPiece3D,
    Plane,
    Shape3D,
    matrix_quaternion,
    rotation_matrices,
    rotation_matrix,
)

__all__ = ["LOG_LIMIT", "RECORD_BYTES", "Frame", "Material", "Recording", "World"]

FloatArray = NDArray[np.float64]
#: the engines a World can run: "auto" picks "edmd" for spheres alone, "rigid" otherwise
ENGINES = ("auto", "edmd", "rigid")
#: collisions a World keeps in memory with ``log=True`` (64 bytes each: 64 MB); more are
#: counted in ``World.collisions_dropped``: stream them with ``on_collisions`` instead
LOG_LIMIT = 1_000_000


@dataclass(frozen=True)
class Frame:
    """The state of every body at one output time.

    Attributes
    ----------
    time : float
        [s].
    positions, velocities : (N, d) float64
        [m], [m/s]; periodic boxes wrap positions into the box.
    orientations : (N,) float64 in 2D, (N, 4) float64 in 3D
        Angle about z [rad]; unit quaternion ``w, x, y, z`` (body to world).
    angular_velocities : (N, 3) float64
        [rad/s], world frame (2D: about z, column 2).
    """

    time: float
    positions: FloatArray
    velocities: FloatArray
    orientations: FloatArray
    angular_velocities: FloatArray


#: the most memory [bytes] one :meth:`World.record` call may fill with frames
RECORD_BYTES = 2_000_000_000


@dataclass(frozen=True)
class Recording:
    """Every body's state at each of ``F`` frame times (:meth:`World.record`).

    Attributes
    ----------
    times : (F,) float64
        [s].
    positions, velocities : (F, N, d) float64
        [m], [m/s]; periodic boxes wrap positions into the box.
    orientations : (F, N) float64 in 2D, (F, N, 4) float64 in 3D
        Angle about z [rad]; unit quaternion ``w, x, y, z`` (body to world).
    angular_velocities : (F, N, 3) float64
        [rad/s], world frame (2D: about z, column 2).
    """

    times: FloatArray
    positions: FloatArray
    velocities: FloatArray
    orientations: FloatArray
    angular_velocities: FloatArray

    def __len__(self) -> int:
        return len(self.times)

    def frame(self, f: int) -> Frame:
        """Frame ``f`` as a :class:`Frame` (views of the recording's arrays)."""
        return Frame(
            float(self.times[f]),
            self.positions[f],
            self.velocities[f],
            self.orientations[f],
            self.angular_velocities[f],
        )


def _recording(out: FrameArrays, done: int, dim: int) -> Recording:
    """The first ``done`` frames an engine wrote into ``out``, as a :class:`Recording`."""
    orientations = out.orientations[:done]
    return Recording(
        times=out.times[:done],
        positions=out.positions[:done],
        velocities=out.velocities[:done],
        orientations=orientations[..., 0] if dim == 2 else orientations,
        angular_velocities=out.angular_velocities[:done],
    )


def _check_interval(frame_interval: float) -> None:
    """Refuse a frame interval that is not a positive, finite time."""
    if not (frame_interval > 0.0 and math.isfinite(frame_interval)):
        raise CaromError(f"frame_interval must be a positive time [s]; got {frame_interval!r}")


class World:
    """Bodies in a box: spheres (3D) or disks (2D) simulated exactly, event by event, or 2D
    rigid bodies of any shape, step by step.

    Parameters
    ----------
    dim : {2, 3}
        Dimension.
    box : (d,) array_like
        Box side lengths [m]; the box spans ``[0, box[k]]``.
    boundary : {"walls", "periodic", "open"}, default "walls"
        Reflecting walls, periodic boundaries, or none ("open", rigid-body engine only: the
        box then only frames the pictures).
    gravity : (d,) array_like, optional
        Uniform acceleration [m/s^2], e.g. ``[0, -9.81]``.
    walls : Material, float, or a sequence of 2 d of them, default 1.0
        The walls' material: one for all, or the lower and upper wall of each axis in turn
        (``x-, x+, y-, ...``); a number is a smooth material of that restitution [-]. A wall's
        restitution is its own, not combined with the body's.
    t_c : float, default 1e-6
        TC-model time [s] (:class:`carom.engines.edmd.settings.EdmdSettings`).
    combine : {"mean", "min", "max", "geometric", "product"}, default "mean"
        How two materials' coefficients combine; :meth:`set_pair` overrides a pair.
    shell_thickness : float, optional
        Neighbour-shell thickness [m] (:class:`carom.engines.edmd.settings.EdmdSettings`).
    engine : {"auto", "edmd", "rigid"}, default "auto"
        The event-driven engine for spheres and disks ("edmd"), the time-stepped rigid-body
        engine ("rigid", 2D), or "auto": "rigid" once :meth:`add_body` adds a body, or when
        the boundary is "open"; "edmd" otherwise.
    rigid : RigidSettings, optional
        The rigid-body engine's step and solver settings
        (:class:`carom.engines.rigid.settings.RigidSettings`).
    """

    def __init__(
        self,
        dim: int,
        box: ArrayLike,
        boundary: Literal["walls", "periodic", "open"] = "walls",
        gravity: ArrayLike | None = None,
        *,
        walls: Material | float | Sequence[Material | float] = 1.0,
        t_c: float = 1e-6,
        combine: CombineRule = "mean",
        shell_thickness: float | None = None,
        engine: Literal["auto", "edmd", "rigid"] = "auto",
        rigid: RigidSettings | None = None,
    ) -> None:
        if isinstance(dim, bool) or not isinstance(dim, int | np.integer) or dim not in (2, 3):
            raise CaromError(f"dim must be the whole number 2 or 3; got {dim!r}")
        self.dim = int(dim)
        self.box = check_size("box", _vector("box", box, self.dim, "m"), "m")
        if boundary not in ("walls", "periodic", "open"):
            raise CaromError(f"boundary must be 'walls', 'periodic' or 'open'; got {boundary!r}")
        self.boundary = boundary
        if engine not in ENGINES:
            raise CaromError(f"engine must be one of {ENGINES}; got {engine!r}")
        self.engine_choice = engine
        if rigid is not None and not isinstance(rigid, RigidSettings):
            raise CaromError(f"rigid must be a carom RigidSettings; got {rigid!r}")
        self.rigid_settings = rigid if rigid is not None else RigidSettings()
        self.gravity = (
            np.zeros(dim)
            if gravity is None
            else check_magnitude("gravity", _vector("gravity", gravity, dim, "m/s^2"), "m/s^2")
        )
        self.walls = self._wall_materials(walls)
        self.settings = EdmdSettings(t_c=t_c, shell_thickness=shell_thickness)
        if combine not in COMBINE_RULES:
            raise CaromError(f"combine must be one of {COMBINE_RULES}; got {combine!r}")
        self.combine: CombineRule = combine
        self.materials: list[Material] = []
        self._pair_overrides: dict[tuple[int, int], float] = {}
        self.planes: list[tuple[FloatArray, FloatArray, Material]] = []
        self.bodies = Bodies(self.dim)
        self._engine: EdmdEngine | RigidEngine | RigidEngine3D | None = None
        self._time = 0.0
        self._log: list[NDArray[Any]] = []
        self._logged = 0
        self.collisions_dropped = 0
        #: whether the last run got to its target (False: its stop request ended it early)
        self.reached = True
        # totals of the engines dropped so far (adding bodies or materials rebuilds it)
        self._counters_before = Counters(0, 0, 0, 0, 0, 0.0, 0.0, 0, 0.0, 0.0)
        self.stats = Stats(self)

    def _wall_materials(
        self, walls: Material | float | Sequence[Material | float]
    ) -> tuple[Material, ...]:
        n = 2 * self.dim
        items = list(walls) if isinstance(walls, Sequence | np.ndarray) else [walls]
        if len(items) not in (1, n):
            raise CaromError(
                f"walls must be one material or {n} (lower and upper wall of each axis in "
                f"turn: x-, x+, ...); got {len(items)}"
            )
        materials = tuple(_as_material("walls", item) for item in items)
        return materials * n if len(materials) == 1 else materials

    # -- building ---------------------------------------------------------------------------

    def add_material(self, material: Material) -> int:
        """Register a material; return its index (identical materials share one)."""
        if not isinstance(material, Material):
            raise CaromError(f"expected a carom.Material; got {material!r}")
        if material in self.materials:
            return self.materials.index(material)
        self.materials.append(material)
        self._invalidate()
        return len(self.materials) - 1

    def set_pair(self, material_a: int, material_b: int, restitution: float) -> None:
        """Override the combined restitution of one material pair [-]."""
        if not 0.0 <= restitution <= 1.0:
            raise CaromError(f"restitution must lie in [0, 1]; got {restitution!r}")
        for index in (material_a, material_b):
            if not 0 <= index < len(self.materials):
                raise CaromError(f"no material {index}; add it with add_material first")
        self._pair_overrides[(material_a, material_b)] = restitution
        self._pair_overrides[(material_b, material_a)] = restitution
        self._invalidate()

    def add_spheres(
        self,
        positions: ArrayLike,
        velocities: ArrayLike | None = None,
        *,
        radius: ArrayLike,
        mass: ArrayLike = 1.0,
        restitution: float | None = None,
        material: Material | int | None = None,
        angular_velocities: ArrayLike | None = None,
        inertia_factor: float | None = None,
    ) -> NDArray[np.int64]:
        """Add moving spheres (disks in 2D); return their indices.

        Parameters
        ----------
        positions : (n, d) or (d,) array_like
            Centres [m].
        velocities : (n, d) or (d,) array_like, optional
            [m/s]; default at rest.
        radius, mass : float or (n,) array_like
            [m] and [kg], positive.
        restitution : float, optional
            Shorthand for ``material=Material(restitution)``; default 1 (elastic).
        material : Material or int, optional
            A material or the index of one added with :meth:`add_material`.
        angular_velocities : (n, 3) array_like, or (n,) in 2D, optional
            [rad/s]; default not spinning.
        inertia_factor : float, optional
            ``q`` in ``I = q m a^2``; default 2/5 (solid sphere), 1/2 in 2D (disk).
        """
        x = self._rows("positions", positions)
        n = x.shape[0]
        v = np.zeros_like(x) if velocities is None else self._rows("velocities", velocities, n)
        mat = self._material_index(restitution, material)
        w = self._angular(angular_velocities, n)
        q = check_inertia_factor(
            default_inertia_factor(self.dim) if inertia_factor is None else inertia_factor
        )
        radii = self._radii(radius, n)
        masses = self._per_body("mass", mass, n, "kg")
        self._invalidate()  # the bodies' state now, out of the engine; it is rebuilt on run
        return self.bodies.append_spheres(x, v, w, radii, masses, q, mat)

    def add_static_spheres(
        self,
        positions: ArrayLike,
        *,
        radius: ArrayLike,
        restitution: float | None = None,
        material: Material | int | None = None,
    ) -> NDArray[np.int64]:
        """Add spheres that never move (pegs, obstacles); return their indices."""
        x = self._rows("positions", positions)
        n = x.shape[0]
        mat = self._material_index(restitution, material)
        radii = self._radii(radius, n)
        self._invalidate()
        return self.bodies.append_spheres(
            x, np.zeros_like(x), np.zeros((n, 3)), radii, np.full(n, np.inf), 0.4, mat
        )

    def add_body(
        self,
        shape: Shape2D | Shape3D,
        position: ArrayLike,
        *,
        velocity: ArrayLike | None = None,
        angle: float = 0.0,
        orientation: ArrayLike | None = None,
        angular_velocity: float | ArrayLike = 0.0,
        density: float | None = None,
        mass: float | None = None,
        restitution: float | None = None,
        material: Material | int | None = None,
        kind: Literal["dynamic", "static", "kinematic"] = "dynamic",
    ) -> int:
        """Add one rigid body of any shape; return its index. (:meth:`add_bodies` adds many of
        one shape at once.)

        Parameters
        ----------
        shape : Shape2D or Shape3D
            2D (:mod:`carom.shapes`): Circle, Capsule, Box, Polygon, Compound; Segment and
            Chain (static only). 3D (:mod:`carom.shapes3d`): Sphere, Capsule, Box, Hull,
            Compound; :class:`carom.meshes.Mesh` (static only).
        position : (d,) array_like
            Where the shape's origin goes [m]. The body's position as the World reports it
            (:attr:`positions`, frames) is its centre of mass, which is the origin for every
            shape centred on it (all but a Polygon or Compound drawn off-centre).
        velocity : (d,) array_like, optional
            Of the centre of mass [m/s]; default at rest.
        angle : float, default 0
            2D: the shape's turn about its origin [rad], anticlockwise.
        orientation : (4,) or (3, 3) array_like, optional
            3D: the shape's turn about its origin, a unit quaternion ``(w, x, y, z)`` or a
            rotation matrix (shape to world); default unturned.
        angular_velocity : float or (3,) array_like, default 0
            [rad/s]: anticlockwise in 2D, a vector in the world frame in 3D.
        density, mass : float, optional
            [kg/m^2] (2D) or [kg/m^3] (3D), or [kg], one of them for a dynamic body (default
            density 1); neither for a static or kinematic body, which is not moved by impacts.
        restitution, material
            As for :meth:`add_spheres`; give the material ``friction=`` for Coulomb friction.
        kind : {"dynamic", "static", "kinematic"}, default "dynamic"
            Dynamic bodies fall and collide; static ones never move; kinematic ones move at
            their own ``velocity`` and ``angular_velocity`` whatever they meet (a paddle, a
            turning tumbler).

        Notes
        -----
        A world with a body added here runs the time-stepped rigid-body engine when
        ``engine="auto"``; spheres (disks) added with :meth:`add_spheres` join it as balls
        (circles).
        """
        return int(
            self.add_bodies(
                shape,
                position,
                velocity,
                angles=angle,
                orientations=orientation,
                angular_velocities=angular_velocity,
                density=density,
                mass=mass,
                restitution=restitution,
                material=material,
                kind=kind,
            )[0]
        )

    def add_bodies(
        self,
        shape: Shape2D | Shape3D,
        positions: ArrayLike,
        velocities: ArrayLike | None = None,
        *,
        angles: ArrayLike = 0.0,
        orientations: ArrayLike | None = None,
        angular_velocities: ArrayLike = 0.0,
        density: float | None = None,
        mass: float | None = None,
        restitution: float | None = None,
        material: Material | int | None = None,
        kind: Literal["dynamic", "static", "kinematic"] = "dynamic",
    ) -> NDArray[np.int64]:
        """Add rigid bodies of one shape; return their indices.

        Parameters
        ----------
        shape : Shape2D or Shape3D
            As for :meth:`add_body`.
        positions : (n, d) or (d,) array_like
            Where each body's shape origin goes [m].
        velocities : (n, d) or (d,) array_like, optional
            [m/s]; default at rest.
        angles : float or (n,) array_like
            2D: [rad], anticlockwise; default 0.
        orientations : (n, 4), (4,), (n, 3, 3) or (3, 3) array_like, optional
            3D: unit quaternions ``(w, x, y, z)`` or rotation matrices; default unturned.
        angular_velocities : float or (n,) array_like (2D), (n, 3) or (3,) (3D)
            [rad/s]; default 0.
        density, mass, restitution, material, kind
            As for :meth:`add_body`, the same for every body.
        """
        if self.dim == 3:
            return self._add_bodies_3d(
                shape, positions, velocities, angles, orientations, angular_velocities,
                density, mass, restitution, material, kind,
            )  # fmt: skip
        if isinstance(shape, Shape3D):
            raise CaromError(
                f"{type(shape).__name__} is a 3D shape (carom.shapes3d) and this world is 2D; "
                f"use carom.shapes, or World(3, ...)"
            )
        if orientations is not None:
            raise CaromError("orientations= is for 3D bodies; a 2D body takes angles= [rad]")
        if not isinstance(shape, Shape2D):
            raise CaromError(
                f"shape must be a carom.shapes shape (Circle, Capsule, Box, Polygon, Compound, "
                f"Segment, Chain); got {shape!r}"
            )
        if kind not in BODY_KINDS:
            raise CaromError(f"kind must be one of {tuple(BODY_KINDS)}; got {kind!r}")
        code = BODY_KINDS[kind]
        origin = self._rows("position", positions)
        n = origin.shape[0]
        v = np.zeros_like(origin) if velocities is None else self._rows("velocity", velocities, n)
        turn = self._per_value("angle", angles, n, "rad")
        spin = self._per_value("angular_velocity", angular_velocities, n, "rad/s")
        if code == KIND_DYNAMIC:
            props = shape.mass_properties(
                1.0 if density is None and mass is None else density, mass=mass
            )
            body_mass, inertia, centroid = props.mass, props.inertia, props.centroid
        else:
            _check_still(kind, density, mass, v, spin)
            body_mass, inertia, centroid = math.inf, math.inf, shape.centroid
        c, s = np.cos(turn), np.sin(turn)
        centre = origin + np.stack(
            [c * centroid[0] - s * centroid[1], s * centroid[0] + c * centroid[1]], axis=1
        )
        pieces = tuple(piece.moved(-centroid, 0.0) for piece in shape.pieces())
        mat = self._material_index(restitution, material)
        self._invalidate()
        return self.bodies.append_bodies(
            centre,
            v,
            turn,
            spin,
            pieces,
            SHAPE_CODES[shape.kind],
            body_mass,
            inertia,
            code,
            mat,
        )

    def _add_bodies_3d(
        self,
        shape: Shape2D | Shape3D,
        positions: ArrayLike,
        velocities: ArrayLike | None,
        angles: ArrayLike,
        orientations: ArrayLike | None,
        angular_velocities: ArrayLike,
        density: float | None,
        mass: float | None,
        restitution: float | None,
        material: Material | int | None,
        kind: str,
    ) -> NDArray[np.int64]:
        """:meth:`add_bodies` in 3D."""
        if isinstance(shape, Plane):
            raise CaromError(
                "a Plane is static ground: add it with World.add_plane(point, normal) "
                f"(here point {(shape.offset * np.asarray(shape.normal)).tolist()}, normal "
                f"{np.asarray(shape.normal).tolist()})"
            )
        if isinstance(shape, Shape2D):
            raise CaromError(
                f"{type(shape).__name__} is a 2D shape (carom.shapes) and this world is 3D; "
                f"use carom.shapes3d, or World(2, ...)"
            )
        if not isinstance(shape, Shape3D):
            raise CaromError(
                f"shape must be a carom.shapes3d shape (Sphere, Capsule, Box, Hull, Compound) "
                f"or a carom.meshes.Mesh in a 3D world; got {shape!r}"
            )
        if np.any(as_float_array("angles", angles) != 0.0):
            raise CaromError("angles= is for 2D bodies; a 3D body takes orientations=")
        if kind not in BODY_KINDS:
            raise CaromError(f"kind must be one of {tuple(BODY_KINDS)}; got {kind!r}")
        code = BODY_KINDS[kind]
        origin = self._rows("position", positions)
        n = origin.shape[0]
        v = np.zeros_like(origin) if velocities is None else self._rows("velocity", velocities, n)
        turns = self._orientations(orientations, n)
        spin = self._angular(angular_velocities, n)
        if isinstance(shape, Mesh):
            if code != BODY_KINDS["static"]:
                raise CaromError(
                    "a Mesh is a static surface; add it with kind='static', or cut a closed "
                    "mesh into convex pieces for a dynamic body: carom.meshes.decompose(path)"
                )
            vertices = np.asarray(shape.vertices, float)
            pieces: tuple[ConvexPiece3D, ...] = tuple(
                ConvexPiece3D(vertices[t], np.array([[0, 1, 2]]), 0.0)
                for t in np.asarray(shape.triangles)
            )
            centroid = np.zeros(3)
        else:
            pieces = shape.pieces()
        if code == KIND_DYNAMIC:
            props = shape.mass_properties(
                1.0 if density is None and mass is None else density, mass=mass
            )
            body_mass, inertia, centroid = props.mass, props.inertia, props.centroid
        else:
            _check_still(kind, density, mass, v, spin)
            if not isinstance(shape, Mesh):
                centroid = shape.centroid
            body_mass, inertia = math.inf, np.diag([math.inf] * 3)
        centre = origin + rotation_matrices(turns) @ centroid
        moved = tuple(piece.moved(np.eye(3), -centroid) for piece in pieces)
        mat = self._material_index(restitution, material)
        self._invalidate()
        name = "ball" if shape.kind == "sphere" else shape.kind
        return self.bodies.append_bodies(
            centre, v, turns, spin, moved, SHAPE_CODES[name], body_mass, inertia, code, mat
        )

    def _orientations(self, value: ArrayLike | None, n: int) -> FloatArray:
        """``n`` unit quaternions (n, 4) from quaternions or rotation matrices (one for all,
        or one each); a CaromError names what is wrong."""
        q = np.zeros((n, 4))
        q[:, 0] = 1.0
        if value is None:
            return q
        arr = as_float_array("orientations", value)
        if arr.shape in ((4,), (3, 3)):
            arr = arr[None]
        if (
            arr.ndim not in (2, 3)
            or arr.shape[1:] not in ((4,), (3, 3))
            or (arr.shape[0] not in (1, n))
        ):
            raise CaromError(
                f"orientations must be quaternions (n, 4) or (4,), or rotation matrices "
                f"(n, 3, 3) or (3, 3); got shape {arr.shape} for {n} bodies"
            )
        for i in range(n):
            each = arr[i if arr.shape[0] == n else 0]
            r = rotation_matrix(each, f"orientations[{i}]")
            q[i] = matrix_quaternion(r)
        return q

    def add_plane(
        self,
        point: ArrayLike,
        normal: ArrayLike,
        *,
        restitution: float | None = None,
        material: Material | None = None,
    ) -> int:
        """Add a static plane; bodies stay on the side ``normal`` points to. Returns its index.

        ``restitution`` is shorthand for ``material=Material(restitution)``; default 1.
        """
        p = check_magnitude("point", _vector("point", point, self.dim, "m"), "m")
        nrm = check_magnitude("normal", _vector("normal", normal, self.dim, "-"), "-")
        length = float(np.sqrt(nrm @ nrm))
        if not length > 0.0 or not math.isfinite(length):
            raise CaromError(f"the plane normal must be a non-zero vector; got {normal!r}")
        if material is not None and restitution is not None:
            raise CaromError("give restitution= or material=, not both")
        mat = (
            material
            if material is not None
            else Material(1.0 if restitution is None else restitution)
        )
        self.planes.append((p, nrm / length, _as_material("material", mat)))
        self._invalidate()
        return len(self.planes) - 1

    def _rows(self, name: str, value: ArrayLike, n: int | None = None) -> FloatArray:
        unit = "m/s" if name == "velocities" else "m"
        arr = as_float_array(name, value)
        if arr.ndim == 1:
            arr = arr[None, :] if n is None or n == 1 or arr.shape[0] == self.dim else arr
        if arr.ndim != 2 or arr.shape[-1] != self.dim:
            raise CaromError(
                f"{name} must have shape (n, {self.dim}) or ({self.dim},) [{unit}]; got shape "
                f"{arr.shape}"
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

    def _per_body(self, name: str, value: ArrayLike, n: int, unit: str) -> FloatArray:
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

    def _per_value(self, name: str, value: ArrayLike, n: int, unit: str) -> FloatArray:
        """One finite number per body (a scalar for all), or a CaromError naming ``name``."""
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

    def _radii(self, value: ArrayLike, n: int) -> FloatArray:
        radii = self._per_body("radius", value, n, "m")
        smallest = RESOLUTION * float(self.box.max())
        if np.any(radii < smallest):
            i = int(np.argmax(radii < smallest))
            raise CaromError(
                f"radius[{i}] = {float(radii[i])!r} m is below {RESOLUTION:g} of the box "
                f"({smallest:g} m): positions are rounded to 1e-16 of the box, so its contacts "
                f"would be round-off; make it larger or the box smaller"
            )
        return radii

    def _angular(self, value: ArrayLike | None, n: int) -> FloatArray:
        w = np.zeros((n, 3))
        if value is None:
            return w
        s = as_float_array("angular_velocities", value)
        try:
            if self.dim == 2:
                w[:, 2] = np.broadcast_to(s.reshape(-1) if s.ndim else s, (n,))
            else:
                w[:] = np.broadcast_to(s, (n, 3))
        except ValueError:
            want = f"({n},) or one number" if self.dim == 2 else f"({n}, 3) or (3,)"
            raise CaromError(
                f"angular_velocities must have shape {want} [rad/s]; got {s.shape}"
            ) from None
        if not np.all(np.isfinite(w)):
            bad = int(np.argmax(~np.all(np.isfinite(w), axis=1)))
            raise CaromError(f"angular_velocities[{bad}] = {w[bad].tolist()} is not finite")
        return check_magnitude("angular_velocities", w, "rad/s")

    def _material_index(self, restitution: float | None, material: Material | int | None) -> int:
        if material is not None and restitution is not None:
            raise CaromError("give restitution= or material=, not both")
        if isinstance(material, int | np.integer) and not isinstance(material, bool):
            if not 0 <= material < len(self.materials):
                raise CaromError(f"no material {material}; add it with add_material first")
            return int(material)
        if material is not None:
            return self.add_material(_as_material("material", material))
        return self.add_material(Material(1.0 if restitution is None else restitution))

    def _invalidate(self) -> None:
        """Bring the body table up to date and drop the engine (it is rebuilt on run)."""
        if self._engine is not None:
            self.bodies.set_state(*self._engine.sample())
            self._counters_before = self.counters()
        self._engine = None

    # -- the engine -------------------------------------------------------------------------

    def _environment(self) -> Environment:
        for where, material in [("walls", m) for m in self.walls] + [
            (f"plane {k}", m) for k, (_, _, m) in enumerate(self.planes)
        ]:
            if material.law != "smooth":
                raise CaromError(
                    f"{where}: the event-driven engine's walls and planes are smooth; give "
                    f"them a material without beta or friction (got {material})"
                )
        planes_p = np.array([p for p, _, _ in self.planes]).reshape(-1, self.dim)
        planes_n = np.array([q for _, q, _ in self.planes]).reshape(-1, self.dim)
        face_e = np.array(
            [m.restitution for m in self.walls] + [m.restitution for _, _, m in self.planes],
            dtype=np.float64,
        )
        return Environment(
            box=self.box.copy(),
            periodic=self.boundary == "periodic",
            gravity=self.gravity.copy(),
            pairs=pair_table(self.materials, self.combine, self._pair_overrides),
            face_e=face_e,
            plane_point=planes_p,
            plane_normal=planes_n,
        )

    @property
    def engine_name(self) -> str:
        """The engine this world runs: "edmd" or "rigid" (``engine="auto"`` resolved)."""
        if self.engine_choice != "auto":
            return self.engine_choice
        event_driven = self.bodies.spheres_only and self.boundary != "open"
        return "edmd" if event_driven else "rigid"

    def build(self) -> EdmdEngine | RigidEngine | RigidEngine3D:
        """Build the engine now (running does it when needed), refusing bodies outside the
        box, on the wrong side of a plane, or overlapping; return it."""
        if self._engine is None:
            if self.bodies.n == 0:
                raise CaromError("the world has no bodies; add some with add_spheres or add_body")
            check_body_count(self.bodies.n, "the world")
            if self.engine_name == "rigid":
                self._engine = self._build_rigid()
            else:
                self._check_edmd()
                self._check_placement()
                self._engine = EdmdEngine(
                    self.bodies, self._environment(), self.settings, self._time
                )
        return self._engine

    def _check_edmd(self) -> None:
        """Refuse what the event-driven engine cannot run."""
        if not self.bodies.spheres_only:
            i = int(np.argmax(self.bodies.shape != SHAPE_CODES["sphere"]))
            raise CaromError(
                f"body {i} is not a sphere: the event-driven engine (engine='edmd') runs "
                f"spheres and disks only; use engine='rigid' or 'auto'"
            )
        if self.boundary == "open":
            raise CaromError(
                "boundary 'open' (no walls) is the rigid-body engine's; the event-driven "
                "engine needs 'walls' or 'periodic'"
            )

    def rigid_parts(self) -> tuple[RigidModel | Model3D, RigidState | State3D, Partners]:
        """The rigid engine's view of this world, as the engine would start from it.

        Returns
        -------
        model : RigidModel or Model3D
            Every body's pieces, mass, inertia, kind and material; the caller's bodies
            first, then the walls and planes as static slabs (3D: plane pieces).
        state : RigidState or State3D
            Their positions (centres of mass), velocities, angles and angular velocities.
        partners : Partners
            What each row is: a body, a wall face or a plane (collision records name them).
        """
        if self.boundary == "periodic":
            raise CaromError(
                "the rigid-body engine has no periodic boundary; use boundary='walls' or 'open'"
            )
        if self.dim == 3:
            return assemble3d(
                self.bodies,
                self.box,
                self.boundary == "walls",
                self.walls,
                self.planes,
                self.gravity,
                self.materials,
                self.combine,
                self._pair_overrides,
            )
        return assemble(
            self.bodies,
            self.box,
            self.boundary == "walls",
            self.walls,
            self.planes,
            self.gravity,
            self.materials,
            self.combine,
            self._pair_overrides,
        )

    def _build_rigid(self) -> RigidEngine | RigidEngine3D:
        """The rigid engine, once no dynamic body starts overlapping another body, a wall or
        a plane deeper than the linear slop (the solver would throw them apart)."""
        model, state, partners = self.rigid_parts()
        engine: RigidEngine | RigidEngine3D
        if isinstance(model, Model3D):
            assert isinstance(state, State3D)
            engine = RigidEngine3D(model, state, self.rigid_settings, self._time, partners)
        else:
            assert isinstance(state, RigidState)
            engine = RigidEngine(model, state, self.rigid_settings, self._time, partners)
        a, b, depth = engine.deepest_overlap()
        slop = self.rigid_settings.linear_slop
        if depth > slop:
            names = []
            for body in (a, b):
                kind, index = int(partners.kind[body]), int(partners.number[body])
                names.append(self.describe_partner(kind, index))
            raise CaromError(
                f"{names[0]} and {names[1]} overlap by {depth:.3g} m at the start (more than "
                f"the linear slop, {slop:g} m): move them apart"
            )
        return engine

    def prepare(self) -> None:
        """Build the engine and compile its kernels now (or load them from the cache), so
        that a timed run times the simulation alone. Changes nothing."""
        engine = self.build()
        engine.advance(self._time, 0, None)  # no event is processed
        if self.engine_name == "rigid" and self.dim == 2:
            from carom.engines.rigid.driver import warm_up

            warm_up()
        elif self.engine_name == "rigid":
            from carom.engines.rigid3d.driver import warm_up as warm_up_3d

            warm_up_3d()  # the kernels a step calls only on its first impact or sleep, too
        if isinstance(engine, EdmdEngine):
            engine.load_sampler()  # the kernel of frame(), without a frame of every body
        else:
            self.frame()
        self.record(np.empty(0))  # the path of record() and frames(), frame-less

    @property
    def engine(self) -> EdmdEngine | RigidEngine | RigidEngine3D | None:
        """The engine, once built (:meth:`build`); None before."""
        return self._engine

    def _check_placement(self) -> None:
        """Refuse bodies outside the box or the planes' free side (overlaps: the engine)."""
        tol = OVERLAP_TOLERANCE
        x, a = self.bodies.position, self.bodies.radius
        if self.boundary == "walls":
            low = x - a[:, None]
            high = x + a[:, None] - self.box
            bad = (low < -tol * a[:, None]) | (high > tol * a[:, None])
            if bad.any():
                i = int(np.argmax(bad.any(axis=1)))
                raise CaromError(
                    f"sphere {i} at {x[i].tolist()} with radius {a[i]:g} m reaches outside the "
                    f"box [0, {self.box.tolist()}]; move it inside or enlarge the box"
                )
        for p_index, (p, nrm, _) in enumerate(self.planes):
            dist = (x - p) @ nrm - a
            bad = dist < -tol * a
            if bad.any():
                i = int(np.argmax(bad))
                raise CaromError(
                    f"sphere {i} at {x[i].tolist()} is {-dist[i]:g} m on the wrong side of plane "
                    f"{p_index} (point {p.tolist()}, normal {nrm.tolist()}); move it to the side "
                    f"the normal points to"
                )

    def counters(self) -> Counters:
        """The engine's running totals since the world was first run (:class:`Stats` takes
        differences of them)."""
        base = self._counters_before
        if self._engine is None:
            return base
        return base.plus(self._engine.counters())

    # -- running ------------------------------------------------------------------------------

    @property
    def time(self) -> float:
        """Simulation time [s]."""
        return self._time

    def run(
        self,
        until: float,
        *,
        frame_interval: float | None = None,
        log: bool | ArrayLike = False,
        on_collisions: Callable[[NDArray[Any]], object] | None = None,
        callback: Callable[[Frame], object] | None = None,
        stop: Callable[[], bool] | None = None,
    ) -> list[Frame] | None:
        """Advance to time ``until`` [s], exactly.

        With ``frame_interval`` [s], frames at ``time + k frame_interval`` (and at ``until``)
        are collected and returned, and ``callback`` is called with each; without it, nothing
        is kept. Collisions: ``log`` True keeps them in :attr:`collisions` (up to
        :data:`LOG_LIMIT`; a list of body indices keeps only those involving one of them);
        ``on_collisions`` receives every block of them as they come (a structured array of
        :data:`carom.engines.base.COLLISION_DTYPE`), with memory flat however long the run.

        ``stop`` is asked between blocks of events (a fraction of a second apart); when it
        returns True the run ends early, at the last event processed (:attr:`time` says
        when), and can be continued with another call. Ctrl-C likewise interrupts between
        blocks and leaves the world consistent.
        """
        if frame_interval is None:
            if callback is not None:
                raise CaromError("callback needs frame_interval: the time between frames [s]")
            for _ in self.frames(until, None, log=log, on_collisions=on_collisions, stop=stop):
                pass
            return None
        frames = []
        for frame in self.frames(
            until, frame_interval, log=log, on_collisions=on_collisions, stop=stop
        ):
            if callback is not None:
                callback(frame)
            frames.append(frame)
        return frames

    def run_events(self, count: int = 1, *, log: bool | ArrayLike = False) -> None:
        """Process the next ``count`` events (collisions and neighbour-list rebuilds).

        The clock moves to the time of the last one; nothing else is skipped over.
        """
        if isinstance(count, bool) or not isinstance(count, int | np.integer) or count < 1:
            raise CaromError(f"count must be a whole number >= 1; got {count!r}")
        engine = self.build()
        engine.advance(math.inf, int(count), self._sink(log, None))
        self._time = engine.time

    def frames(
        self,
        until: float,
        frame_interval: float | None,
        *,
        log: bool | ArrayLike = False,
        on_collisions: Callable[[NDArray[Any]], object] | None = None,
        stop: Callable[[], bool] | None = None,
    ) -> Iterator[Frame]:
        """Advance to ``until``, yielding a :class:`Frame` every ``frame_interval`` (lazily).

        ``log``, ``on_collisions`` and ``stop`` as for :meth:`run` (a stopped run yields no
        more frames).
        """
        until = self._check_until(until)
        if frame_interval is not None:
            _check_interval(frame_interval)
        engine = self.build()
        sink = self._sink(log, on_collisions)
        start = self._time
        k = 1
        while True:
            target = until if frame_interval is None else min(until, start + k * frame_interval)
            out = None if frame_interval is None else FrameArrays.empty(1, self.n_bodies, self.dim)
            try:
                if out is None:
                    reached = engine.advance(target, np.iinfo(np.int64).max, sink, stop)
                else:  # one compiled call advances and samples (event-driven engine)
                    reached = engine.advance_frames(np.array([target]), sink, stop, out) == 1
            finally:
                self._time = engine.time  # the target, or the last event before a stop
            self.reached = reached
            if not reached:
                return
            if out is not None:
                orient = out.orientations[0]
                yield Frame(
                    float(out.times[0]),
                    out.positions[0],
                    out.velocities[0],
                    orient[:, 0] if self.dim == 2 else orient,
                    out.angular_velocities[0],
                )
            if target >= until:
                return
            k += 1

    def record(
        self,
        times: ArrayLike,
        *,
        log: bool | ArrayLike = False,
        on_collisions: Callable[[NDArray[Any]], object] | None = None,
        stop: Callable[[], bool] | None = None,
    ) -> Recording:
        """Advance through each of ``times`` in turn and return every body's state at each.

        The frames of :meth:`frames`, all at once: the event-driven engine runs the whole
        stretch in one compiled call, where :meth:`frames` makes a call per frame. The world
        ends at the last time.

        Parameters
        ----------
        times : (F,) array_like
            Frame times [s], finite, non-decreasing, none before :attr:`time`.
        log, on_collisions, stop
            As for :meth:`run`. A stopped run returns the frames done before the stop.

        Returns
        -------
        Recording
            ``times`` (F,) and the states (F, N, ...) at them.

        Raises
        ------
        CaromError
            Times not finite, decreasing or before now, or frames that would take more than
            :data:`RECORD_BYTES` of memory (use :meth:`frames` to stream them instead).
        """
        grid = np.ascontiguousarray(as_float_array("times", times))
        if grid.ndim != 1:
            raise CaromError(f"times must be a 1-D array of frame times [s]; got {grid.shape}")
        # one pass when all is well (ascending between finite ends is finite throughout)
        if grid.size and not (
            math.isfinite(grid[0])
            and math.isfinite(grid[-1])
            and grid[0] >= self._time
            and bool((grid[1:] >= grid[:-1]).all())
        ):
            self._refuse_times(grid)
        per_frame = FrameArrays.frame_bytes(self.n_bodies, self.dim)
        if grid.size * per_frame > RECORD_BYTES:
            raise CaromError(
                f"{grid.size:,} frames of {self.n_bodies:,} bodies take "
                f"{grid.size * per_frame / 1e9:.1f} GB, more than the {RECORD_BYTES / 1e9:g} GB "
                f"a recording may; record fewer times at once, or stream them with frames()"
            )
        engine = self.build()
        sink = self._sink(log, on_collisions)
        out = FrameArrays.empty(grid.size, self.n_bodies, self.dim)
        try:
            done = engine.advance_frames(grid, sink, stop, out)
        finally:
            self._time = engine.time
        if grid.size:  # no frame asked, nothing said (prepare() warms this path so)
            self.reached = done == grid.size
        return _recording(out, done, self.dim)

    def _refuse_times(self, grid: FloatArray) -> NoReturn:
        """Name the first frame time :meth:`record` cannot take."""
        bad = ~np.isfinite(grid)
        if bad.any():
            i = int(np.argmax(bad))
            raise CaromError(f"times must be finite [s]; got times[{i}] = {float(grid[i])!r}")
        if grid[0] < self._time:
            raise CaromError(
                f"times must not start before the current time {self._time} s; "
                f"got times[0] = {float(grid[0])!r}"
            )
        i = int(np.argmax(np.diff(grid) < 0.0))
        raise CaromError(
            f"times must not decrease; got times[{i}] = {float(grid[i])!r} then "
            f"times[{i + 1}] = {float(grid[i + 1])!r}"
        )

    def frame_times(self, until: float, frame_interval: float) -> FloatArray:
        """The times [s] at which :meth:`frames` yields, (F,): ``time + k frame_interval``
        for k = 1, 2, ... while before ``until``, then ``until`` (for :meth:`record`)."""
        until = self._check_until(until)
        _check_interval(frame_interval)
        start = self._time
        count = int(min((until - start) / frame_interval + 2.0, MAX_FRAMES + 2.0))
        grid = start + np.arange(1, count + 1, dtype=np.float64) * frame_interval
        grid = grid[grid < until]
        if grid.size >= MAX_FRAMES:
            raise CaromError(
                f"{grid.size:,} frames or more: more than the {MAX_FRAMES:,} carom writes; "
                f"take a longer frame_interval"
            )
        return np.append(grid, until)

    def _check_until(self, until: float) -> float:
        """``until`` as a float at or after the current time, or a CaromError naming it."""
        wrong = CaromError(
            f"until must be a finite time >= the current time {self._time} s; got {until!r}"
        )
        if isinstance(until, str | bytes | bool):
            raise wrong
        try:
            until = float(until)
        except (TypeError, ValueError):
            raise wrong from None
        if not math.isfinite(until) or until < self._time:
            raise wrong
        return until

    def _sink(
        self, log: bool | ArrayLike, stream: Callable[[NDArray[Any]], object] | None
    ) -> Callable[[NDArray[Any]], None] | None:
        """Where the engine's collisions go: kept (all, or those of some bodies), streamed,
        both, or nowhere (None: the engine then logs nothing)."""
        if isinstance(log, bool | np.bool_):
            keep_all, bodies = bool(log), None
        else:
            bodies = np.asarray(log).reshape(-1)
            if bodies.size and (
                not np.issubdtype(bodies.dtype, np.integer)
                or np.any((bodies < 0) | (bodies >= self.n_bodies))
            ):
                raise CaromError(
                    f"log must be True, False or body indices in [0, {self.n_bodies}); got {log!r}"
                )
            keep_all = False
        keep = keep_all or (bodies is not None and bodies.size > 0)
        if not keep and stream is None:
            return None

        def sink(block: NDArray[Any]) -> None:
            if stream is not None:
                stream(block)
            if not keep:
                return
            if bodies is not None:
                mine = np.isin(block["body"], bodies)
                mine |= (block["kind"] == KIND_PAIR) & np.isin(block["partner"], bodies)
                block = block[mine]
            room = LOG_LIMIT - self._logged
            if block.size > room:
                if self.collisions_dropped == 0:
                    warnings.warn(
                        f"the in-memory collision log is full ({LOG_LIMIT} collisions, "
                        f"{LOG_LIMIT * COLLISION_DTYPE.itemsize / 1e6:.0f} MB); later ones are "
                        f"counted in World.collisions_dropped but not kept: stream them with "
                        f"on_collisions=... instead",
                        CaromWarning,
                        stacklevel=4,
                    )
                self.collisions_dropped += block.size - room
                block = block[:room]
            if block.size:
                self._log.append(block)
                self._logged += block.size

        return sink

    def frame(self) -> Frame:
        """The current state as a :class:`Frame`."""
        x, v, orient, w = self._state_now()
        return Frame(self._time, x, v, orient[:, 0] if self.dim == 2 else orient, w)

    # -- reading ------------------------------------------------------------------------------

    def _state_now(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        if self._engine is None:
            b = self.bodies
            return (
                b.position.copy(),
                b.velocity.copy(),
                b.orientation.copy(),
                b.angular_velocity.copy(),
            )
        return self._engine.sample()

    @property
    def n_bodies(self) -> int:
        return self.bodies.n

    def _motion_now(self) -> tuple[FloatArray, FloatArray]:
        """Positions and velocities now: :meth:`_state_now`'s first two, without its
        orientations and spins."""
        if self._engine is None:
            return self.bodies.position.copy(), self.bodies.velocity.copy()
        return self._engine.sample_motion()

    @property
    def positions(self) -> FloatArray:
        """Centres now, (N, d) [m] (periodic: wrapped into the box)."""
        return self._motion_now()[0]

    @property
    def velocities(self) -> FloatArray:
        """Velocities now, (N, d) [m/s]."""
        return self._motion_now()[1]

    @property
    def angular_velocities(self) -> FloatArray:
        """Angular velocities now, (N, 3) [rad/s] (2D: column 2)."""
        return self._state_now()[3]

    @property
    def orientations(self) -> FloatArray:
        """Orientations now: (N,) angles [rad] in 2D, (N, 4) unit quaternions in 3D."""
        return self.frame().orientations

    @property
    def resting(self) -> NDArray[np.int64]:
        """The wall face or plane each body rests on (-1: none), (N,) int."""
        if self._engine is None:
            return np.full(self.n_bodies, -1, np.int64)
        return self._engine.resting()

    @property
    def radii(self) -> FloatArray:
        return self.bodies.radius.copy()

    @property
    def masses(self) -> FloatArray:
        return self.bodies.mass.copy()

    @property
    def collisions(self) -> NDArray[Any]:
        """The collisions kept with ``log=True`` so far, a structured array of
        :data:`carom.engines.base.COLLISION_DTYPE`: ``time`` [s]; ``body``; ``kind`` and
        ``partner`` (a body, a wall face or a plane, see :meth:`describe_partner`);
        ``impulse`` on ``body`` [N s], always 3 components; ``un_before``, ``un_after`` the
        normal relative speeds [m/s]."""
        if not self._log:
            return np.empty(0, dtype=COLLISION_DTYPE)
        if len(self._log) > 1:
            self._log = [np.concatenate(self._log)]
        return self._log[0]

    def describe_partner(self, kind: int, partner: int) -> str:
        """A readable name for a collision's partner: ``body 3``, ``wall x-``, ``plane 0``."""
        if kind == KIND_PAIR:
            return f"body {partner}"
        if kind == KIND_WALL:
            return f"wall {'xyz'[partner // 2]}{'-' if partner % 2 == 0 else '+'}"
        return f"plane {partner}"

    # -- checkpoints --------------------------------------------------------------------------

    def save(self, path: str | Path, *, extra: Mapping[str, NDArray[Any]] | None = None) -> None:
        """Write a checkpoint of the whole world (:mod:`carom.checkpoint`) to ``path``.

        A world loaded from it continues exactly, bit for bit, as this one would. ``extra``
        arrays are stored beside it under their names and come back from
        :meth:`load_with_extra`.
        """
        from carom.checkpoint import save_world

        save_world(self, Path(path), extra or {})

    @classmethod
    def load(cls, path: str | Path) -> World:
        """Read a checkpoint written by :meth:`save`."""
        return cls.load_with_extra(path)[0]

    @classmethod
    def load_with_extra(cls, path: str | Path) -> tuple[World, dict[str, NDArray[Any]]]:
        """Read a checkpoint written by :meth:`save`, and the ``extra`` arrays saved with it."""
        from carom.checkpoint import load_world

        return load_world(Path(path))

    @property
    def pair_overrides(self) -> dict[tuple[int, int], float]:
        """Material pairs given their own restitution (:meth:`set_pair`), both orders."""
        return dict(self._pair_overrides)

    @property
    def counters_before(self) -> Counters:
        """Totals of engines this world built and dropped before its current one."""
        return self._counters_before

    def restore(
        self,
        time: float,
        engine_arrays: Mapping[str, NDArray[Any]] | None,
        counters_before: Counters,
        log: NDArray[Any],
        collisions_dropped: int,
    ) -> None:
        """Continue from a checkpoint (:mod:`carom.checkpoint`): the clock, the engine's
        arrays (None: not built yet), the totals and the kept log."""
        self._time = time
        self._counters_before = counters_before
        self._log = [log] if log.size else []
        self._logged = int(log.size)
        self.collisions_dropped = collisions_dropped
        if engine_arrays is None:
            return
        if self.engine_name == "rigid":
            model, _, partners = self.rigid_parts()
            if isinstance(model, Model3D):
                self._engine = RigidEngine3D.restore(
                    model, self.rigid_settings, partners, engine_arrays
                )
            else:
                self._engine = RigidEngine.restore(
                    model, self.rigid_settings, partners, engine_arrays
                )
        else:
            self._engine = EdmdEngine.restore(
                self.bodies, self._environment(), self.settings, engine_arrays
            )


def _vector(name: str, value: ArrayLike, dim: int, unit: str) -> FloatArray:
    """``value`` as ``dim`` finite numbers, or a CaromError naming ``name``."""
    try:
        arr = np.asarray(value, dtype=np.float64).reshape(-1)
    except (TypeError, ValueError):
        raise CaromError(f"{name} must be {dim} numbers [{unit}]; got {value!r}") from None
    if arr.shape != (dim,) or not np.all(np.isfinite(arr)):
        raise CaromError(f"{name} must be {dim} finite numbers [{unit}]; got {value!r}")
    return arr


def _as_material(name: str, value: Material | float) -> Material:
    """A material, or a number read as the restitution of a smooth one."""
    if isinstance(value, Material):
        return value
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise CaromError(f"{name} must be a carom.Material or a restitution; got {value!r}")
    return Material(float(value))


def _check_still(kind: str, density: float | None, mass: float | None, v: FloatArray,
                 spin: FloatArray) -> None:  # fmt: skip
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
