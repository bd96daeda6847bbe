"""Building a :class:`carom.World` from a checked :class:`carom.scene.Scene`: materials, bodies
from ``[[bodies]]``, the generators and ``[[gas]]``, in that order; rigid bodies' shapes from
their ``shape`` keys."""

from __future__ import annotations

import math
from collections.abc import Callable, Iterator, Mapping
from pathlib import Path
from typing import Any, Literal, Protocol, cast

import numpy as np
from numpy.typing import NDArray

from carom import shapes, shapes3d
from carom.errors import CaromError
from carom.joints import Distance, Joint, Prismatic, Revolute, Spherical, Target, Weld, Wheel
from carom.limits import check_body_count
from carom.materials import Material
from carom.meshes import Mesh, decompose, load_mesh
from carom.scene import layouts
from carom.scene.schema import GENERATORS, Locator, SceneError
from carom.shape_base import SHAPES
from carom.world import World

__all__ = ["build_world", "count_bodies"]

#: packing fractions at which random sequential addition jams (disks: Hinrichsen, Feder &
#: Jullien 1986; spheres: Torquato, Uche & Stillinger 2006): a [[gas]] denser than this cannot
#: be placed at random
RSA_JAMMING = {2: 0.547, 3: 0.384}


class Scene(Protocol):
    """What the build reads of a checked :class:`carom.scene.Scene` (whose ``build`` calls
    this module: it is typed by this protocol, not imported)."""

    world: dict[str, Any]
    materials: list[dict[str, Any]]
    bodies: list[dict[str, Any]]
    row: list[dict[str, Any]]
    rack: list[dict[str, Any]]
    lattice: list[dict[str, Any]]
    pegs: list[dict[str, Any]]
    pyramid: list[dict[str, Any]]
    cushions: list[dict[str, Any]]
    gas: list[dict[str, Any]]
    joints: list[dict[str, Any]]
    settings: dict[str, Any]
    source: str
    text: str


def build_world(scene: Scene, *, engine: bool = True) -> World:
    """The :class:`carom.World` ``scene`` describes (bodies placed, nothing run yet); with
    ``engine``, its engine built too (:meth:`carom.World.build`: the bodies' start checked)."""
    where = Locator(scene.source, scene.text)
    try:
        check_body_count(count_bodies(scene))
    except CaromError as exc:
        raise SceneError(f"{scene.source}: {exc}") from None
    materials: dict[str, Material] = {}
    for index, m in enumerate(scene.materials):
        try:
            materials[m["name"]] = Material(
                m["restitution"],
                beta=m["beta"],
                friction=m["friction"],
                beta0=m["beta0"],
                rolling=m["rolling"],
            )
        except CaromError as exc:
            raise where.refused("materials", exc, m, index) from None
    w = scene.world
    if "t_c" in w:  # (a checked scene keeps it in settings["edmd"]: a key set since is not read)
        raise SceneError(
            f"{scene.source}: the scene's world holds t_c; a checked scene keeps the engines' "
            f"settings in Scene.settings: set scene.settings['edmd'] = EdmdSettings(t_c=...)"
        )
    try:
        walls = _walls(w["walls"], materials)
    except CaromError as exc:
        raise where.error(["world", "walls"], str(exc), "") from None
    try:
        world = World(
            w["dimension"],
            w["box"],
            w["boundary"],
            w["gravity"],
            walls=walls,
            combine=w["combine"],
            engine=w["engine"],
            settings=scene.settings,
        )
    except CaromError as exc:
        raise where.error(["world"], str(exc), "") from None
    touching = []  # (table, index, entry, its bodies) of entries with a filter or a sensor
    for table, index, b in _placed_bodies(scene):
        material = materials.get(b["material"]) if b["material"] else None
        first = world.n_bodies
        try:
            if b.get("shape", "sphere") != "sphere":
                _add_shaped(world, _with_file(b, scene.source), material)
            elif b["radius"] is None:
                raise CaromError("radius is required for spheres: add radius = ... [m]")
            elif b["static"] or b.get("kind") == "static":
                _refuse_motion(b)
                world.add_static_spheres(b["positions"], radius=b["radius"], material=material)
            else:
                world.add_spheres(
                    b["positions"],
                    b["velocities"],
                    radius=b["radius"],
                    mass=1.0 if b["mass"] is None else b["mass"],
                    material=material,
                    angular_velocities=_sphere_spins(b, world.dim),
                )
        except CaromError as exc:
            raise where.error([table], str(exc), "", index) from None
        if b.get("sensor") or _sensor_parts(b) or any(b.get(k) is not None for k in _FILTER_KEYS):
            touching.append((table, index, b, np.arange(first, world.n_bodies)))
    for index, g in enumerate(scene.gas):
        try:
            _add_gas(world, g, materials.get(g["material"]) if g["material"] else None)
        except CaromError as exc:
            raise where.error(["gas"], str(exc), "", index) from None
    if world.n_bodies == 0:
        raise where.error(
            ["bodies"],
            "the scene has no bodies",
            "add [[bodies]], [[gas]] or generator ([[row]], [[rack]], ...) tables",
        )
    for table, index, b, ids in touching:  # (once the bodies are in: the engine is known)
        try:
            _filter_and_sense(world, b, ids)
        except CaromError as exc:
            raise where.error([table], str(exc), "", index) from None
    for index, j in enumerate(scene.joints):
        try:
            for joint in joints_of(j, world.dim):
                world.add_joint(joint)
        except CaromError as exc:
            raise where.error(["joints"], str(exc), "", index) from None
    if not engine:
        return world
    try:
        world.build()  # refuses overlapping spheres and spheres outside the box
    except CaromError as exc:
        raise SceneError(f"{scene.source}: {exc}") from None
    return world


