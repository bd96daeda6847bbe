"""Asking a world about its bodies now: rays and overlaps (issue 43, item 4).

:class:`Queries` is the part of :class:`carom.World` that casts rays: ``world.ray_cast`` for
one (the first body a line of sight meets), ``world.ray_casts`` for many in one compiled call
(a lidar, a line of sight for every unit). Every shape kind is met exactly, at its closed form
(:mod:`carom.geometry.rays`): circles, capsules, boxes, polygons, compounds, segments and
chains in 2D; spheres, capsules, boxes, hulls, compounds, meshes and planes in 3D. A ray that
starts inside a body does not hit that body. ``world.overlap_point`` and ``world.overlap_box``
say which bodies hold a point or meet a box (:mod:`carom.geometry.overlaps`). The rigid
engines.

>>> import carom
>>> from carom.shapes import Circle
>>> world = carom.World(2, [10.0, 10.0], boundary="open")
>>> _ = world.add_body(Circle(1.0), [5.0, 5.0])
>>> hit = world.ray_cast([0.0, 5.0], [1.0, 0.0])
>>> hit.body, round(hit.distance, 12), hit.normal.tolist()
(0, 4.0, [-1.0, 0.0])
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple, Protocol

import numpy as np
from numpy.typing import ArrayLike, NDArray

from carom.engines.base import Engine
from carom.engines.stepped.driver import SteppedEngine
from carom.engines.stepped.filters import bits64
from carom.errors import CaromError
from carom.limits import LARGEST

__all__ = ["Queries", "RayHit", "ShapeHit", "ray_dtype"]


class _World(Protocol):
    """What :class:`Queries` takes from the World it is part of."""

    @property
    def dim(self) -> int: ...

    def build(self) -> Engine: ...


class RayHit(NamedTuple):
    """The first body a ray meets (:meth:`Queries.ray_cast`)."""

    #: the body's index (-1: a wall or plane of the world's scenery)
    body: int
    #: where the ray enters it (d,) [m]
    point: NDArray[np.float64]
    #: the body's outward unit normal there (d,)
    normal: NDArray[np.float64]
    #: from the ray's origin [m]
    distance: float


def ray_dtype(d: int) -> np.dtype[np.void]:
    """The structured dtype of :meth:`Queries.ray_casts`' hits in ``d`` dimensions."""
    return np.dtype([("body", np.int64), ("point", np.float64, (d,)),
                     ("normal", np.float64, (d,)), ("distance", np.float64)])  # fmt: skip


