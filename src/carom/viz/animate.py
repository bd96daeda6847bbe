"""Animations of a trajectory: MP4 (imageio-ffmpeg) or GIF (imageio with Pillow).

Frames are drawn with matplotlib from an H5MD trajectory (``carom run`` writes one) and
handed to the encoder one by one, so memory stays flat for MP4 however long the run. Every
body is a shaded disk: seven nested disks, each smaller, brighter and shifted towards the
light, which reads as a lit sphere at a glance; a rigid body of another shape is its outline
(rounded corners drawn as arcs), turned by its angle, with a lighter inset towards the light.
In 3D a rigid body is drawn as its pieces' shaded faces (flat shading by the light, the faces
turned away from the camera left out, all faces of the picture drawn far to near): a polytope
by its own triangles, a ball or capsule tessellated; static and kinematic bodies are
translucent, so a drum or a bowl shows what it holds.
Colour is speed (one scale for the whole
film, shown by the colour bar); static bodies are grey. In 3D the camera looks at the box
from above and in front, in perspective: bodies are drawn far to near, scaled by their
distance, and dimmed with it; the box's back edges are drawn behind them, the others in
front. A time stamp and the scene's title are on every frame.
"""

from __future__ import annotations

import math
from collections.abc import Iterator, Sequence
from functools import cache
from pathlib import Path
from typing import Any, cast

import numpy as np
from numpy.typing import NDArray

from carom.bodies import PIECE_ARRAYS, Pieces, pieces_from_arrays
from carom.errors import CaromError
from carom.geometry.rotation import rotation_matrices
from carom.joints import joint_lines
from carom.shapes import ConvexPiece
from carom.shapes3d import ConvexPiece3D
from carom.viz import require_matplotlib

__all__ = ["need_encoder", "write_animation"]

FloatArray = NDArray[np.float64]

#: the shading: relative size, shift towards the light (in radii) and brightness of each layer
_LAYER_SIZE = np.array([1.0, 0.9, 0.78, 0.64, 0.48, 0.3, 0.14])
_LAYER_SHIFT = np.array([0.0, 0.06, 0.13, 0.2, 0.28, 0.36, 0.42])
_LAYER_LIGHT = np.array([0.55, 0.7, 0.83, 0.94, 1.0, -0.25, -0.6])  # < 0: that much to white
_LIGHT = np.array([-0.6, 0.8])  # on screen: up and to the left
_STATIC = np.array([0.62, 0.62, 0.66])
_PIXELS = {"mp4": (960, 720), "gif": (560, 420)}


def need_encoder(fmt: str) -> None:
    """Raise a :class:`CaromError` naming the package to install if ``fmt`` cannot be written."""
    try:
        if fmt == "mp4":
            import imageio_ffmpeg

            imageio_ffmpeg.get_ffmpeg_exe()
        elif fmt == "gif":
            import imageio.v3  # noqa: F401
            import PIL  # noqa: F401
        else:
            raise CaromError(f"animation format must be 'mp4', 'gif' or 'none'; got {fmt!r}")
    except (ImportError, RuntimeError):
        raise CaromError(
            f"the {fmt.upper()} animation needs imageio and imageio-ffmpeg: install the viz "
            f"extra, pip install 'carom[viz]' (or pass --animation none)"
        ) from None


