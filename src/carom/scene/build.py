"""Building a :class:`carom.World` from a checked :class:`carom.scene.Scene`: materials, bodies
from ``[[bodies]]``, the generators and ``[[gas]]``, in that order; rigid bodies' shapes from
their ``shape`` keys."""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from pathlib import Path
from typing import Any, Literal, Protocol, cast

import numpy as np

from carom import shapes, shapes3d
from carom.errors import CaromError
from carom.limits import check_body_count
from carom.materials import Material
from carom.meshes import Mesh, decompose, load_mesh
from carom.scene import layouts
from carom.scene.schema import GENERATORS, Locator, SceneError
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
    gas: list[dict[str, Any]]
    settings: dict[str, Any]
    source: str
    text: str


def build_world(scene: Scene) -> World:
    """The :class:`carom.World` ``scene`` describes (bodies placed, nothing run yet)."""
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
    for table, index, b in _placed_bodies(scene):
        material = materials.get(b["material"]) if b["material"] else None
        try:
            if b.get("shape", "sphere") != "sphere":
                _add_shaped(world, _with_file(b, scene.source), material)
            elif b["radius"] is None:
                raise CaromError("radius is required for spheres: add radius = ... [m]")
            elif b["static"] or b.get("kind") == "static":
                world.add_static_spheres(b["positions"], radius=b["radius"], material=material)
            else:
                world.add_spheres(
                    b["positions"],
                    b["velocities"],
                    radius=b["radius"],
                    mass=1.0 if b["mass"] is None else b["mass"],
                    material=material,
                )
        except CaromError as exc:
            raise where.error([table], str(exc), "", index) from None
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
    try:
        world.build()  # refuses overlapping spheres and spheres outside the box
    except CaromError as exc:
        raise SceneError(f"{scene.source}: {exc}") from None
    return world


def shape_of(entry: Mapping[str, Any]) -> shapes.Shape2D:
    """The 2D shape a ``[[bodies]]`` entry (or a compound's piece) describes, from its
    ``shape`` and ``size``, ``radius``, ``vertices``, ``loop`` and ``pieces`` keys."""
    kind = entry["shape"]
    size = entry.get("size")
    radius = entry.get("radius")
    vertices = entry.get("vertices")
    sizes = [] if size is None else size if isinstance(size, list) else [size]

    def need(key: str, value: Any, example: str) -> Any:
        if value is None:
            raise CaromError(f"a {kind} needs {key} = {example}")
        return value

    rounding = 0.0 if radius is None else _one("radius", radius)
    if kind == "circle":
        return shapes.Circle(_one("radius", need("radius", radius, "... [m]")))
    if kind == "capsule":
        length = need("size", size, "the length between the caps' centres [m]")
        if len(sizes) != 1:
            raise CaromError(f"a capsule's size is one length [m]; got {length!r}")
        return shapes.Capsule(sizes[0], _one("radius", need("radius", radius, "... [m]")))
    if kind == "box":
        need("size", size, "[width, height] [m]")
        if len(sizes) != 2:
            raise CaromError(f"a box's size is [width, height] [m]; got {size!r}")
        return shapes.Box(sizes[0], sizes[1], rounding)
    if kind == "polygon":
        return shapes.Polygon(need("vertices", vertices, "[[x, y], ...] [m]"), rounding)
    if kind == "segment":
        ends = need("vertices", vertices, "[[x1, y1], [x2, y2]] [m]")
        if len(ends) != 2:
            raise CaromError(f"a segment has vertices = [[x1, y1], [x2, y2]]; got {ends!r}")
        return shapes.Segment(ends[0], ends[1], rounding)
    if kind == "chain":
        points = need("vertices", vertices, "[[x, y], ...] [m]")
        return shapes.Chain(points, loop=bool(entry.get("loop", False)), radius=rounding)
    assert kind == "compound"
    parts: list[Any] = []
    for k, piece in enumerate(need("pieces", entry.get("pieces"), "[{shape = ...}, ...]")):
        try:
            part = shape_of(piece)
        except CaromError as exc:
            raise CaromError(f"piece {k + 1}: {exc}") from None
        parts.append((part, piece.get("offset", [0.0, 0.0]), piece.get("angle", 0.0)))
    return shapes.Compound(parts)


def _with_file(entry: dict[str, Any], source: str) -> dict[str, Any]:
    """``entry`` with its ``file`` (a mesh) resolved against the scene file's folder."""
    file = entry.get("file")
    if file is None or Path(file).is_absolute() or source.startswith("<"):
        return entry
    return entry | {"file": str(Path(source).parent / file)}