class Queries:
    """Rays cast into a :class:`carom.World` as it is now."""

    def ray_cast(
        self: _World,
        origin: ArrayLike,
        direction: ArrayLike,
        max_distance: float = math.inf,
        *,
        mask: int | None = None,
    ) -> RayHit | None:
        """The first body the ray from ``origin`` along ``direction`` meets.

        Parameters
        ----------
        origin : (d,) array_like
            Where the ray starts [m].
        direction : (d,) array_like
            Its direction (any length but zero; distances are along the unit vector).
        max_distance : float, optional
            How far it reaches [m] (default: without end).
        mask : int, optional
            The collision categories it sees (:meth:`carom.World.set_filter`), 0 to
            2**64 - 1 or a signed 64-bit integer (-1: every one); default: every one.

        Returns
        -------
        RayHit or None
            The body, the point where the ray enters it, the outward normal there and the
            distance [m]; None when it meets nothing within ``max_distance``.

        Raises
        ------
        CaromError
            A value not finite or beyond carom's limits, a zero direction, a shape that does
            not fit, ``max_distance`` not positive; the event-driven engine.
        """
        hits = Queries.ray_casts(self, [origin], [direction], max_distance, mask=mask)  # type: ignore[arg-type]
        (hit,) = hits
        if hit["body"] == -2:
            return None
        return RayHit(
            int(hit["body"]), hit["point"].copy(), hit["normal"].copy(), float(hit["distance"])
        )

    def ray_casts(
        self: _World,
        origins: ArrayLike,
        directions: ArrayLike,
        max_distance: float | ArrayLike = math.inf,
        *,
        mask: int | None = None,
    ) -> NDArray[np.void]:
        """Many rays in one compiled call: the first body each meets.

        Parameters
        ----------
        origins : (R, d) array_like
            Where they start [m].
        directions : (R, d) or (d,) array_like
            Their directions (one for all when (d,)); none zero.
        max_distance : float or (R,) array_like, optional
            How far each reaches [m] (default: without end).
        mask : int, optional
            As :meth:`ray_cast`'s.

        Returns
        -------
        (R,) structured array
            ``body`` (-2: no hit; -1: a wall or plane of the world's scenery), ``point`` (d,) [m],
            ``normal`` (d,), ``distance`` [m] (inf: no hit) (:func:`ray_dtype`).

        Raises
        ------
        CaromError
            As :meth:`ray_cast`; nothing is cast then.
        """
        engine = self.build()
        if not isinstance(engine, SteppedEngine):
            raise CaromError(
                "ray casts are the rigid engines' so far; the event-driven engine's spheres "
                "are in World.positions"
            )
        d = self.dim
        o = _finite("origins", origins, d)
        if o.ndim == 1:
            o = o[None, :]
        if o.ndim != 2 or o.shape[1] != d:
            raise CaromError(f"origins must have shape (R, {d}); got {o.shape}")
        rays = o.shape[0]
        u = _finite("directions", directions, d)
        if u.shape == (d,):
            u = np.broadcast_to(u, (rays, d))
        if u.shape != (rays, d):
            raise CaromError(f"directions must have shape ({d},) or ({rays}, {d}); got {u.shape}")
        size = np.sqrt(np.sum(u * u, axis=1))
        if np.any(size == 0.0):
            bad = int(np.flatnonzero(size == 0.0)[0])
            raise CaromError(f"ray {bad} has a zero direction; give it a direction to look in")
        u = u / size[:, None]
        lengths = np.broadcast_to(np.asarray(max_distance, dtype=np.float64), (rays,))
        if lengths.ndim != 1 or np.any(np.isnan(lengths)) or np.any(lengths <= 0.0):
            raise CaromError(
                f"max_distance must be positive [m] (inf: without end); got {max_distance!r}"
            )
        seen = -1 if mask is None else bits64("mask", mask)
        distance, body, normal = engine.cast_rays(
            np.ascontiguousarray(o), np.ascontiguousarray(u), np.array(lengths, dtype=float), seen
        )
        hit = body > -2
        out = np.zeros(rays, ray_dtype(d))
        out["body"] = body
        out["distance"] = distance
        out["point"] = out["normal"] = np.nan
        out["point"][hit] = o[hit] + distance[hit, None] * u[hit]
        out["normal"][hit] = normal[hit]
        return out

    def overlap_point(
        self: _World, point: ArrayLike, *, mask: int | None = None
    ) -> NDArray[np.int64]:
        """The bodies that hold ``point`` now (a mouse pick), exactly for every shape kind.

        Parameters
        ----------
        point : (d,) array_like
            [m].
        mask : int, optional
            The collision categories seen (:meth:`carom.World.set_filter`); default every one.

        Returns
        -------
        (k,) int64
            Their indices, sorted (-1 once for the walls and planes of the scenery). A point
            on a body's boundary is in it; a mesh, a surface, holds no point; a plane's solid
            is the half-space under it.

        Raises
        ------
        CaromError
            A point not finite, within carom's limits or of the world's dimension; the
            event-driven engine.
        """
        engine = _rigid_queries(self)
        p = _finite("point", point, self.dim)
        if p.shape != (self.dim,):
            raise CaromError(f"point must be {self.dim} numbers [m]; got shape {p.shape}")
        seen = -1 if mask is None else bits64("mask", mask)
        return engine.overlaps(p, p, True, seen)

    def overlap_box(
        self: _World, low: ArrayLike, high: ArrayLike, *, mask: int | None = None
    ) -> NDArray[np.int64]:
        """The bodies that meet the axis-aligned box ``[low, high]`` now, exactly for every
        shape kind (not their bounding boxes: a disc beside the box's corner is out).

        Parameters
        ----------
        low, high : (d,) array_like
            The box's least and greatest corners [m], ``low <= high``.
        mask : int, optional
            As :meth:`overlap_point`'s.

        Returns
        -------
        (k,) int64
            Their indices, sorted (-1 once for the walls and planes of the scenery). Touching
            counts.

        Raises
        ------
        CaromError
            Corners not finite, within carom's limits or of the world's dimension, or
            ``low`` above ``high``; the event-driven engine.
        """
        engine = _rigid_queries(self)
        lo = _finite("low", low, self.dim)
        hi = _finite("high", high, self.dim)
        for name, corner in (("low", lo), ("high", hi)):
            if corner.shape != (self.dim,):
                raise CaromError(f"{name} must be {self.dim} numbers [m]; got shape {corner.shape}")
        if np.any(lo > hi):
            raise CaromError(f"low {lo.tolist()} must lie below high {hi.tolist()} on every axis")
        seen = -1 if mask is None else bits64("mask", mask)
        return engine.overlaps(lo, hi, False, seen)

    def shape_cast(
        self: _World, shape: Any, position: ArrayLike, translation: ArrayLike, *,
        angle: float = 0.0, orientation: ArrayLike | None = None, mask: int | None = None,
    ) -> ShapeHit | None:  # fmt: skip
        """The first body a shape moved along a straight line would touch, and when: Box2D's
        ``b2World_CastShape``, Rapier's ``cast_shape``.

        Parameters
        ----------
        shape : Shape2D or Shape3D
            Any shape a body of the world's dimension may have, placed by its own origin: a
            circle, capsule, box, polygon or compound (2D); a sphere, capsule, box, hull or
            compound (3D).
        position : (d,) array_like
            Where its origin starts [m].
        translation : (d,) array_like
            The straight move [m], not zero; the shape does not turn.
        angle : float, default 0
            2D: its turn [rad], anticlockwise.
        orientation : (4,) array_like, optional
            3D: its turn as a unit quaternion ``[w, x, y, z]`` (default: none).
        mask : int, optional
            As :meth:`ray_cast`'s.

        Returns
        -------
        ShapeHit or None
            ``body``, ``fraction`` of the translation travelled when they touch, ``point``
            and the body's outward ``normal`` there; None when the whole move touches
            nothing. Sensors and removed bodies are not seen.

        Notes
        -----
        Conservative advancement against each piece near the swept path: from an exact gap
        ``d`` the shape cannot touch before travelling ``d``, so it moves on by that much
        until the gap is under a billionth of the two pieces' size (tested against closed
        forms in 2D and 3D, tests/test_queries.py).

        Raises
        ------
        CaromError
            The event-driven engine; a shape that is not a body's of the world's dimension
            (or a static-only one: a segment, chain, mesh or plane); a position, translation
            or turn not finite, beyond carom's limits or of the wrong size; a zero
            translation. Nothing has changed then.
        """
        engine = _rigid_queries(self)
        d = self.dim
        origin = _finite("position", position, d)
        move = _finite("translation", translation, d)
        for name, value in (("position", origin), ("translation", move)):
            if value.shape != (d,):
                raise CaromError(f"{name} must be {d} numbers [m]; got shape {value.shape}")
        if not np.any(move != 0.0):
            raise CaromError("translation is zero; give the shape a move to cast along [m]")
        seen = -1 if mask is None else bits64("mask", mask)
        if d == 2:
            cast, corners, rim, pose = _cast_2d(shape, origin, angle, orientation)
        else:
            cast, corners, rim, pose = _cast_3d(shape, origin, angle, orientation)
        low = np.minimum(corners.min(axis=0), (corners + move).min(axis=0)) - rim
        high = np.maximum(corners.max(axis=0), (corners + move).max(axis=0)) + rim
        body, hit = engine.cast_shape(cast, pose, move, (low, high), seen)
        if body == -2:
            return None
        return ShapeHit(body, float(hit[0]), hit[1 : 1 + d].copy(), hit[1 + d :].copy())


