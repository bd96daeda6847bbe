"""One point of a sweep, run where Dask puts it: build the scene, run it, measure.

:func:`run_point` is the task. It runs the scene to ``warmup``, opens the averaging window
(:meth:`carom.observables.Stats.reset`), runs to ``until`` and returns the observables of
that window, with the closed form each one has where carom knows it for this point
(``<name>_theory``), or the message of whatever went wrong. It never raises for a bad point:
a failing point is a row of the table like any other.

The observables (``docs/sweeps.md``), over the window:

==================== ======== ================================================ ==================
name                 unit     what                                             closed form
==================== ======== ================================================ ==================
pressure             Pa       collision virial (2D: N/m; NaN under gravity)    -
compressibility      -        Z = P / (n T)                                    Kolafa (3D),
                                                                               Henderson (2D)
temperature          J        translational, k_B = 1, at the end               -
temperature_ratio    -        T at the end over T at the start                 Haff's law
collision_rate       1/s      collisions per body per second, 2 C / (N t)      Enskog
mean_free_time       s        N t / (2 C)                                      Enskog
energy_lost          J        dissipated by the impacts                        -
energy_lost_fraction -        energy_lost over the kinetic energy at the start -
packing_fraction     -        the bodies' volume over the box's                -
rebound_height       m        body 0's first rebound off the floor, u^2/(2 g)  e^2 h0
stack_drift          m        the farthest any moving body went from where     -
                              the window found it
==================== ======== ================================================ ==================

Any field of ``summary.json`` is an observable too, by its dotted path
(``energy.dissipated_J``, ``momentum.end_kg_m_s.0``); it then describes the window.
"""

from __future__ import annotations

import math
import os
import socket
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from numpy.typing import NDArray

from carom.errors import CaromError

if TYPE_CHECKING:
    from carom.world import World

__all__ = [
    "OBSERVABLES",
    "SUMMARY_FIELDS",
    "Observable",
    "check_observable",
    "kernels_in_memory",
    "run_point",
]


@dataclass(frozen=True)
class Window:
    """The world when the averaging window opened, and what the run saw."""

    time: float  # [s]
    temperature: float  # [J]
    kinetic: float  # [J]
    positions: NDArray[np.float64]  # (N, d) [m]
    fluid: _Fluid | None  # the world as a hard-sphere fluid, for the closed forms
    first_bounce: tuple[float, float] | None  # body 0's first (u_before, u_after) at the floor
    initial_height: float | None  # body 0's drop height above the floor at t = 0 [m]
    floor_restitution: float | None


@dataclass(frozen=True)
class Observable:
    """What an observable measures and how; its closed form where carom knows one."""

    unit: str
    what: str
    measure: Callable[[World, Window], float]
    theory: Callable[[World, Window], float | None] | None = None
    theory_name: Callable[[int], str] | None = None


# -- the fluid's numbers, for the closed forms (PHYSICS.md section 6) ------------------------


@dataclass(frozen=True)
class _Fluid:
    dim: int
    n: float  # number density [1/m^d]
    sigma: float  # diameter [m]
    mass: float  # [kg]
    fraction: float  # packing (area) fraction
    restitution: float  # of a pair of its bodies

    def contact(self) -> float:
        """The pair distribution at contact, g(sigma): Carnahan-Starling (3D), Henderson
        (2D)."""
        f = self.fraction
        if self.dim == 3:
            return (1 - f / 2) / (1 - f) ** 3
        return (1 - 7 * f / 16) / (1 - f) ** 2

    def enskog_rate(self, temperature: float) -> float:
        """Collisions per body per second: 4 n sigma^2 g sqrt(pi T / m) (3D),
        2 n sigma g sqrt(pi T / m) (2D)."""
        s = self.sigma ** (self.dim - 1)
        factor = 4.0 if self.dim == 3 else 2.0
        return factor * self.n * s * self.contact() * math.sqrt(math.pi * temperature / self.mass)


def _fluid(world: World) -> _Fluid | None:
    """The world as a homogeneous fluid of hard spheres (disks), if it is one: one radius,
    one mass, one material, a periodic box, no gravity, smooth impacts; else None."""
    from carom.materials import pair_table

    b = world.bodies
    if (
        world.boundary != "periodic"
        or np.any(world.gravity != 0.0)
        or not b.spheres_only
        or not np.all(b.mobile)
        or b.n < 2
    ):
        return None
    r, m, mat = b.radius, b.mass, b.material
    if np.ptp(r) != 0.0 or np.ptp(m) != 0.0 or np.ptp(mat) != 0:
        return None
    material = world.materials[int(mat[0])]
    if material.law != "smooth":
        return None
    e = float(pair_table(world.materials, world.combine).e[mat[0], mat[0]])
    volume = float(np.prod(world.box))
    sigma = 2.0 * float(r[0])
    unit = math.pi * sigma**3 / 6 if world.dim == 3 else math.pi * sigma**2 / 4
    n = b.n / volume
    return _Fluid(world.dim, n, sigma, float(m[0]), n * unit, e)