def write_animation(
    trajectory: Path,
    out: Path,
    *,
    title: str = "",
    fps: float | None = None,
) -> int:
    """Draw every frame of an H5MD trajectory into an MP4 or GIF (by ``out``'s suffix).

    Parameters
    ----------
    trajectory : Path
        An H5MD file as written by :class:`carom.io.h5md.H5MDWriter`.
    out : Path
        ``*.mp4`` or ``*.gif``.
    title : str
        Shown above the picture.
    fps : float, optional
        Frames per second of the film; by default real time (one over the frame interval)
        kept within 10 to 60 (GIF: 10 to 25).

    Returns
    -------
    int
        The number of frames written: one per trajectory frame.
    """
    require_matplotlib()
    fmt = out.suffix.lstrip(".").lower()
    need_encoder(fmt)
    from carom.io.h5md import read_trajectory

    with read_trajectory(trajectory) as f:
        scene = TrajectoryScene.read(f)
        times = f["particles/all/position/time"][:]
        positions = f["particles/all/position/value"]
        velocities = f["particles/all/velocity/value"]
        angles = f["particles/all/orientation/value"]  # angles (2D), quaternions (3D)
        if fps is None:
            dt = float(np.median(np.diff(times))) if len(times) > 1 else 1.0
            fps = min(25.0 if fmt == "gif" else 60.0, max(10.0, 1.0 / dt if dt > 0 else 10.0))
        scene.speed_scale = speed_scale(sampled_speeds(velocities, scene.moving))
        painter = _Painter(scene, title, _PIXELS[fmt])
        try:
            frames = (
                painter.draw(
                    float(times[k]),
                    positions[k],
                    velocities[k],
                    None if angles is None else angles[k],
                )
                for k in range(len(times))
            )
            if fmt == "mp4":
                return _encode_mp4(frames, out, painter.pixels, fps)
            return _encode_gif(frames, out, fps)
        finally:
            painter.close()


def sampled_speeds(velocities: Any, moving: NDArray[np.bool_]) -> FloatArray:
    """Speeds [m/s] of the moving bodies in up to 50 evenly spaced frames of a trajectory's
    velocities (F, N, d): what the colour scale (and the replay's arrows) are set from."""
    picks = np.unique(np.linspace(0, velocities.shape[0] - 1, 50).astype(int))
    return np.concatenate([np.linalg.norm(velocities[k][moving], axis=1) for k in picks])


def speed_scale(speeds: FloatArray) -> float:
    """The top of the colour scale [m/s]: the 99th percentile of ``speeds`` (1 if none move)."""
    top = float(np.percentile(speeds, 99)) if speeds.size else 0.0
    return top if top > 0 else 1.0


def speed_colours(velocities: FloatArray, moving: NDArray[np.bool_], top: float) -> FloatArray:
    """RGB in [0, 1] per body (N, 3): the plasma colour map by speed up to ``top`` [m/s];
    static bodies grey. The film and the replay colour alike."""
    import matplotlib

    level = np.clip(np.linalg.norm(velocities, axis=1) / top, 0.0, 1.0)
    rgb = np.asarray(matplotlib.colormaps["plasma"](level))[:, :3]
    rgb[~moving] = _STATIC
    return rgb


def _encode_mp4(
    frames: Iterator[NDArray[np.uint8]], out: Path, pixels: tuple[int, int], fps: float
) -> int:
    import imageio_ffmpeg

    writer = imageio_ffmpeg.write_frames(
        str(out),
        pixels,
        fps=fps,
        codec="libx264",
        quality=7,
        macro_block_size=16,
        ffmpeg_log_level="error",
        # one thread: the same bytes every time; veryfast: half the time of the default
        # preset (medium) for files of the same size, measured on the showcase's films
        output_params=["-threads", "1", "-preset", "veryfast"],
    )
    writer.send(None)
    count = 0
    try:
        for frame in frames:
            writer.send(np.ascontiguousarray(frame))
            count += 1
    finally:
        writer.close()
    return count


def _encode_gif(frames: Iterator[NDArray[np.uint8]], out: Path, fps: float) -> int:
    import imageio.v3 as iio

    images = list(frames)
    iio.imwrite(out, np.stack(images), extension=".gif", duration=1000.0 / fps, loop=0)
    return len(images)