def _cast_2d(
    shape: Any, origin: NDArray[np.float64], angle: float, orientation: ArrayLike | None
) -> tuple[tuple[NDArray[Any], ...], NDArray[np.float64], float, NDArray[np.float64]]:
    """A 2D shape to cast: its pieces' arrays (the 2D kernel's, as its one-body model keeps
    them), its corners placed, its largest rounding radius [m], and its pose (x, y, angle)."""
    from carom.engines.rigid.model import build_model
    from carom.laws.kinds import KIND_DYNAMIC
    from carom.shapes import Segment, Shape2D

    if not isinstance(shape, Shape2D) or isinstance(shape, Segment):
        raise CaromError(
            f"shape must be a 2D body's shape (carom.shapes: Circle, Capsule, Box, Polygon, "
            f"Compound); got {shape!r}"
        )
    if orientation is not None:
        raise CaromError("orientation is a 3D turn; a 2D shape turns by angle [rad]")
    turn = _finite("angle", angle, 2)
    if turn.shape != ():
        raise CaromError(f"angle must be one number [rad]; got {angle!r}")
    none = np.zeros((1, 1))
    model = build_model(
        [shape.pieces()], np.array([KIND_DYNAMIC]), np.ones(1), np.ones(1),
        np.zeros(1, np.int64), none, none, np.zeros(2),
    )  # fmt: skip
    cast = (
        model.local_vertices, model.local_normals, model.piece_start, model.piece_count,
        model.piece_radius, model.piece_reach,
    )  # fmt: skip
    c, s = math.cos(float(turn)), math.sin(float(turn))
    placed = cast[0] @ np.array([[c, s], [-s, c]]) + origin
    return cast, placed, float(cast[4].max()), np.array([origin[0], origin[1], float(turn)])