def kolafa(phi: float) -> float:
    """Kolafa, Labik & Malijevsky (PCCP 6, 2335, 2004): the hard-sphere fluid's Z(phi)."""
    return (1 + phi + phi**2 - (2 / 3) * (phi**3 + phi**4)) / (1 - phi) ** 3


def carnahan_starling(phi: float) -> float:
    """Carnahan & Starling (J. Chem. Phys. 51, 635, 1969): Z(phi) of hard spheres."""
    return (1 + phi + phi**2 - phi**3) / (1 - phi) ** 3


def henderson(eta: float) -> float:
    """Henderson (Mol. Phys. 30, 971, 1975): Z(eta) of hard disks."""
    return (1 + eta**2 / 8) / (1 - eta) ** 2


# -- the observables --------------------------------------------------------------------------


def _span(world: World, window: Window) -> float:
    return world.time - window.time


def _pressure(world: World, window: Window) -> float:
    return float(world.stats.pressure)


def _compressibility(world: World, window: Window) -> float:
    mobile = int(np.count_nonzero(world.bodies.mobile))
    n = mobile / float(np.prod(world.box))
    t = world.stats.temperature
    return float(world.stats.pressure / (n * t)) if n > 0 and t > 0 else math.nan


def _compressibility_theory(world: World, window: Window) -> float | None:
    fluid = window.fluid
    if fluid is None or fluid.restitution != 1.0:
        return None
    return kolafa(fluid.fraction) if fluid.dim == 3 else henderson(fluid.fraction)


def _temperature_ratio(world: World, window: Window) -> float:
    return world.stats.temperature / window.temperature if window.temperature > 0 else math.nan


def _haff(world: World, window: Window) -> float | None:
    """Haff's law: T / T0 = 1 / (1 + t / tau0)^2, 1/tau0 = (1 - e^2) omega(T0) / (2 d)."""
    fluid = window.fluid
    if fluid is None:
        return None
    inv_tau0 = (1 - fluid.restitution**2) * fluid.enskog_rate(window.temperature) / (2 * fluid.dim)
    return 1.0 / (1.0 + _span(world, window) * inv_tau0) ** 2


def _collision_rate(world: World, window: Window) -> float:
    mobile = int(np.count_nonzero(world.bodies.mobile))
    span = _span(world, window)
    return 2.0 * world.stats.collisions / (mobile * span) if mobile and span > 0 else math.nan


def _enskog_rate(world: World, window: Window) -> float | None:
    fluid = window.fluid
    if fluid is None or fluid.restitution != 1.0:
        return None  # a cooling gas's rate falls with its temperature
    return fluid.enskog_rate(window.temperature)


def _enskog_time(world: World, window: Window) -> float | None:
    rate = _enskog_rate(world, window)
    return None if rate is None else 1.0 / rate


def _energy_lost_fraction(world: World, window: Window) -> float:
    return world.stats.energy_lost / window.kinetic if window.kinetic > 0 else math.nan


def _packing_fraction(world: World, window: Window) -> float:
    b = world.bodies
    if not b.spheres_only:
        return math.nan  # (the volume of other shapes is not the bounding sphere's)
    r = b.radius[b.mobile]
    unit = 4 / 3 * math.pi * r**3 if world.dim == 3 else math.pi * r**2
    return float(np.sum(unit) / np.prod(world.box))


def _rebound(world: World, window: Window) -> float:
    g = float(np.linalg.norm(world.gravity))
    if window.first_bounce is None or g == 0.0:
        return math.nan
    return window.first_bounce[1] ** 2 / (2.0 * g)


def _rebound_theory(world: World, window: Window) -> float | None:
    if window.initial_height is None or window.floor_restitution is None:
        return None
    return window.floor_restitution**2 * window.initial_height


def _stack_drift(world: World, window: Window) -> float:
    moving = world.bodies.mobile
    if not np.any(moving):
        return 0.0
    shift = world.positions[moving] - window.positions[moving]
    return float(np.max(np.sqrt(np.sum(shift * shift, axis=1))))


def _dim_name(names: dict[int, str]) -> Callable[[int], str]:
    return lambda dim: names[dim]