class TrajectoryScene:
    """What the drawing needs from the trajectory: box, bodies and how to look at them."""

    def __init__(
        self,
        dim: int,
        box: FloatArray,
        periodic: bool,
        radius: FloatArray,
        mass: FloatArray,
        pieces: Sequence[Pieces] | None = None,
        joints: tuple[NDArray[np.int64], FloatArray] | None = None,
    ) -> None:
        self.dim, self.box, self.periodic = dim, box, periodic
        #: the joints, drawn as lines (:func:`carom.joints.joint_lines`): their rows (J, 4)
        #: and local anchors (J, 2 d), or None
        self.joints = joints
        self.radius = radius
        self.moving = np.isfinite(mass)
        self.speed_scale = 1.0
        every = list(pieces) if pieces else [() for _ in range(len(radius))]
        flat = cast("list[tuple[ConvexPiece, ...]]", every if dim == 2 else [() for _ in every])
        #: bodies drawn as shaded disks (spheres), the outlines of 2D bodies, the faces of 3D ones
        self.round = np.array([not body for body in every], dtype=bool)
        self.outlines = Outlines(flat)
        self.facets = Facets(cast("list[tuple[ConvexPiece3D, ...]]", every) if dim == 3 else [])

    @classmethod
    def read(cls, f: Any) -> TrajectoryScene:
        """From an open H5MD file."""
        box = f["particles/all/box"]
        boundary = [
            str(b, "utf-8") if isinstance(b, bytes) else str(b) for b in box.attrs["boundary"]
        ]
        radius = np.asarray(f["particles/all/radius"][:], dtype=float)
        stored = f["particles/all"].get("pieces")
        pieces = (
            None
            if stored is None
            else pieces_from_arrays(
                {k: stored[k][:] for k in PIECE_ARRAYS if k in stored}, len(radius)
            )
        )
        stored_joints = f["particles/all"].get("joints")
        joints = None
        if stored_joints is not None:
            kinds = [
                str(k, "utf-8") if isinstance(k, bytes) else str(k)
                for k in stored_joints["kind"][:]
            ]
            ints = np.zeros((len(kinds), 4), np.int64)
            ints[:, 0] = [0 if k != "removed" else -1 for k in kinds]
            ints[:, 1:3] = stored_joints["bodies"][:]
            anchors = np.asarray(stored_joints["anchors"][:], dtype=float)
            joints = (ints, anchors.reshape(len(kinds), -1))  # (J, 2 d): A's, then B's
        return cls(
            int(box.attrs["dimension"]),
            np.asarray(box["edges"][:], dtype=float),
            boundary[0] == "periodic",
            radius,
            np.asarray(f["particles/all/mass"][:], dtype=float),
            pieces,
            joints,
        )


class Outlines:
    """The outlines of the rigid bodies' pieces, in their frames, ready to be turned and
    moved: a circle as a 32-gon, a rounded corner as an arc of 6 segments.

    Attributes
    ----------
    points : (M, 2) float64
        Every outline point in its body's frame [m], polygon after polygon.
    owner : (M,) int64
        Each point's body.
    inset : (M, 2) float64
        The points of the lighter inset (towards the piece's middle) [m].
    size : (M,) float64
        The size of each point's piece: its farthest point from its middle [m].
    body : (K,) int64
        Each polygon's body.
    splits : (K - 1,) int64
        Where each polygon after the first starts in ``points``.
    circle : (K,) bool
        Whether the polygon is a circle (a piece with one core vertex).
    """

    def __init__(self, pieces: list[tuple[ConvexPiece, ...]]) -> None:
        points: list[FloatArray] = [np.zeros((0, 2))]
        insets: list[FloatArray] = [np.zeros((0, 2))]
        size: list[FloatArray] = [np.zeros(0)]
        body: list[int] = []
        circle: list[bool] = []
        for i, shapes in enumerate(pieces):
            for piece in shapes:
                ring = _outline(piece.vertices, piece.radius)
                middle = ring.mean(axis=0)
                points.append(ring)
                insets.append(middle + 0.72 * (ring - middle))
                size.append(np.full(len(ring), np.max(np.hypot(*(ring - middle).T))))
                body.append(i)
                circle.append(len(piece.vertices) == 1)
        self.points = np.concatenate(points)
        self.inset = np.concatenate(insets)
        self.size = np.concatenate(size)
        self.body = np.array(body, np.int64)
        self.circle = np.array(circle, bool)
        sizes = [len(ring) for ring in points[1:]]
        self.owner = np.repeat(self.body, sizes)
        self.splits = np.cumsum(sizes, dtype=np.int64)[:-1]

    def polygons(self, local: FloatArray) -> list[FloatArray]:
        """``local`` outline points (M, 2), one per point of :attr:`points`, split into their
        polygons (in their bodies' frames) [m]."""
        return np.split(local, self.splits)

    def placements(self, positions: FloatArray, angles: FloatArray) -> FloatArray:
        """Each polygon's map from its body's frame to the world (K, 3, 3), as an affine
        matrix on (x, y, 1): bodies at ``positions`` (N, 2) [m] turned by ``angles`` (N,)
        [rad]."""
        theta = angles[self.body]
        c, s = np.cos(theta), np.sin(theta)
        placement = np.zeros((len(self.body), 3, 3))
        placement[:, 0, 0], placement[:, 0, 1], placement[:, 0, 2] = c, -s, positions[self.body, 0]
        placement[:, 1, 0], placement[:, 1, 1], placement[:, 1, 2] = s, c, positions[self.body, 1]
        placement[:, 2, 2] = 1.0
        return placement

    def strips(self) -> tuple[FloatArray, NDArray[np.int64], NDArray[np.int64]]:
        """The outlines as closed line strips, a circle's ending in a spoke to its centre (so
        that its turning shows): the points (M', 2) [m] in their bodies' frames, each point's
        body (M',) and where each strip after the first starts (K - 1,)."""
        rings = np.split(self.points, self.splits) if len(self.body) else []
        closed = [
            np.concatenate(
                [ring, ring[:1], ring.mean(axis=0, keepdims=True)] if round_ else [ring, ring[:1]]
            )
            for ring, round_ in zip(rings, self.circle, strict=True)
        ]
        sizes = [len(strip) for strip in closed]
        points = np.concatenate(closed) if closed else np.zeros((0, 2))
        return points, np.repeat(self.body, sizes), np.cumsum(sizes, dtype=np.int64)[:-1]