#: a body entry's collision filter keys (:meth:`carom.World.set_filter`)
_FILTER_KEYS = ("category", "mask", "group")


def _filter_and_sense(world: World, b: Mapping[str, Any], ids: NDArray[np.int64]) -> None:
    """Give bodies ``ids`` of entry ``b`` its collision filter and make them sensors if it
    says so."""
    given = {key: b[key] for key in _FILTER_KEYS if b.get(key) is not None}
    if given:
        world.set_filter(ids, **given)
    if b.get("sensor"):
        world.set_sensor(ids)
    parts = _sensor_parts(b)
    if parts:
        # the parts' pieces in order, each part's own in a row (one a part for every piece
        # shape a compound takes; counted, not assumed)
        counts = [len(shape_of(piece, world.dim).pieces()) for piece in b["pieces"]]
        starts = np.concatenate(([0], np.cumsum(counts)))
        pieces = np.concatenate([np.arange(starts[k], starts[k + 1]) for k in parts])
        for i in ids.tolist():
            world.set_sensor(i, pieces=pieces)


def _sensor_parts(b: Mapping[str, Any]) -> list[int]:
    """The parts of a compound entry ``b`` marked ``sensor = true`` (by place)."""
    return [k for k, piece in enumerate(b.get("pieces") or ()) if piece.get("sensor")]


class _Entry:
    """A ``[[bodies]]`` entry (or a compound's piece) read for its shape: each key it needs,
    with an example in the message when it is missing."""

    def __init__(self, entry: Mapping[str, Any]) -> None:
        self.entry = entry
        self.kind = entry["shape"]
        size = entry.get("size")
        self.sizes = [] if size is None else size if isinstance(size, list) else [size]

    def need(self, key: str, example: str) -> Any:
        value = self.entry.get(key)
        if value is None:
            raise CaromError(f"a {self.kind} needs {key} = {example}")
        return value

    def radius(self) -> float:
        return _one("radius", self.need("radius", "... [m]"))

    def rounding(self) -> float:
        radius = self.entry.get("radius")
        return 0.0 if radius is None else _one("radius", radius)

    def size(self, count: int, example: str, what: str) -> list[Any]:
        """The ``size``: ``count`` numbers (``what`` says which, for the message)."""
        size = self.need("size", example)
        if len(self.sizes) != count:
            raise CaromError(f"a {self.kind}'s size {what}; got {size!r}")
        return self.sizes

    def mesh(self) -> shapes3d.Shape3D | Mesh:
        file = self.need("file", '"bowl.obj" (beside the scene file)')
        entry = self.entry
        kind = entry.get("kind") or ("static" if entry.get("static") else "dynamic")
        return decompose(file) if kind == "dynamic" else load_mesh(file)