OBSERVABLES: dict[str, Observable] = {
    "pressure": Observable("Pa", "collision virial (2D: N/m)", _pressure),
    "compressibility": Observable(
        "-",
        "compressibility factor Z = P / (n T)",
        _compressibility,
        _compressibility_theory,
        _dim_name({3: "Kolafa, Labik & Malijevsky", 2: "Henderson"}),
    ),
    "temperature": Observable(
        "J", "translational temperature at the end (k_B = 1)", lambda w, _: w.stats.temperature
    ),
    "temperature_ratio": Observable(
        "-",
        "temperature at the end over that at the start",
        _temperature_ratio,
        _haff,
        _dim_name({3: "Haff", 2: "Haff"}),
    ),
    "collision_rate": Observable(
        "1/s",
        "collisions per body per second",
        _collision_rate,
        _enskog_rate,
        _dim_name({3: "Enskog", 2: "Enskog"}),
    ),
    "mean_free_time": Observable(
        "s",
        "mean time between collisions of a body",
        lambda w, _: float(w.stats.mean_free_time),
        _enskog_time,
        _dim_name({3: "Enskog", 2: "Enskog"}),
    ),
    "energy_lost": Observable(
        "J", "kinetic energy dissipated by impacts", lambda w, _: float(w.stats.energy_lost)
    ),
    "energy_lost_fraction": Observable(
        "-", "energy lost over the kinetic energy at the start", _energy_lost_fraction
    ),
    "packing_fraction": Observable("-", "the spheres' volume over the box's", _packing_fraction),
    "rebound_height": Observable(
        "m",
        "body 0's first rebound off the floor",
        _rebound,
        _rebound_theory,
        _dim_name({3: "e² h0", 2: "e² h0"}),
    ),
    "stack_drift": Observable("m", "farthest any moving body went over the window", _stack_drift),
}

#: the top-level fields of summary.json (carom.io.results.summary)
SUMMARY_FIELDS = (
    "bodies",
    "dimension",
    "simulated_time_s",
    "collisions",
    "wall_collisions",
    "parting_floor_collisions",
    "events",
    "energy",
    "momentum",
    "angular_momentum",
    "temperature_J",
    "rotational_temperature_J",
    "performance",
    "pressure_Pa",
    "mean_free_time_s",
)


def check_observable(name: str) -> str | None:
    """What is wrong with an observable's name, or None."""
    if name in OBSERVABLES or name.split(".")[0] in SUMMARY_FIELDS:
        return None
    return (
        f"{name!r} is not an observable; use one of {', '.join(OBSERVABLES)}, or a field of "
        f"summary.json by its dotted path (e.g. energy.dissipated_J)"
    )


def has_theory(name: str) -> bool:
    """Whether ``name`` has a closed form (a ``<name>_theory`` column)."""
    obs = OBSERVABLES.get(name)
    return obs is not None and obs.theory is not None


# -- the task ---------------------------------------------------------------------------------


class _FirstBounce:
    """Finds body 0's first impact on the floor (the wall below it, against gravity)."""

    def __init__(self, floor: int) -> None:
        self.floor = floor
        self.found: tuple[float, float] | None = None

    def __call__(self, block: NDArray[Any]) -> None:
        from carom.engines.base import PARTNER_WALL

        if self.found is not None:
            return
        hit = block[(block["body"] == 0) & (block["kind"] == PARTNER_WALL)]
        hit = hit[hit["partner"] == self.floor]
        if len(hit):
            self.found = (float(hit["un_before"][0]), float(hit["un_after"][0]))


def _floor(world: World) -> tuple[int, float, float] | None:
    """The wall face that gravity points at (its index), its restitution, and body 0's drop
    height above it at t = 0 (from rest or not: the height its energy would reach) [m]."""
    g = world.gravity
    if world.boundary != "walls" or not np.any(g != 0.0) or np.count_nonzero(g) != 1:
        return None
    axis = int(np.flatnonzero(g)[0])
    if g[axis] > 0:
        return None  # (a floor above: not this observable's setting)
    face = 2 * axis
    x, v = world.positions[0], world.velocities[0]
    height = float(x[axis] - world.bodies.radius[0]) + float(v[axis]) ** 2 / (2 * -g[axis])
    return face, float(world.walls[face].restitution), height


def _lookup(data: dict[str, Any], path: str) -> float:
    node: Any = data
    for part in path.split("."):
        if isinstance(node, dict) and part in node:
            node = node[part]
        elif isinstance(node, list) and part.isdigit() and int(part) < len(node):
            node = node[int(part)]
        else:
            raise CaromError(f"summary.json has no field {path}")
    if isinstance(node, list):
        raise CaromError(f"{path} is a list in summary.json; name an element, e.g. {path}.0")
    if node is None:
        return math.nan
    if isinstance(node, bool) or not isinstance(node, int | float):
        raise CaromError(f"{path} in summary.json is not a number ({node!r})")
    return float(node)


