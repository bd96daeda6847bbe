"""What surrounds a World's bodies, and how its engines are set: the box, its boundary and
gravity, the walls and planes, the materials and how two of them combine, the choice of engine
and each engine's settings. :class:`carom.World` is a Scenery with bodies and an engine.
"""

from __future__ import annotations

import math
from collections.abc import Mapping, Sequence
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, NDArray

from carom.body_input import vector
from carom.engines import registry
from carom.engines.edmd.settings import EdmdSettings
from carom.engines.registry import AUTO
from carom.engines.stepped.settings import RigidSettings
from carom.errors import CaromError
from carom.limits import check_magnitude, check_size
from carom.materials import COMBINE_RULES, CombineRule, Material

__all__ = ["Scenery", "as_material"]

FloatArray = NDArray[np.float64]


class EngineSettings(dict[str, Any]):
    """A world's settings of each engine, by the engine's name: assigning one checks that it
    is that engine's settings dataclass (a world built its engine with the settings object
    it held then, and rebuilds it at the next run when another is there); none can be
    removed."""

    def __setitem__(self, name: str, value: Any) -> None:
        entry = registry.find(name)
        if entry.settings is None or not isinstance(value, entry.settings):
            want = "no settings" if entry.settings is None else entry.settings.__name__
            raise CaromError(f"settings[{name!r}]: the {name} engine takes {want}")
        super().__setitem__(entry.name, value)

    def __delitem__(self, name: str) -> None:
        raise CaromError(
            f"every engine keeps its settings; assign new ones instead of removing {name!r}"
        )

    def update(self, *args: Any, **kwargs: Any) -> None:
        for name, value in dict(*args, **kwargs).items():
            self[name] = value

    def pop(self, name: str, *default: Any) -> Any:
        del self[name]

    def popitem(self) -> tuple[str, Any]:
        raise CaromError("every engine keeps its settings; assign new ones instead")

    def clear(self) -> None:
        self.popitem()