#: how each shape is read, in each world: (shape name, dimension) -> the shape
_READERS: dict[tuple[str, int], Callable[[_Entry], Any]] = {
    ("circle", 2): lambda e: shapes.Circle(e.radius()),
    ("capsule", 2): lambda e: shapes.Capsule(
        e.size(1, "the length between the caps' centres [m]", "is one length [m]")[0], e.radius()
    ),
    ("box", 2): lambda e: _box(e, e.size(2, "[width, height] [m]", "is [width, height] [m]")),
    ("polygon", 2): lambda e: shapes.Polygon(e.need("vertices", "[[x, y], ...] [m]"), e.rounding()),
    ("segment", 2): lambda e: shapes.Segment(*_ends(e), radius=e.rounding()),
    ("chain", 2): lambda e: shapes.Chain(
        e.need("vertices", "[[x, y], ...] [m]"), loop=bool(e.entry.get("loop", False)),
        radius=e.rounding(),
    ),
    ("ball", 3): lambda e: shapes3d.Sphere(e.radius()),
    ("box", 3): lambda e: shapes3d.Box(e.size(3, "[x, y, z] [m]", "in 3D is [x, y, z] [m]")),
    ("capsule", 3): lambda e: shapes3d.Capsule(
        e.size(1, "the length between the caps' centres [m]", "is one length [m]")[0], e.radius()
    ),
    ("hull", 3): lambda e: shapes3d.Hull(e.need("vertices", "[[x, y, z], ...] [m]")),
    ("mesh", 3): _Entry.mesh,
}  # fmt: skip
#: a compound's piece placed: each dimension's keys and defaults for its offset and turn
_PLACING = {2: (("offset", [0.0, 0.0]), ("angle", 0.0)),
            3: (("offset", [0.0, 0.0, 0.0]), ("orientation", [1.0, 0, 0, 0]))}  # fmt: skip


def joints_of(entry: Mapping[str, Any], dim: int) -> list[Joint]:
    """The joints a ``[[joints]]`` table describes (:mod:`carom.joints`): one per pair of
    ``bodies``, each taking its own row of ``anchor``, ``anchors``, ``axis`` or ``target``
    when those are given one per joint."""
    raw = entry["bodies"]
    pairs = raw if isinstance(raw[0], list) else [raw]
    n = len(pairs)

    def each(key: str, width: int) -> list[Any]:
        value = entry[key]
        if value is None:
            return [None] * n
        if width == 2:  # rows of two points (a distance joint's anchors)
            if isinstance(value[0][0], list):
                return list(value) if len(value) == n else _count(key, len(value), n)
            return [value] * n
        if isinstance(value[0], list):
            return list(value) if len(value) == n else _count(key, len(value), n)
        return [value] * n

    kind = "weld" if entry["type"] == "fixed" else entry["type"]
    anchor, anchors = each("anchor", 1), each("anchors", 2)
    axis, target = each("axis", 1), each("target", 1)
    body = [None if a == -1 else a for a, _ in pairs], [None if b == -1 else b for _, b in pairs]
    common = {"collide": entry["collide"]}
    made: list[Joint] = []
    for k in range(n):
        a, b = body[0][k], body[1][k]
        if kind in ("revolute", "weld", "prismatic", "wheel", "spherical") and anchor[k] is None:
            raise CaromError(f"anchor is required for a {kind} joint: the point [m]")
        if kind in ("prismatic", "wheel") and axis[k] is None:
            raise CaromError(f"axis is required for a {kind} joint: its direction")
        if kind == "revolute":
            made.append(
                Revolute(
                    a, b, anchor[k], entry["limits"], entry["motor"], entry["spring"],
                    entry["collide"], axis[k],
                )
            )  # fmt: skip
        elif kind == "spherical":
            made.append(Spherical(a, b, anchor[k], **common))
        elif kind == "prismatic":
            made.append(
                Prismatic(
                    a,
                    b,
                    anchor[k],
                    axis[k],
                    entry["limits"],
                    entry["motor"],
                    entry["spring"],
                    **common,
                )
            )
        elif kind == "wheel":
            made.append(
                Wheel(
                    a,
                    b,
                    anchor[k],
                    axis[k],
                    entry["spring"],
                    entry["motor"],
                    entry["limits"],
                    **common,
                )
            )
        elif kind == "weld":
            made.append(Weld(a, b, anchor[k], entry["spring"], entry["angular_spring"], **common))
        elif kind == "distance":
            if anchors[k] is None or len(anchors[k]) != 2:
                raise CaromError(
                    "anchors is required for a distance joint: [[xa, ya], [xb, yb]] [m]"
                )
            made.append(
                Distance(
                    a, b, anchors[k][0], anchors[k][1], entry["length"], entry["min_length"],
                    entry["max_length"], entry["spring"], **common,
                )
            )  # fmt: skip
        else:
            if target[k] is None or b is None:
                raise CaromError("a target joint needs target = [x, y] and bodies = [-1, b]")
            made.append(
                Target(
                    b,
                    target[k],
                    anchor[k],
                    entry["hertz"],
                    entry["damping_ratio"],
                    entry["max_force"],
                )
            )
    return made