def shape3d_of(entry: Mapping[str, Any]) -> shapes3d.Shape3D | Mesh:
    """The 3D shape a ``[[bodies]]`` entry (or a compound's piece) describes: ``ball``
    (radius), ``box`` (size = [x, y, z]), ``capsule`` (size = the length between the caps'
    centres, along z; radius), ``hull`` (vertices = its points), ``compound`` (pieces, each
    with an offset = [x, y, z] and an orientation = [w, x, y, z]) or ``mesh`` (a ``file``:
    a static body's surface as it is; a dynamic body's closed mesh cut into convex pieces,
    :func:`carom.meshes.decompose`, kept beside the file)."""
    kind = entry["shape"]
    size = entry.get("size")
    radius = entry.get("radius")
    sizes = [] if size is None else size if isinstance(size, list) else [size]

    def need(key: str, value: Any, example: str) -> Any:
        if value is None:
            raise CaromError(f"a {kind} needs {key} = {example}")
        return value

    if kind == "ball":
        return shapes3d.Sphere(_one("radius", need("radius", radius, "... [m]")))
    if kind == "box":
        need("size", size, "[x, y, z] [m]")
        if len(sizes) != 3:
            raise CaromError(f"a box's size in 3D is [x, y, z] [m]; got {size!r}")
        return shapes3d.Box(sizes)
    if kind == "capsule":
        need("size", size, "the length between the caps' centres [m]")
        if len(sizes) != 1:
            raise CaromError(f"a capsule's size is one length [m]; got {size!r}")
        return shapes3d.Capsule(sizes[0], _one("radius", need("radius", radius, "... [m]")))
    if kind == "hull":
        return shapes3d.Hull(need("vertices", entry.get("vertices"), "[[x, y, z], ...] [m]"))
    if kind == "mesh":
        file = need("file", entry.get("file"), '"bowl.obj" (beside the scene file)')
        dynamic = (entry.get("kind") or ("static" if entry.get("static") else "dynamic")) == (
            "dynamic"
        )
        return decompose(file) if dynamic else load_mesh(file)
    if kind != "compound":
        raise CaromError(
            f"a {kind} is a 2D shape; in 3D use ball, box, capsule, hull or compound "
            f"(or sphere for the event-driven engine's spheres)"
        )
    parts: list[Any] = []
    for k, piece in enumerate(need("pieces", entry.get("pieces"), "[{shape = ...}, ...]")):
        try:
            part = shape3d_of(piece)
        except CaromError as exc:
            raise CaromError(f"piece {k + 1}: {exc}") from None
        parts.append(
            (part, piece.get("offset", [0.0, 0.0, 0.0]), piece.get("orientation", [1.0, 0, 0, 0]))
        )
    return shapes3d.Compound(parts)


def _one(key: str, value: Any) -> float:
    if isinstance(value, list):
        raise CaromError(f"{key} must be one number for a body of this shape; got {value!r}")
    return float(value)


def _add_shaped(world: World, b: Mapping[str, Any], material: Material | None) -> None:
    """Add the rigid bodies of a ``[[bodies]]`` entry of a shape other than a sphere."""
    if world.dim == 3:
        _add_shaped_3d(world, b, material)
        return
    if b.get("orientations") is not None:
        raise CaromError("orientations are for 3D bodies; a 2D body takes angles = ... [rad]")
    shape = shape_of(b)
    kind = b.get("kind") or ("static" if b["static"] else "dynamic")
    positions = b["positions"]
    n = len(positions)
    velocities = [[0.0, 0.0]] * n if b["velocities"] is None else b["velocities"]
    angles = _per_body("angles", b.get("angles", 0.0), n)
    spins = _per_body("angular_velocities", b.get("angular_velocities", 0.0), n)
    masses = _per_body("mass", b["mass"], n) if b["mass"] is not None else [None] * n
    density = b.get("density")
    if kind == "dynamic" and density is None and b["mass"] is None:
        density = 1.0
    if b["mass"] is None or not isinstance(b["mass"], list):
        world.add_bodies(
            shape,
            positions,
            None if kind == "static" else velocities,
            angles=angles,
            angular_velocities=spins,
            density=density,
            mass=b["mass"],
            material=material,
            kind=cast("Literal['dynamic', 'static', 'kinematic']", kind),
        )
        return
    for i in range(n):  # a mass per body
        world.add_body(
            shape,
            positions[i],
            velocity=velocities[i],
            angle=angles[i],
            angular_velocity=spins[i],
            mass=masses[i],
            material=material,
            kind=cast("Literal['dynamic', 'static', 'kinematic']", kind),
        )


def _add_shaped_3d(world: World, b: Mapping[str, Any], material: Material | None) -> None:
    """Add the 3D rigid bodies of a ``[[bodies]]`` entry: one shape, one material, per-body
    positions, velocities, orientations and angular velocities (one for all, or one each)."""
    shape = shape3d_of(b)
    kind = b.get("kind") or ("static" if b["static"] else "dynamic")
    if np.any(np.asarray(b.get("angles", 0.0)) != 0.0):
        raise CaromError("angles are for 2D bodies; a 3D body takes orientations = [w, x, y, z]")
    positions = b["positions"]
    n = len(positions)
    spins = b.get("angular_velocities", 0.0)
    spins = [0.0, 0.0, 0.0] if isinstance(spins, int | float) and spins == 0 else spins
    masses = _per_body("mass", b["mass"], n) if isinstance(b["mass"], list) else [b["mass"]] * n
    density = b.get("density")
    if kind == "dynamic" and density is None and b["mass"] is None:
        density = 1.0
    common = {"material": material, "kind": cast("Literal['dynamic', 'static', 'kinematic']", kind)}
    if not isinstance(b["mass"], list):
        world.add_bodies(
            shape,
            positions,
            None if kind == "static" else b["velocities"],
            orientations=b.get("orientations"),
            angular_velocities=spins,
            density=density,
            mass=b["mass"],
            **common,  # type: ignore[arg-type]
        )
        return
    turns = b.get("orientations")
    for i in range(n):  # a mass per body
        world.add_body(
            shape,
            positions[i],
            velocity=None if b["velocities"] is None else b["velocities"][i],
            orientation=turns[i] if turns and isinstance(turns[0], list) else turns,
            angular_velocity=spins[i] if spins and isinstance(spins[0], list) else spins,
            mass=masses[i],
            **common,  # type: ignore[arg-type]
        )


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
        if table == "pyramid":
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
    return {
        "shape": "box",
        "size": [w, h],
        "radius": entry["radius"],
        "positions": positions.tolist(),
        "velocities": None,
        "mass": None,
        "density": entry["density"],
        "material": entry["material"],
        "static": False,
    }


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
    return {
        "shape": "box",
        "size": [a, b, c],
        "radius": None,
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