class Scenery:
    """The box, boundary, gravity, walls, planes, materials and engine settings of a World
    (:class:`carom.World` documents the parameters)."""

    def __init__(
        self,
        dim: int,
        box: ArrayLike,
        boundary: str = "walls",
        gravity: ArrayLike | None = None,
        *,
        walls: Material | float | Sequence[Material | float] = 1.0,
        t_c: float | None = None,
        combine: CombineRule = "mean",
        shell_thickness: float | None = None,
        engine: str = AUTO,
        rigid: RigidSettings | None = None,
        settings: Mapping[str, object] | None = None,
    ) -> None:
        if isinstance(dim, bool) or not isinstance(dim, int | np.integer) or dim not in (2, 3):
            raise CaromError(f"dim must be the whole number 2 or 3; got {dim!r}")
        self.dim = int(dim)
        self.box = check_size("box", vector("box", box, self.dim, "m"), "m")
        if boundary not in ("walls", "periodic", "open"):
            raise CaromError(f"boundary must be 'walls', 'periodic' or 'open'; got {boundary!r}")
        self.boundary = boundary
        if not isinstance(engine, str) or not registry.known(engine):
            raise CaromError(f"engine must be one of {registry.engine_choices()}; got {engine!r}")
        #: the engine chosen by name, or "auto"
        self.engine_choice = engine if engine == AUTO else registry.find(engine).name
        if rigid is not None and not isinstance(rigid, RigidSettings):
            raise CaromError(f"rigid must be a carom RigidSettings; got {rigid!r}")
        self.gravity = (
            np.zeros(dim)
            if gravity is None
            else check_magnitude("gravity", vector("gravity", gravity, dim, "m/s^2"), "m/s^2")
        )
        self.walls = self._wall_materials(walls)
        #: each engine's settings, by its name (:meth:`settings_of`); assigning an engine's
        #: settings (``world.engine_settings["rigid"] = RigidSettings(...)``) checks them and
        #: rebuilds the engine at the next run, from the world as it stands
        self.engine_settings: dict[str, Any] = EngineSettings(
            {e.name: e.settings() for e in registry.engines() if e.settings is not None}
        )
        if t_c is not None or shell_thickness is not None:
            given = {"t_c": t_c, "shell_thickness": shell_thickness}
            self.engine_settings["edmd"] = EdmdSettings(
                **{k: v for k, v in given.items() if v is not None}
            )
        if rigid is not None:
            self.engine_settings["rigid"] = rigid
        for name, value in (settings or {}).items():
            self.engine_settings[name] = value
        if combine not in COMBINE_RULES:
            raise CaromError(f"combine must be one of {COMBINE_RULES}; got {combine!r}")
        self.combine: CombineRule = combine
        self.materials: list[Material] = []
        self._pair_overrides: dict[tuple[int, int], float] = {}
        self.planes: list[tuple[FloatArray, FloatArray, Material]] = []
        self._start()

    def _start(self) -> None:
        """Called last by ``__init__``: a World starts its bodies, engine and clock."""

    def _invalidate(self) -> None:
        """Called after every change: a World drops its engine (rebuilt on the next run)."""

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
        materials = tuple(as_material("walls", item) for item in items)
        return materials * n if len(materials) == 1 else materials

    def settings_of(self, engine: str) -> Any:
        """The settings this world keeps for the engine called ``engine`` (None: it has
        none)."""
        return self.engine_settings.get(registry.find(engine).name)

    @property
    def settings(self) -> EdmdSettings:
        """The event-driven engine's settings (``t_c``, ``shell_thickness``)."""
        value = self.engine_settings["edmd"]
        assert isinstance(value, EdmdSettings)
        return value

    @property
    def rigid_settings(self) -> RigidSettings:
        """The rigid-body engine's settings (step, solver, sleep)."""
        value = self.engine_settings["rigid"]
        assert isinstance(value, RigidSettings)
        return value

    def add_material(self, material: Material) -> int:
        """Register a material; return its index (identical materials share one)."""
        if not isinstance(material, Material):
            raise CaromError(f"expected a carom.Material; got {material!r}")
        if material in self.materials:
            return self.materials.index(material)
        self.materials.append(material)
        self._invalidate()
        return len(self.materials) - 1

    def set_material(self, index: int, material: Material) -> None:
        """Replace material ``index`` (as :meth:`add_material` returned it) by ``material``:
        every body and plane of that material takes it from the next step (a built engine is
        built again then, the state and warm starts kept; the sleeping bodies wake when the
        change reaches a pair of the materials in the world).

        Raises
        ------
        CaromError
            No material ``index``, or not a Material. Nothing has changed then.
        """
        if isinstance(index, bool) or not isinstance(index, int | np.integer):
            raise CaromError(f"index must be a material's index; got {index!r}")
        if not 0 <= index < len(self.materials):
            raise CaromError(f"no material {index}; add it with add_material first")
        if not isinstance(material, Material):
            raise CaromError(f"expected a carom.Material; got {material!r}")
        self.materials[int(index)] = material
        self._invalidate()

    def set_gravity(self, gravity: ArrayLike) -> None:
        """Change gravity (d,) [m/s^2] from the next step on (a built engine is built again
        then, the state and warm starts kept; a new gravity wakes the sleeping bodies, which
        Box2D's ``b2World_SetGravity`` leaves asleep).

        Raises
        ------
        CaromError
            Not d finite numbers, or beyond the world's limits. Nothing has changed then.
        """
        self.gravity = check_magnitude(
            "gravity", vector("gravity", gravity, self.dim, "m/s^2"), "m/s^2"
        )
        self._invalidate()

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
        p = check_magnitude("point", vector("point", point, self.dim, "m"), "m")
        nrm = check_magnitude("normal", vector("normal", normal, self.dim, "-"), "-")
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
        self.planes.append((p, nrm / length, as_material("material", mat)))
        self._invalidate()
        return len(self.planes) - 1

    def _material_index(self, restitution: float | None, material: Material | int | None) -> int:
        if material is not None and restitution is not None:
            raise CaromError("give restitution= or material=, not both")
        if isinstance(material, int | np.integer) and not isinstance(material, bool):
            if not 0 <= material < len(self.materials):
                raise CaromError(f"no material {material}; add it with add_material first")
            return int(material)
        if material is not None:
            return self.add_material(as_material("material", material))
        return self.add_material(Material(1.0 if restitution is None else restitution))

    @property
    def pair_overrides(self) -> dict[tuple[int, int], float]:
        """Material pairs given their own restitution (:meth:`set_pair`), both orders."""
        return dict(self._pair_overrides)


def as_material(name: str, value: Material | float) -> Material:
    """A material, or a number read as the restitution of a smooth one."""
    if isinstance(value, Material):
        return value
    if isinstance(value, bool) or not isinstance(value, int | float | np.floating | np.integer):
        raise CaromError(f"{name} must be a carom.Material or a restitution; got {value!r}")
    return Material(float(value))