def _count(key: str, got: int, n: int) -> list[Any]:
    raise CaromError(f"{key} has {got} rows for {n} joints: give one, or one per joint")


def _box(e: _Entry, size: list[Any]) -> shapes.Box:
    return shapes.Box(size[0], size[1], e.rounding())


def _ends(e: _Entry) -> tuple[Any, Any]:
    ends = e.need("vertices", "[[x1, y1], [x2, y2]] [m]")
    if len(ends) != 2:
        raise CaromError(f"a segment has vertices = [[x1, y1], [x2, y2]]; got {ends!r}")
    return ends[0], ends[1]


def shape_of(entry: Mapping[str, Any], dim: int = 2) -> Any:
    """The shape a ``[[bodies]]`` entry (or a compound's piece) describes in a ``dim``-D
    world, from its ``shape`` and ``size``, ``radius``, ``vertices``, ``loop``, ``file`` and
    ``pieces`` keys (docs/scenes.md): a :class:`carom.shapes.Shape2D`, a
    :class:`carom.shapes3d.Shape3D` or a :class:`carom.meshes.Mesh` (a static body's surface
    as it is; a dynamic body's closed mesh cut into convex pieces,
    :func:`carom.meshes.decompose`, kept beside the file)."""
    read = _Entry(entry)
    kind = read.kind
    if dim not in SHAPES[kind].dims:
        *some, last = (n for n, shape in SHAPES.items() if dim in shape.dims and n != "sphere")
        raise CaromError(
            f"a {kind} is a {SHAPES[kind].dims[0]}D shape; in {dim}D use {', '.join(some)} or "
            f"{last} (or sphere for the event-driven engine's spheres)"
        )
    if kind != "compound":
        return _READERS[kind, dim](read)
    (at, origin), (turn, unturned) = _PLACING[dim]
    (_, _), (other, _) = _PLACING[5 - dim]
    parts: list[Any] = []
    for k, piece in enumerate(read.need("pieces", "[{shape = ...}, ...]")):
        try:
            if other in piece:  # (it was ignored: the piece stood unturned)
                raise CaromError(
                    f"{other} turns a piece in {5 - dim}D; in {dim}D a piece is turned by "
                    f"{turn} = {unturned!r}"
                )
            part = shape_of(piece, dim)
        except CaromError as exc:
            raise CaromError(f"piece {k + 1}: {exc}") from None
        parts.append((part, piece.get(at, origin), piece.get(turn, unturned)))
    return shapes.Compound(parts) if dim == 2 else shapes3d.Compound(parts)


def _with_file(entry: dict[str, Any], source: str) -> dict[str, Any]:
    """``entry`` with its ``file`` (a mesh) resolved against the scene file's folder."""
    file = entry.get("file")
    if file is None or Path(file).is_absolute() or source.startswith("<"):
        return entry
    return entry | {"file": str(Path(source).parent / file)}


def _one(key: str, value: Any) -> float:
    if isinstance(value, list):
        raise CaromError(f"{key} must be one number for a body of this shape; got {value!r}")
    return float(value)