class Facets:
    """The faces of the 3D rigid bodies' pieces, in their frames: a polytope's own triangles,
    a ball as a 12 x 6 globe, a capsule as a globe split at its equator and stretched along
    its axis (both convex, outward).

    Attributes
    ----------
    corners : (T, 3, 3) float64
        Each triangle's corners in its body's frame [m].
    body : (T,) int64
        Each triangle's body.
    """

    def __init__(self, pieces: list[tuple[ConvexPiece3D, ...]]) -> None:
        corners: list[FloatArray] = [np.zeros((0, 3, 3))]
        body: list[NDArray[np.int64]] = [np.zeros(0, np.int64)]
        for i, shapes in enumerate(pieces):
            for piece in shapes:
                triangles = _tessellate(piece)
                corners.append(triangles)
                body.append(np.full(len(triangles), i, np.int64))
        self.corners = np.concatenate(corners)
        self.body = np.concatenate(body)

    def placed(
        self, positions: FloatArray, orientations: FloatArray
    ) -> tuple[FloatArray, FloatArray]:
        """The triangles (T, 3, 3) and their unit outward normals (T, 3) in the world, bodies
        at ``positions`` (N, 3) [m] turned by quaternions ``orientations`` (N, 4)."""
        r = rotation_matrices(orientations)[self.body]  # (T, 3, 3)
        world = np.einsum("tij,tkj->tki", r, self.corners) + positions[self.body][:, None, :]
        normal = np.cross(world[:, 1] - world[:, 0], world[:, 2] - world[:, 0])
        size = np.linalg.norm(normal, axis=1, keepdims=True)
        return world, normal / np.where(size > 0.0, size, 1.0)


def _globe(around: int = 12, rings: int = 6) -> tuple[FloatArray, NDArray[np.int64]]:
    """A unit globe's corners (around (rings - 1) + 2, 3) and outward triangles."""
    polar = np.pi * np.arange(1, rings) / rings
    u = 2.0 * np.pi * np.arange(around) / around
    body = np.stack(
        [
            np.outer(np.sin(polar), np.cos(u)).ravel(),
            np.outer(np.sin(polar), np.sin(u)).ravel(),
            np.repeat(np.cos(polar), around),
        ],
        axis=1,
    )
    points = np.concatenate([[[0.0, 0.0, 1.0]], body, [[0.0, 0.0, -1.0]]])
    bottom = len(points) - 1
    faces = []
    for i in range(around):
        j = (i + 1) % around
        faces.append([0, 1 + i, 1 + j])
        for k in range(rings - 2):
            a, b = 1 + k * around + i, 1 + k * around + j
            c, d = a + around, b + around
            faces += [[a, c, d], [a, d, b]]
        last = 1 + (rings - 2) * around
        faces.append([last + i, bottom, last + j])
    return points, np.array(faces, np.int64)


