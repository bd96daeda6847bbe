"""Building a :class:`carom.World` from a checked :class:`carom.scene.Scene`: materials, bodies
from ``[[bodies]]``, the generators and ``[[gas]]``, in that order."""

from __future__ import annotations

import math
from collections.abc import Iterator, Mapping
from typing import Any

import numpy as np

from carom.errors import CaromError
from carom.limits import check_body_count
from carom.materials import Material
from carom.scene import layouts
from carom.scene.load import Scene
from carom.scene.schema import GENERATORS, Locator, SceneError
from carom.world import World

__all__ = ["build_world", "count_bodies"]

#: packing fractions at which random sequential addition jams (disks: Hinrichsen, Feder &
#: Jullien 1986; spheres: Torquato, Uche & Stillinger 2006): a [[gas]] denser than this cannot
#: be placed at random
RSA_JAMMING = {2: 0.547, 3: 0.384}


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
                m["restitution"], beta=m["beta"], friction=m["friction"], beta0=m["beta0"]
            )
        except CaromError as exc:
            raise where.error(["materials"], str(exc), "", index) from None
    w = scene.world
    try:
        world = World(
            w["dimension"],
            w["box"],
            w["boundary"],
            w["gravity"],
            walls=_walls(w["walls"], materials),
            t_c=w["t_c"],
            combine=w["combine"],
        )
    except CaromError as exc:
        raise where.error(["world"], str(exc), "") from None
    for table, index, b in _placed_bodies(scene):
        material = materials.get(b["material"]) if b["material"] else None
        try:
            if b["static"]:
                world.add_static_spheres(b["positions"], radius=b["radius"], material=material)
            else:
                world.add_spheres(
                    b["positions"],
                    b["velocities"],
                    radius=b["radius"],
                    mass=b["mass"],
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


def count_bodies(scene: Scene) -> int:
    """How many bodies ``scene`` places, counted from its tables without placing them."""
    n = sum(len(b["positions"]) for b in scene.bodies)
    n += sum(r["count"] for r in scene.row)
    n += sum(r["rows"] * (r["rows"] + 1) // 2 for r in scene.rack)
    n += sum(math.prod(lattice["shape"]) for lattice in scene.lattice)
    for p in scene.pegs:
        rows = p["rows"]
        n += rows * (rows + 1) // 2 if p["layout"] == "triangle" else rows * (p["columns"] or 1)
    return int(n + sum(g["count"] for g in scene.gas))


def _placed_bodies(scene: Scene) -> Iterator[tuple[str, int, dict[str, Any]]]:
    """(table, index, [[bodies]]-shaped entry) for [[bodies]] and every generator, in the
    order they are added to the world."""
    dim = scene.world["dimension"]
    for index, entry in enumerate(scene.bodies):
        yield "bodies", index, entry
    for table in GENERATORS:
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
            yield (
                table,
                index,
                {
                    "positions": positions,
                    "velocities": velocities,
                    "radius": entry["radius"],
                    "mass": entry.get("mass", 1.0),
                    "material": entry["material"],
                    "static": table == "pegs",
                },
            )


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
    """``[world] walls``: restitutions or material names, one or one per wall face."""
    items = value if isinstance(value, list) else [value]
    return [materials[v] if isinstance(v, str) else float(v) for v in items]