def _refuse_motion(b: Mapping[str, Any]) -> None:
    """Refuse velocities or spins on a static entry (it never moves: they would be
    dropped without a word)."""
    for key in ("velocities", "angular_velocities"):
        value = b.get(key)
        if value is not None and np.any(np.asarray(value, dtype=float) != 0.0):
            raise CaromError(
                f"a static body never moves, but {key} is given; remove {key}, or make the "
                f'bodies kind = "kinematic" (moving on their own) or "dynamic"'
            )


def _add_shaped(world: World, b: Mapping[str, Any], material: Material | None) -> None:
    """Add the rigid bodies of a ``[[bodies]]`` entry of a shape other than a sphere: one
    shape, one material, per-body positions, velocities, turns and spins (one for all, or
    one each), and a mass for all or one each."""
    shape = shape_of(b, world.dim)
    kind = cast("Literal['dynamic', 'static', 'kinematic']",
                b.get("kind") or ("static" if b["static"] else "dynamic"))  # fmt: skip
    positions = b["positions"]
    n = len(positions)
    turning, each = (_turning_2d if world.dim == 2 else _turning_3d)(b, n)
    density = b.get("density")
    if kind == "dynamic" and density is None and b["mass"] is None:
        density = 1.0
    velocities = b["velocities"]
    if kind == "static":
        _refuse_motion(b)
    if not isinstance(b["mass"], list):
        world.add_bodies(
            shape, positions, velocities, density=density,
            mass=b["mass"], material=material, kind=kind, **turning,
        )  # fmt: skip
        return
    masses = _per_body("mass", b["mass"], n)
    for i in range(n):  # a mass per body
        world.add_body(
            shape, positions[i], velocity=None if velocities is None else velocities[i],
            mass=masses[i], material=material, kind=kind, **each(i),
        )  # fmt: skip


def _turning_2d(b: Mapping[str, Any], n: int) -> tuple[dict[str, Any], Callable[[int], Any]]:
    """A 2D entry's angles and angular velocities: for all the bodies, and for body ``i``."""
    if b.get("orientations") is not None:
        raise CaromError("orientations are for 3D bodies; a 2D body takes angles = ... [rad]")
    angles = _per_body("angles", b.get("angles", 0.0), n)
    spins = _per_body("angular_velocities", b.get("angular_velocities", 0.0), n)
    return (
        {"angles": angles, "angular_velocities": spins},
        lambda i: {"angle": angles[i], "angular_velocity": spins[i]},
    )


def _turning_3d(b: Mapping[str, Any], n: int) -> tuple[dict[str, Any], Callable[[int], Any]]:
    """A 3D entry's orientations and angular velocities: for all the bodies (one for all or
    one each), and for body ``i``."""
    if np.any(np.asarray(b.get("angles", 0.0)) != 0.0):
        raise CaromError("angles are for 2D bodies; a 3D body takes orientations = [w, x, y, z]")
    spins = b.get("angular_velocities", 0.0)
    spins = [0.0, 0.0, 0.0] if isinstance(spins, int | float) and spins == 0 else spins
    turns = b.get("orientations")

    def one(values: Any, i: int) -> Any:
        return values[i] if values and isinstance(values[0], list) else values

    return (
        {"orientations": turns, "angular_velocities": spins},
        lambda i: {"orientation": one(turns, i), "angular_velocity": one(spins, i)},
    )


def _sphere_spins(b: Mapping[str, Any], dim: int) -> Any:
    """A sphere entry's ``angular_velocities`` as :meth:`carom.World.add_spheres` takes them
    (one for all, or one each; None when not spinning)."""
    spins = b.get("angular_velocities")
    if spins is None or (isinstance(spins, int | float) and spins == 0):
        return None
    n = len(b["positions"])
    value = np.asarray(spins, dtype=float)
    if dim == 3 and value.shape == (3,):
        return np.tile(value, (n, 1))
    if dim == 2 and value.ndim == 0:
        return np.full(n, float(value))
    return value


def _per_body(key: str, value: Any, n: int) -> list[Any]:
    if isinstance(value, list):
        if len(value) != n:
            raise CaromError(f"{key} has {len(value)} values for {n} positions; give one or {n}")
        return list(value)
    return [value] * n