def _tessellate(piece: ConvexPiece3D) -> FloatArray:
    """A piece's triangles (T, 3, 3) in its body's frame [m]."""
    v = np.asarray(piece.vertices, float)
    if len(v) >= 3:
        return v[np.asarray(piece.triangles, np.int64)]
    points, faces = _globe()
    points = points * piece.radius
    if len(v) == 1:
        ball: FloatArray = (points + v[0])[faces]
        return ball
    # a capsule: the upper half globe at one end, the lower at the other, along the axis
    axis = v[1] - v[0]
    length = float(np.linalg.norm(axis))
    z = np.array([0.0, 0.0, 1.0])
    k = np.cross(z, axis / length)
    c = float(z @ axis) / length
    if c < -1.0 + 1e-12:
        turn = np.diag([1.0, -1.0, -1.0])
    else:
        skew = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
        turn = np.eye(3) + skew + skew @ skew / (1.0 + c)
    stretched = points + np.where(points[:, 2:] >= 0.0, 0.5, -0.5) * length * z
    placed: FloatArray = (stretched @ turn.T + 0.5 * (v[0] + v[1]))[faces]
    return placed


def _place(
    local: FloatArray, owner: NDArray[np.int64], positions: FloatArray, angles: FloatArray
) -> FloatArray:
    """Points (M, 2) given in their ``owner`` bodies' frames, in the world: bodies at
    ``positions`` (N, 2) [m] turned by ``angles`` (N,) [rad]."""
    theta = angles[owner]
    c, s = np.cos(theta), np.sin(theta)
    x = positions[owner, 0] + c * local[:, 0] - s * local[:, 1]
    y = positions[owner, 1] + s * local[:, 0] + c * local[:, 1]
    return np.stack([x, y], axis=1)


def placed_strips(
    strips: tuple[FloatArray, NDArray[np.int64], NDArray[np.int64]],
    positions: FloatArray,
    angles: FloatArray,
) -> list[FloatArray]:
    """The line strips of :meth:`Outlines.strips` in the world, bodies at ``positions``
    (N, 2) [m] turned by ``angles`` (N,) [rad]."""
    local, owner, splits = strips
    return np.split(_place(local, owner, positions, angles), splits)


def _outline(core: FloatArray, radius: float) -> FloatArray:
    """The outline of a rounded convex piece: its core's corners (k, 2), each replaced by an
    arc of ``radius`` [m] between its edges' normals; a circle when k = 1."""
    if len(core) == 1:
        a = np.linspace(0.0, 2.0 * math.pi, 32, endpoint=False)
        circle: FloatArray = core[0] + radius * np.stack([np.cos(a), np.sin(a)], axis=1)
        return circle
    if radius <= 0.0:
        return np.asarray(core, float)
    edges = np.roll(core, -1, axis=0) - core
    normal_angle = np.arctan2(-edges[:, 0], edges[:, 1])  # outward: the edge turned clockwise
    ring = []
    for i in range(len(core)):
        start = normal_angle[i - 1]
        sweep = (normal_angle[i] - start) % (2.0 * math.pi)
        a = start + np.linspace(0.0, sweep, 7)
        ring.append(core[i] + radius * np.stack([np.cos(a), np.sin(a)], axis=1))
    return np.concatenate(ring)