def _cast_3d(
    shape: Any, origin: NDArray[np.float64], angle: float, orientation: ArrayLike | None
) -> tuple[tuple[Any, ...], NDArray[np.float64], float, NDArray[np.float64]]:
    """A 3D shape to cast: its one-body model (pieces in its origin's frame), its corners
    placed, its largest rounding radius [m], and its pose (x, y, z, quaternion)."""
    from carom.engines.rigid3d.model import build_model, piece_of
    from carom.geometry.rotation import matrix
    from carom.laws.kinds import KIND_DYNAMIC
    from carom.shapes3d import Plane, Shape3D

    if not isinstance(shape, Shape3D) or isinstance(shape, Plane):
        raise CaromError(
            f"shape must be a 3D body's shape (carom.shapes3d: Sphere, Capsule, Box, Hull, "
            f"Compound); got {shape!r}"
        )
    if angle != 0.0:
        raise CaromError("angle is a 2D turn; a 3D shape turns by orientation [w, x, y, z]")
    q = (
        np.array([1.0, 0.0, 0.0, 0.0])
        if orientation is None
        else _finite("orientation", orientation, 4)
    )
    size = float(np.linalg.norm(q)) if q.shape == (4,) else 0.0
    if size == 0.0:
        raise CaromError(
            f"orientation must be a quaternion [w, x, y, z], not zero; got {orientation!r}"
        )
    q = q / size
    pieces = [piece_of(p, np.zeros(3)) for p in shape.pieces()]
    none = np.zeros((1, 1))
    model = build_model(
        [pieces], np.array([KIND_DYNAMIC]), np.ones(1), np.eye(3)[None], np.zeros(1, np.int64),
        none, none, none, np.zeros(3),
    )  # fmt: skip
    turn = np.empty(9)
    matrix(q[None, :], 0, turn)
    placed = model.local_vertices @ turn.reshape(3, 3).T + origin
    return (model,), placed, float(model.piece_radius.max()), np.concatenate((origin, q))


class ShapeHit(NamedTuple):
    """The first body a moving shape would touch (:meth:`Queries.shape_cast`)."""

    #: the body's index (-1: a wall or plane of the world's scenery)
    body: int
    #: the fraction of the translation travelled when it touches, 0 to 1 (0: it starts
    #: touching or overlapping)
    fraction: float
    #: where they touch (d,) [m]
    point: NDArray[np.float64]
    #: the body's outward unit normal there (d,), toward the shape
    normal: NDArray[np.float64]


def _rigid_queries(world: _World) -> SteppedEngine:
    """The world's rigid engine, built; else a CaromError."""
    engine = world.build()
    if not isinstance(engine, SteppedEngine):
        raise CaromError(
            "overlap queries are the rigid engines' so far; the event-driven engine's spheres "
            "are in World.positions"
        )
    return engine


def _finite(name: str, values: Any, d: int) -> NDArray[np.float64]:
    """``values`` as floats, finite and within carom's limits, or a CaromError naming it."""
    try:
        array = np.asarray(values, dtype=np.float64)
    except (TypeError, ValueError):
        raise CaromError(f"{name} must be numbers; got {values!r}") from None
    if not np.all(np.isfinite(array)) or np.any(np.abs(array) > LARGEST):
        raise CaromError(
            f"{name} must be finite, within carom's limits (|x| <= {LARGEST:g}); got {values!r}"
        )
    return array