def count_bodies(scene: Scene) -> int:
    """How many bodies ``scene`` places, counted from its tables without placing them."""
    n = sum(len(b["positions"]) for b in scene.bodies)
    n += sum(r["count"] for r in scene.row)
    n += sum(r["rows"] * (r["rows"] + 1) // 2 for r in scene.rack)
    n += 4 * len(scene.cushions)
    n += sum(math.prod(lattice["shape"]) for lattice in scene.lattice)
    for p in scene.pegs:
        rows = p["rows"]
        n += rows * (rows + 1) // 2 if p["layout"] == "triangle" else rows * (p["columns"] or 1)
    for p in scene.pyramid:
        rows = p["rows"]
        if scene.world["dimension"] == 3:
            n += rows * (rows + 1) * (2 * rows + 1) // 6  # the sum of squares
        else:
            n += rows * (rows + 1) // 2 * math.prod(p["repeat"])
    return int(n + sum(g["count"] for g in scene.gas))


def _placed_bodies(scene: Scene) -> Iterator[tuple[str, int, dict[str, Any]]]:
    """(table, index, [[bodies]]-shaped entry) for [[bodies]] and every generator, in the
    order they are added to the world."""
    dim = scene.world["dimension"]
    for index, entry in enumerate(scene.bodies):
        yield "bodies", index, entry
    for index, entry in enumerate(scene.pyramid):
        yield "pyramid", index, _pyramid(entry, dim)
    for table in GENERATORS:
        if table in ("pyramid", "cushions"):
            continue
        for index, entry in enumerate(getattr(scene, table)):
            positions = _generated_positions(table, entry, dim)
            count = len(positions)
            velocity = entry.get("velocity")
            velocities = (
                np.zeros((count, dim)) if velocity is None else np.tile(velocity, (count, 1))
            )
            if table == "lattice" and entry["temperature"] > 0:
                rng = np.random.default_rng(entry["seed"])
                velocities += layouts.maxwell_velocities(
                    rng, count, dim, entry["temperature"], entry["mass"]
                )
            placed = {
                "positions": positions,
                "velocities": velocities,
                "radius": entry["radius"],
                "mass": entry.get("mass", 1.0),
                "material": entry["material"],
                "static": table == "pegs",
            }
            if entry.get("body") is not None:  # a lattice of rigid bodies
                body = entry["body"]
                placed |= {"radius": body.get("radius"), "size": body.get("size")}
                placed |= {"shape": body["shape"], "vertices": body.get("vertices")}
            yield table, index, placed
    for index, entry in enumerate(scene.cushions):  # (the rails after every ball)
        for rail in _cushions(entry, dim):
            yield "cushions", index, rail


def _cushions(entry: Mapping[str, Any], dim: int) -> list[dict[str, Any]]:
    """A ``[[cushions]]`` table as four ``[[bodies]]`` entries: the static rails of a billiards
    table around ``area`` (:func:`carom.scene.layouts.cushion_rails`), their noses ``height``
    above the cloth at z = ``cloth``."""
    if dim != 3:
        raise CaromError(
            "cushions are 3D rails (their nose above the ball's centre); use walls in 2D"
        )
    low, high = entry["area"]
    if len(low) != 2 or len(high) != 2:
        raise CaromError(f"area is [[x0, y0], [x1, y1]] on the cloth [m]; got {entry['area']!r}")
    rails = layouts.cushion_rails(low, high, entry["height"], entry["width"], entry["cloth"])
    return [
        {
            "shape": "hull",
            "vertices": points.tolist(),
            "positions": [position.tolist()],
            "orientations": orientation.tolist(),
            "velocities": None,
            "mass": None,
            "material": entry["material"],
            "kind": "static",
            "static": True,
        }
        for points, position, orientation in rails
    ]


def _pyramid(entry: Mapping[str, Any], dim: int = 2) -> dict[str, Any]:
    """A ``[[pyramid]]`` as a ``[[bodies]]`` entry of boxes: ``rows`` rows of boxes standing on
    the line through ``base`` (the bottom row's centre, on the ground), ``rows - i`` boxes in
    row ``i``, ``gap`` apart; repeated ``repeat = [nx, ny]`` times, ``pitch`` apart. In 3D a
    square pyramid: ``(rows - i)^2`` boxes in layer ``i``, standing on the plane z = base's z
    around base's x and y (no repeats)."""
    if dim == 3:
        return _pyramid_3d(entry)
    size = entry["size"] if isinstance(entry["size"], list) else [entry["size"]]
    w, h = float(size[0]), float(size[-1])  # one number: a square
    rows, gap = int(entry["rows"]), float(entry["gap"])
    repeat = entry["repeat"]
    if len(repeat) > 2:
        raise CaromError(f"repeat must be [nx] or [nx, ny]; got {repeat!r}")
    nx, ny = int(repeat[0]), int(repeat[-1]) if len(repeat) == 2 else 1
    pitch = entry["pitch"] or [(rows + 1) * (w + gap), (rows + 1) * h]
    if len(pitch) != 2:
        raise CaromError(f"pitch must be [dx, dy] [m]; got {pitch!r}")
    one = np.array(
        [
            [(j - (rows - i - 1) / 2.0) * (w + gap), (i + 0.5) * h]
            for i in range(rows)
            for j in range(rows - i)
        ]
    )
    copies = np.array([[cx * pitch[0], cy * pitch[1]] for cy in range(ny) for cx in range(nx)])
    positions = (np.asarray(entry["base"], float) + copies[:, None, :] + one[None, :, :]).reshape(
        -1, 2
    )
    return _stacked_boxes(entry, [w, h], entry["radius"], positions)


def _pyramid_3d(entry: Mapping[str, Any]) -> dict[str, Any]:
    """A 3D ``[[pyramid]]`` (:func:`_pyramid`)."""
    size = entry["size"] if isinstance(entry["size"], list) else [entry["size"]]
    if len(size) == 1:
        size = size * 3
    if len(size) != 3:
        raise CaromError(f"a 3D pyramid's size is one length or [x, y, z] [m]; got {size!r}")
    if list(entry["repeat"]) not in ([1], [1, 1]):
        raise CaromError("repeat is for 2D pyramids; place more [[pyramid]] tables in 3D")
    a, b, c = (float(s) for s in size)
    rows, gap = int(entry["rows"]), float(entry["gap"])
    base = np.asarray(entry["base"], float)
    if base.shape != (3,):
        raise CaromError(f"a 3D pyramid's base is [x, y, z] [m]; got {entry['base']!r}")
    offsets = [
        ((i - (n - 1) / 2.0) * (a + gap), (j - (n - 1) / 2.0) * (b + gap), (layer + 0.5) * c)
        for layer in range(rows)
        for n in [rows - layer]
        for j in range(n)
        for i in range(n)
    ]
    positions = base + np.array(offsets)
    return _stacked_boxes(entry, [a, b, c], None, positions)


def _stacked_boxes(
    entry: Mapping[str, Any], size: list[float], radius: float | None, positions: np.ndarray
) -> dict[str, Any]:
    """The ``[[bodies]]`` entry of a pyramid's boxes (2D or 3D): dynamic, at rest, the
    pyramid's density and material."""
    return {
        "shape": "box",
        "size": size,
        "radius": radius,
        "positions": positions.tolist(),
        "velocities": None,
        "mass": None,
        "density": entry["density"],
        "material": entry["material"],
        "static": False,
    }


def _generated_positions(table: str, entry: Mapping[str, Any], dim: int) -> np.ndarray:
    """The centres a generator table places, (n, dim) [m]."""
    if table == "row":
        spacing = entry["spacing"] or 2.0 * entry["radius"]
        return layouts.row_positions(entry["count"], entry["start"], spacing, entry["direction"])
    if table == "rack":
        return layouts.rack_positions(
            entry["rows"], entry["apex"], 2.0 * entry["radius"] + entry["gap"], entry["direction"]
        )
    if table == "lattice":
        return layouts.lattice_positions(entry["shape"], entry["origin"], entry["spacing"])
    assert table == "pegs"
    return layouts.peg_positions(
        entry["rows"], entry["top"], entry["spacing"], entry["layout"], entry["columns"]
    )


def _add_gas(world: World, gas: Mapping[str, Any], material: Material | None) -> None:
    """``count`` spheres of one radius placed at random, without overlap, at the packing
    fraction ``packing`` of the box, with Maxwell velocities at ``temperature`` (k_B = 1)."""
    dim = world.dim
    count, radius, packing = gas["count"], gas["radius"], gas["packing"]
    if gas["region"] is None:
        volume = float(np.prod(world.box))
    else:
        volume = float(np.prod(np.subtract(gas["region"][1], gas["region"][0])))
    unit = math.pi * radius**2 if dim == 2 else 4.0 / 3.0 * math.pi * radius**3
    if count * unit > packing * volume * (1 + 1e-12):
        raise CaromError(
            f"{count} spheres of radius {radius} need a packing of "
            f"{count * unit / volume:.4g}, more than packing = {packing}; enlarge the box, "
            f"or lower count or radius"
        )
    if count * unit > RSA_JAMMING[dim] * volume:
        raise CaromError(
            f"{count} spheres of radius {radius} need a packing of "
            f"{count * unit / volume:.4g}, beyond {RSA_JAMMING[dim]}, where placing them at "
            f"random jams; enlarge the box or lower count or radius (or place them on a "
            f"[[lattice]])"
        )
    rng = np.random.default_rng(gas["seed"])
    region = gas["region"]
    low = np.zeros(dim) if region is None else np.asarray(region[0], dtype=float)
    high = world.box.copy() if region is None else np.asarray(region[1], dtype=float)
    if np.any(low < 0) or np.any(high > world.box) or np.any(high <= low):
        raise CaromError(
            f"region {region} must be a box inside [0, {world.box.tolist()}] with its high "
            f"corner above its low one; fix its corners"
        )
    positions = _random_positions(world, count, radius, rng, low, high)
    velocities = layouts.maxwell_velocities(rng, count, dim, gas["temperature"], gas["mass"])
    if gas["drift"] is not None:
        velocities += np.asarray(gas["drift"], dtype=float)
    world.add_spheres(positions, velocities, radius=radius, mass=gas["mass"], material=material)


def _random_positions(
    world: World,
    count: int,
    radius: float,
    rng: np.random.Generator,
    low: np.ndarray,
    high: np.ndarray,
) -> np.ndarray:
    """Random sequential addition in the box ``[low, high]``: uniform trial points, each kept
    if it overlaps nothing placed before (walls, earlier gas, bodies already in the world)."""
    dim = world.dim
    box = world.box
    walled = world.boundary == "walls" or np.any(low > 0) or np.any(high < box)
    margin = radius if walled else 0.0
    cell = 2.0 * radius
    grid: dict[tuple[int, ...], list[int]] = {}
    others = [(p, r) for p, r in zip(world.positions, world.radii, strict=True)]
    placed: list[np.ndarray] = []
    tries = 0
    while len(placed) < count:
        tries += 1
        if tries > 200 * count + 10_000:
            raise CaromError(
                f"could place only {len(placed)} of {count} spheres at random without overlap; "
                f"lower packing (random placement jams near 0.38 in 3D, 0.55 in 2D)"
            )
        p = low + margin + rng.random(dim) * (high - low - 2 * margin)
        key = tuple(int(c) for c in np.floor(p / cell))
        clash = False
        for offset in np.ndindex(*([3] * dim)):
            near = tuple((k + o - 1) for k, o in zip(key, offset, strict=True))
            if world.boundary == "periodic":
                near = tuple(n % max(1, int(box[d] // cell)) for d, n in enumerate(near))
            for j in grid.get(near, []):
                d = p - placed[j]
                if world.boundary == "periodic":
                    d -= box * np.round(d / box)
                if d @ d < (2 * radius) ** 2:
                    clash = True
                    break
            if clash:
                break
        if not clash:
            for q, r in others:
                d = p - q
                if world.boundary == "periodic":
                    d -= box * np.round(d / box)
                if d @ d < (radius + r) ** 2:
                    clash = True
                    break
        if clash:
            continue
        if world.boundary == "periodic":
            key = tuple(k % max(1, int(box[d] // cell)) for d, k in enumerate(key))
        grid.setdefault(key, []).append(len(placed))
        placed.append(p)
    return np.array(placed)


def _walls(value: Any, materials: Mapping[str, Material]) -> list[Material | float]:
    # (a number is a smooth material of that restitution: Material checks its range)
    """``[world] walls``: restitutions or material names, one or one per wall face."""
    items = value if isinstance(value, list) else [value]
    return [materials[v] if isinstance(v, str) else Material(float(v)) for v in items]