@cache
def _placed_polygons() -> Any:
    """A matplotlib ``PolyCollection`` whose polygons stay as given (in their bodies'
    frames) and are drawn through the affine maps (K, 3, 3) in its ``placement``, one per
    polygon, before the axes' own transform (``Collection.get_transforms``)."""
    from matplotlib.collections import PolyCollection

    class PlacedPolygons(PolyCollection):
        def __init__(self, polygons: list[FloatArray], **style: Any) -> None:
            super().__init__(polygons, **style)
            self.placement = np.zeros((0, 3, 3))

        def get_transforms(self) -> Any:  # (K, 3, 3) float64
            return self.placement

    return PlacedPolygons


class _Camera:
    """Perspective view of a 3D box from above and in front (z up)."""

    def __init__(self, box: FloatArray, azimuth: float = -58.0, elevation: float = 24.0) -> None:
        centre = box / 2.0
        az, el = math.radians(azimuth), math.radians(elevation)
        toward = np.array([math.cos(el) * math.cos(az), math.cos(el) * math.sin(az), math.sin(el)])
        self.eye = centre + 2.4 * float(np.linalg.norm(box)) * toward
        forward = (centre - self.eye) / np.linalg.norm(centre - self.eye)
        right = np.cross(forward, [0.0, 0.0, 1.0])
        right /= np.linalg.norm(right)
        self.axes = np.stack([right, np.cross(right, forward), forward])  # rows: x, y, depth

    def project(self, points: FloatArray) -> tuple[FloatArray, FloatArray]:
        """Screen coordinates (n, 2) and depth (n,) of points (n, 3)."""
        local = (points - self.eye) @ self.axes.T
        depth = local[:, 2]
        return local[:, :2] / depth[:, None], depth