def kernels_in_memory() -> int:
    """How many compiled kernel specialisations this process holds (loaded from the disk
    cache or compiled): what a task added tells whether it compiled or loaded any."""
    from numba.core.dispatcher import Dispatcher

    found: dict[int, Any] = {}
    for name, module in list(sys.modules.items()):
        if name.startswith("carom.") and module is not None:
            for value in list(vars(module).values()):
                if isinstance(value, Dispatcher):
                    found[id(value)] = value
    return sum(len(d.overloads) for d in found.values())


def run_point(task: dict[str, Any]) -> dict[str, Any]:
    """Run one point of a sweep and measure it: the Dask task.

    Parameters
    ----------
    task : dict
        ``index`` and ``seed`` (the row's key), ``scene`` (nested dicts), ``source`` (the
        scene file's path, for relative paths and messages), ``until`` and ``warmup`` [s],
        ``observables`` (names).

    Returns
    -------
    dict
        ``index``, ``seed``, ``status`` ("ok" or "failed"), ``message`` (empty when ok),
        ``values`` (name -> float), ``theory`` (name -> float, where a closed form applies),
        and for the timing log ``wall_s``, ``prepare_s`` (compiling or loading kernels) [s],
        ``kernels_loaded`` (kernel specialisations the task compiled or loaded: 0 in a
        worker whose kernels are ready), ``worker`` (host:pid).
    """
    began = time.perf_counter()
    kernels = kernels_in_memory()
    out: dict[str, Any] = {
        "index": task["index"],
        "seed": task["seed"],
        "status": "ok",
        "message": "",
        "values": {},
        "theory": {},
        "prepare_s": 0.0,
        "worker": f"{socket.gethostname()}:{os.getpid()}",
    }
    try:
        _measure(task, out)
    except Exception as exc:  # a failing point is recorded; the sweep goes on
        out["status"] = "failed"
        message = str(exc) if isinstance(exc, CaromError) else f"{type(exc).__name__}: {exc}"
        out["message"] = " ".join(message.split())  # one line in the table
        out["values"], out["theory"] = {}, {}
    out["wall_s"] = time.perf_counter() - began
    out["kernels_loaded"] = kernels_in_memory() - kernels
    return out


def _measure(task: dict[str, Any], out: dict[str, Any]) -> None:
    from carom.observables import kinetic_energy, momentum, potential_energy
    from carom.scene import Scene

    scene = Scene.from_dict(task["scene"], task["source"])
    world = scene.build()
    # (a stepped engine ends on until and warmup whatever they are, a shorter last step if
    # need be: a sweep records no frames, so nothing else has to fall on its steps)
    mark = time.perf_counter()
    world.prepare()
    out["prepare_s"] = time.perf_counter() - mark
    names: list[str] = task["observables"]
    floor = _floor(world) if "rebound_height" in names else None
    watcher = _FirstBounce(floor[0]) if floor is not None else None
    if task["warmup"] > 0:
        world.run(until=task["warmup"], on_collisions=watcher)
    world.stats.reset()
    frame = world.frame()
    b = world.bodies
    kinetic = kinetic_energy(b, frame.velocities, frame.angular_velocities, frame.orientations)
    start = {
        "kinetic_energy": kinetic,
        "potential_energy": potential_energy(b, frame.positions, world.gravity),
        "momentum": momentum(b, frame.velocities).tolist(),
    }
    t0, temp0 = world.time, world.stats.temperature
    began = time.perf_counter()
    world.run(until=task["until"], on_collisions=watcher)
    wall = time.perf_counter() - began
    window = Window(
        time=t0,
        temperature=temp0,
        kinetic=kinetic,
        positions=frame.positions.copy(),
        fluid=_fluid(world),
        first_bounce=None if watcher is None else watcher.found,
        initial_height=None if floor is None else floor[2],
        floor_restitution=None if floor is None else floor[1],
    )
    summary: dict[str, Any] | None = None
    for name in names:
        obs = OBSERVABLES.get(name)
        if obs is not None:
            out["values"][name] = float(obs.measure(world, window))
            if obs.theory is not None:
                value = obs.theory(world, window)
                if value is not None:
                    out["theory"][name] = float(value)
            continue
        if summary is None:
            from carom.io.results import summary as make_summary

            summary = make_summary(world, scene=str(task["source"]), start=start, wall_seconds=wall)
        out["values"][name] = _lookup(summary, name)