class _Painter:
    """One matplotlib figure, redrawn for every frame."""

    def __init__(self, scene: TrajectoryScene, title: str, pixels: tuple[int, int]) -> None:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
        from matplotlib.collections import EllipseCollection, LineCollection
        from matplotlib.colors import Normalize

        self.scene, self.pixels = scene, pixels
        dpi = 100
        self.fig = plt.figure(figsize=(pixels[0] / dpi, pixels[1] / dpi), dpi=dpi)
        self.ax = self.fig.add_axes((0.03, 0.04, 0.82, 0.86))
        self.ax.set_aspect("equal")
        self.ax.set_axis_off()
        self.camera: _Camera | None = None
        self.front: Any = None
        box = scene.box
        style = {"colors": "0.25", "linewidths": 1.2, "linestyles": "--" if scene.periodic else "-"}
        if scene.dim == 2:
            corners = np.array([[0, 0], [box[0], 0], [box[0], box[1]], [0, box[1]], [0, 0]])
            self.ax.add_collection(LineCollection([corners], zorder=1, **style))
            low, high = np.zeros(2), box[:2]
        else:
            self.camera = _Camera(box)
            corner = np.array(list(np.ndindex(2, 2, 2)), dtype=float) * box
            screen, depth = self.camera.project(corner)
            self.depth_range = (float(depth.min()), float(depth.max()))
            far = int(np.argmax(depth))
            edges = [
                (a, b)
                for a in range(8)
                for b in range(a + 1, 8)
                if np.sum(
                    np.array(np.unravel_index(a, (2, 2, 2))) != np.unravel_index(b, (2, 2, 2))
                )
                == 1
            ]
            back = [screen[[a, b]] for a, b in edges if far in (a, b)]
            front = [screen[[a, b]] for a, b in edges if far not in (a, b)]
            self.ax.add_collection(LineCollection(back, zorder=1, alpha=0.8, **style))
            front_style = {**style, "linewidths": 0.9}
            self.front = LineCollection(front, zorder=3, alpha=0.45, **front_style)
            self.ax.add_collection(self.front)
            low, high = screen.min(axis=0), screen.max(axis=0)
        pad = 0.04 * float(np.max(high - low))
        self.ax.set_xlim(low[0] - pad, high[0] + pad)
        self.ax.set_ylim(low[1] - pad, high[1] + pad)
        n = int(np.count_nonzero(scene.round)) * len(_LAYER_SIZE)
        self.disks = EllipseCollection(
            np.ones(n),
            np.ones(n),
            np.zeros(n),
            units="xy",
            offsets=np.zeros((n, 2)),
            offset_transform=self.ax.transData,
            linewidths=0,
            zorder=2,
        )
        self.ax.add_collection(self.disks)
        from matplotlib.collections import PolyCollection

        self.faces: Any = PolyCollection([], linewidths=0.3, zorder=2)
        self.ax.add_collection(self.faces)
        # a 2D body's outline and its lighter inset, shifted towards the light, are fixed in
        # its frame: each frame moves them (as matplotlib's per-path transforms) rather than
        # building them anew
        outlines = scene.outlines
        # (each piece's inset shifted by a share of its own size: a long static chain's
        # would otherwise carry the small bodies' insets off them)
        shift = 0.04 * outlines.size[:, None]
        placed = _placed_polygons()
        self.shapes: Any = placed(outlines.polygons(outlines.points), linewidths=0.4, zorder=2)
        self.insets: Any = placed(
            outlines.polygons(outlines.inset + shift * _LIGHT), linewidths=0, zorder=2
        )
        self.ax.add_collection(self.shapes)
        self.ax.add_collection(self.insets)
        # the joints: a line from each body's centre to its anchor, anchor to anchor
        self.joints: Any = LineCollection([], colors="#2a9d8f", linewidths=1.1, zorder=4)
        self.ax.add_collection(self.joints)
        self.fig.text(0.04, 0.965, title, fontsize=13, weight="bold")
        self.stamp = self.fig.text(0.04, 0.93, "", family="monospace", fontsize=13)
        bar_ax = self.fig.add_axes((0.88, 0.15, 0.025, 0.6))
        mappable = matplotlib.cm.ScalarMappable(
            norm=Normalize(0.0, scene.speed_scale), cmap=matplotlib.colormaps["plasma"]
        )
        self.fig.colorbar(mappable, cax=bar_ax, label="speed [m/s]")
        self.plt = plt
        # what moves is drawn every frame over a picture of what does not (blitting): the
        # colour bar, the title, the box's back edges are drawn once; the box's front edges
        # go over the bodies
        self.moving_parts = [self.disks, self.faces, self.shapes, self.insets, self.joints]
        self.moving_parts += [self.front] if self.front is not None else []
        for artist in [*self.moving_parts, self.stamp]:
            artist.set_animated(True)
        self.fig.canvas.draw()
        self.still = cast(Any, self.fig.canvas).copy_from_bbox(self.fig.bbox)

    def _joint_lines(self, positions: FloatArray, angles: FloatArray | None) -> FloatArray:
        """The joints as lines on the picture (K, 4, 2): each from A's centre through the
        anchors to B's centre (:func:`carom.joints.joint_lines`), seen through the camera in
        3D."""
        assert self.scene.joints is not None
        if self.camera is None:
            turn = np.zeros(len(positions)) if angles is None else np.asarray(angles, float)
            return joint_lines(*self.scene.joints, positions, turn)
        turns = np.asarray(angles, float) if angles is not None else None
        if turns is None:
            turns = np.zeros((len(positions), 4))
            turns[:, 0] = 1.0  # (unturned)
        lines = joint_lines(*self.scene.joints, positions, turns)
        screen, _ = self.camera.project(lines.reshape(-1, 3))
        return screen.reshape(-1, 4, 2)

    def draw(
        self,
        t: float,
        positions: FloatArray,
        velocities: FloatArray,
        angles: FloatArray | None = None,
    ) -> NDArray[np.uint8]:
        """The picture at time ``t`` [s]: (height, width, 3) RGB bytes."""
        scene = self.scene
        every = speed_colours(velocities, scene.moving, scene.speed_scale)
        outlines = scene.outlines
        if len(outlines.body):
            turn = np.zeros(len(positions)) if angles is None else np.asarray(angles, float)
            colour = every[outlines.body]
            placement = outlines.placements(positions, turn)
            self.shapes.placement = self.insets.placement = placement
            self.shapes.set_facecolor(colour * 0.72)
            self.shapes.set_edgecolor(colour * 0.45)
            self.insets.set_facecolor(colour + (1.0 - colour) * 0.12)
        if scene.joints is not None:
            self.joints.set_segments(list(self._joint_lines(positions, angles)))
        if self.camera is not None and len(scene.facets.body):
            turns = np.zeros((len(positions), 4)) if angles is None else np.asarray(angles)
            self._draw_faces(positions, turns, every)
        positions, velocities = positions[scene.round], velocities[scene.round]
        base = every[scene.round]
        radius = scene.radius[scene.round]
        if self.camera is None:
            centre, size = positions[:, :2], radius.copy()
            order = np.arange(len(size))
            shade = np.ones(len(size))
        else:
            centre, depth = self.camera.project(positions)
            size = radius / depth
            order = np.argsort(-depth, kind="stable")  # far first: near bodies cover them
            near, far = self.depth_range
            shade = 1.0 - 0.4 * np.clip((depth - near) / (far - near), 0.0, 1.0)
        centre, size, base, shade = centre[order], size[order], base[order], shade[order]
        # the layers of a body, consecutive so that a nearer body covers all of a farther one
        layer_size = size[:, None] * _LAYER_SIZE[None, :]
        shift = (size[:, None] * _LAYER_SHIFT[None, :])[..., None] * _LIGHT
        offsets = centre[:, None, :] + shift
        light = _LAYER_LIGHT
        colours = np.where(
            (light >= 0)[None, :, None],
            base[:, None, :] * np.abs(light)[None, :, None],
            base[:, None, :] + (1.0 - base[:, None, :]) * np.abs(light)[None, :, None],
        )
        colours *= shade[:, None, None]
        self.disks.set_offsets(offsets.reshape(-1, 2))
        self.disks.set_widths(2.0 * layer_size.reshape(-1))
        self.disks.set_heights(2.0 * layer_size.reshape(-1))
        self.disks.set_facecolor(np.clip(colours.reshape(-1, 3), 0.0, 1.0))
        self.stamp.set_text(f"t = {t:8.4f} s")
        canvas: Any = self.fig.canvas  # Agg: it has buffer_rgba
        canvas.restore_region(self.still)
        for artist in self.moving_parts:
            self.ax.draw_artist(artist)
        self.fig.draw_artist(self.stamp)
        rgba = np.asarray(canvas.buffer_rgba())
        return rgba[..., :3].copy()

    def _draw_faces(
        self, positions: FloatArray, orientations: FloatArray, colours: FloatArray
    ) -> None:
        """The 3D rigid bodies' faces that look at the camera, shaded by the light, far to
        near (the painter's algorithm), dimmed with distance as the balls are."""
        assert self.camera is not None
        facets = self.scene.facets
        world, normal = facets.placed(np.asarray(positions, float), orientations)
        middle = world.mean(axis=1)
        facing = np.einsum("ij,ij->i", normal, self.camera.eye - middle) > 0.0
        world, normal, middle = world[facing], normal[facing], middle[facing]
        owner = facets.body[facing]
        screen, depth = self.camera.project(world.reshape(-1, 3))
        screen = screen.reshape(-1, 3, 2)
        centre_depth = depth.reshape(-1, 3).mean(axis=1)
        order = np.argsort(-centre_depth, kind="stable")  # far first
        light = np.array([-0.35, -0.45, 0.82])  # from above, front left
        light /= np.linalg.norm(light)
        lit = 0.35 + 0.65 * np.clip(normal @ light, 0.0, 1.0)
        near, far = self.depth_range
        dim = 1.0 - 0.4 * np.clip((centre_depth - near) / (far - near), 0.0, 1.0)
        face = np.ones((len(owner), 4))
        face[:, :3] = np.clip(colours[owner] * (lit * dim)[:, None], 0.0, 1.0)
        # static and kinematic bodies (a drum, a bowl, the ground) are glass: what they hold
        # shows through
        face[~self.scene.moving[owner], 3] = 0.2
        face = face[order]
        edge = face.copy()
        edge[:, :3] *= 0.8
        self.faces.set_verts(screen[order])  # an array: matplotlib closes the triangles at once
        self.faces.set_facecolor(face)
        self.faces.set_edgecolor(edge)

    def close(self) -> None:
        self.plt.close(self.fig)
