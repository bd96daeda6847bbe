"""A scene running live for ``carom play``: the world, what a page may do to it, and the
frames it draws.

:class:`Live` owns one :class:`carom.World` and touches it from one thread only (the server's
physics thread). It advances the world in real time (:meth:`Live.advance`: the rigid engines
in their own steps, 60 a second by default, as many as the real time asks, at most
:data:`MOST_STEPS` at once so that a slow machine falls behind instead of freezing; the
event-driven engine exactly by the real time), takes the page's commands
(:meth:`Live.obey`, after :func:`carom.play.wire.read_command` has checked them), and packs
frames (:meth:`Live.frame`) and shapes (:meth:`Live.shapes`) as binary messages.

Hands on the world, all through the game-loop API (docs/gameloop.md):

- **drag**: a :class:`carom.joints.Target` joint on the body under the pointer (Box2D's mouse
  joint), its target moved with the pointer, removed on release; in the event-driven engine
  (no joints) the sphere's velocity is set each step toward the pointer;
- **shoot**: a ball added at a point with a velocity (a body of the scene's size and twice
  its density); the oldest shot balls are removed past :data:`MOST_BALLS`;
- **settings**: gravity, restitution, friction and substeps, applied to the world at once.
"""

from __future__ import annotations

import dataclasses
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom.engines.stepped.driver import STAGES, SteppedEngine
from carom.joints import Target
from carom.laws.kinds import KIND_DYNAMIC
from carom.materials import Material
from carom.observables import kinetic_energy, potential_energy
from carom.play.drawn import shape_arrays
from carom.play.wire import Command, Refused, check_setting, pack
from carom.scene import builtin_scenes, find_scene, load_scene
from carom.shapes import Circle
from carom.shapes3d import Sphere
from carom.world import World

__all__ = ["MOST_BALLS", "MOST_STEPS", "Live"]

#: the most steps one call of :meth:`Live.advance` takes (behind that, real time is dropped)
MOST_STEPS = 4
#: the most shot balls in the world at once
MOST_BALLS = 64
#: the fastest ball a page may shoot, in units of the scene's size a second
TOP_SPEED = 100.0

FloatArray = NDArray[np.float64]


class Live:
    """One scene, live (module docstring).

    Parameters
    ----------
    scene : str or Path
        A built-in scene's name or a scene file.
    clock : callable, optional
        Real time [s] (``time.perf_counter``; tests pass their own).

    Raises
    ------
    CaromError
        The scene cannot be found, read or built (its message says why).
    """

    def __init__(self, scene: str | Path, *, clock: Callable[[], float] = time.perf_counter):
        self.clock = clock
        names = list(builtin_scenes())
        given = str(scene)
        if given not in names:
            names.insert(0, given)
        #: the scenes the picker offers: the built-in ones, and a file given first
        self.catalog = names
        self.paused = False
        self.slow = 1.0
        self.drawings: set[str] = set()
        self.version = 0  # of the shapes: a new number when bodies are added
        self.world: World = World(2, [1.0, 1.0])  # (replaced by load)
        self.load(given)

    # -- scenes -----------------------------------------------------------------------------

    def load(self, name: str) -> None:
        """Start scene ``name`` (a name of :attr:`catalog`) from its beginning."""
        if name not in self.catalog:
            raise Refused(
                f"scene: no scene {name!r}; pick one of the {len(self.catalog)} the picker lists"
            )
        scene = load_scene(find_scene(name))
        world = scene.build()
        world.prepare()
        self.world, self.scene_name = world, name
        self.title = str(scene.scene.get("title", name))
        self.description = str(scene.scene.get("description", ""))
        self.dim = world.dim
        self.dt = world.fixed_step
        self.rigid = isinstance(world.build(), SteppedEngine)
        self._debt = 0.0
        self._last = self.clock()
        self._held: tuple[int, int] | None = None  # (body, joint) dragged
        self._pull: FloatArray | None = None  # (event-driven) the pointer a sphere follows
        self._balls: list[int] = []
        self._e0 = sum(self._energies())
        self.step_seconds = 0.0  # a running mean of one step's wall time
        self.stage_seconds = np.zeros(len(STAGES))  # (the rigid engines': each stage's)
        self.behind = 0.0  # real time dropped [s]
        self._shape_cache: dict[str, NDArray[Any]] | None = None
        self.version += 1
        g = np.asarray(world.gravity, float)
        self.settings = {
            "gravity": float(np.linalg.norm(g)),
            "restitution": _typical(world, "restitution"),
            "friction": _typical(world, "friction"),
            "substeps": float(world.rigid_settings.substeps) if self.rigid else 0.0,
        }
        self._down = g / np.linalg.norm(g) if np.any(g) else _down(self.dim)
        lo, hi = _extent(world)
        #: how far a point a page sends may be from the origin [m]
        self.reach = 10.0 * float(np.max(np.abs(np.concatenate([lo, hi])))) + 10.0
        self.size = _body_size(world)
        self.top_speed = TOP_SPEED * self.size
        if self.rigid:  # the queries' kernels compiled (or loaded) now, not at the first click
            world.overlap_point(lo)
            world.overlap_box(lo, lo)
            world.ray_cast(lo, np.ones(self.dim))

    # -- time -------------------------------------------------------------------------------

    def advance(self) -> int:
        """Advance the world by the real time since the last call (times the slow-motion
        factor; nothing when paused); return the steps taken."""
        now = self.clock()
        real, self._last = now - self._last, now
        if self.paused:
            return 0
        self._follow()
        if self.dt is None:  # the event-driven engine: exactly the time asked
            span = min(real, 0.1) * self.slow
            self.behind += max(real - 0.1, 0.0)
            if span > 0.0:
                self._timed(span)
            return 1 if span > 0.0 else 0
        self._debt += real * self.slow
        steps = min(int(self._debt / self.dt), MOST_STEPS)
        self._debt -= steps * self.dt
        if self._debt > self.dt:  # behind: drop what cannot be caught up
            self.behind += (self._debt - self.dt) / self.slow
            self._debt = self.dt
        for _ in range(steps):
            self._timed(None)
        return steps

    def single_step(self) -> None:
        """One step (paused), of the engine's length (event-driven: 1/60 s)."""
        self._follow()
        self._timed(None if self.dt is not None else 1.0 / 60.0)

    def _timed(self, dt: float | None) -> None:
        start = time.perf_counter()
        self.world.step(dt)
        spent = time.perf_counter() - start
        fresh = self.step_seconds == 0.0
        self.step_seconds = spent if fresh else 0.9 * self.step_seconds + 0.1 * spent
        engine: object = self.world.engine
        if isinstance(engine, SteppedEngine):  # each stage's time, a running mean as well
            now = np.array(engine.stage_seconds)
            self.stage_seconds = now if fresh else 0.9 * self.stage_seconds + 0.1 * now

    # -- commands ---------------------------------------------------------------------------

    def obey(self, command: Command) -> dict[str, Any] | None:
        """Carry out a checked command; return a reply for the page, or None.

        Raises
        ------
        Refused
            It cannot be done (no body under the pointer, a ball that would start inside a
            body, ...); the world is as it was.
        """
        op, f = command.op, command.fields
        if op == "pause":
            self.paused = True
        elif op == "play":
            self.paused = False
            self._last = self.clock()
        elif op == "step":
            self.paused = True
            self.single_step()
        elif op == "slow":
            self.slow = float(f["factor"])
        elif op == "reset":
            self.load(self.scene_name)
        elif op == "scene":
            self.load(f["name"])
        elif op == "grab":
            return self._grab(f["point"], f.get("direction"))
        elif op == "drag":
            self._drag(f["target"])
        elif op == "release":
            self.release()
        elif op == "shoot":
            return {"op": "shot", "body": self._rebased(self._shoot, f["point"], f["velocity"])}
        elif op == "set":
            self._rebased(self._set, f["name"], check_setting(f["name"], f["value"]))
        elif op == "draw":
            if f["on"]:
                self.drawings.add(f["name"])
            else:
                self.drawings.discard(f["name"])
        return None

    def _rebased(self, change: Callable[..., Any], *args: Any) -> Any:
        """``change(*args)``, the energy it adds to the world by hand (a ball shot, gravity
        changed: its potential energy) added to the ledger's start, so that the ledger the
        panel shows still closes."""
        before = sum(self._energies())
        out = change(*args)
        self._e0 += sum(self._energies()) - before
        return out

    def _grab(self, point: FloatArray, direction: FloatArray | None) -> dict[str, Any]:
        self.release()
        try:
            body, at = self._pick(point, direction)
        except Refused as why:  # nothing to hold there: the page shoots instead
            return {"op": "grabbed", "body": -1, "why": str(why)}
        if self.rigid:
            joint = self.world.add_joint(Target(body, target=at, anchor=at))
            self._held = (body, joint)
        else:
            self._held = (body, -1)
            self._pull = at
        return {"op": "grabbed", "body": body, "point": [float(v) for v in at]}

    def _pick(self, point: FloatArray, direction: FloatArray | None) -> tuple[int, FloatArray]:
        world = self.world
        if direction is not None:  # 3D: the first body the ray meets
            if self.rigid:
                hit = world.ray_cast(point, direction)
                met, at = (-1, point) if hit is None else (int(hit.body), hit.point)
            else:  # (the event-driven engine's spheres: no ray casts of its own)
                met, at = _sphere_ray(world, point, direction)
            if met < 0:
                raise Refused("grab: the ray meets no body")
            return self._dynamic(met), np.asarray(at, float)
        if self.rigid:
            inside = [int(i) for i in world.overlap_point(point) if i >= 0]
        else:
            x = world.positions
            inside = list(np.flatnonzero(np.sum((x - point) ** 2, axis=1) <= world.radii**2))
        dynamic = [i for i in inside if self._is_dynamic(i)]
        if not dynamic:
            raise Refused("grab: no dynamic body under the pointer")
        return dynamic[-1], np.asarray(point, float)

    def _is_dynamic(self, i: int) -> bool:
        return bool(self.world.alive[i]) and self.world.body(i).kind == "dynamic"

    def _dynamic(self, i: int) -> int:
        if not self._is_dynamic(i):
            raise Refused(f"grab: body {i} is not dynamic (static and kinematic bodies stay)")
        return i

    def _drag(self, target: FloatArray) -> None:
        if self._held is None:
            raise Refused("drag: nothing is held (grab a body first)")
        if self._held[1] >= 0:
            self.world.set_joint_target(self._held[1], target)
        else:
            self._pull = np.asarray(target, float)

    def release(self) -> None:
        """Let go of the body dragged (nothing if none)."""
        if self._held is not None and self._held[1] >= 0:
            self.world.remove_joint(self._held[1])
        self._held, self._pull = None, None

    def _follow(self) -> None:
        """(Event-driven engine) the held sphere's velocity toward the pointer: it closes a
        tenth of the distance in a tenth of a second, at most the top speed."""
        if self._held is None or self._pull is None:
            return
        body = self._held[0]
        gap = self._pull - self.world.body(body).position
        v = gap / 0.1
        speed = float(np.linalg.norm(v))
        if speed > self.top_speed:
            v *= self.top_speed / speed
        self.world.body(body).velocity = v

    def _shoot(self, point: FloatArray, velocity: FloatArray) -> int:
        world = self.world
        r = 0.5 * self.size
        lo, hi = _extent(world)
        if world.boundary != "open" and (np.any(point - r < lo) or np.any(point + r > hi)):
            raise Refused("shoot: the ball would start outside the box; shoot from inside it")
        if self._touches(point, r):
            raise Refused("shoot: the ball would start inside a body; shoot from open space")
        density = 2.0 * _typical_density(world)
        if self.rigid:
            shape = Circle(r) if self.dim == 2 else Sphere(r)
            body = world.add_body(shape, point, velocity=velocity, density=density)
        else:
            mass = 2.0 * float(np.median(world.masses[np.isfinite(world.masses)]))
            body = int(world.add_spheres(point, velocity, radius=r, mass=mass)[0])
        self._balls.append(body)
        while len(self._balls) > MOST_BALLS:
            world.remove_body(self._balls.pop(0))
        self._shape_cache = None
        self.version += 1
        return body

    def _touches(self, point: FloatArray, r: float) -> bool:
        world = self.world
        if self.rigid:
            near = world.overlap_box(point - r, point + r)
            return bool(np.any(near >= 0))
        x = world.positions
        gap = np.sqrt(np.sum((x - point) ** 2, axis=1)) - world.radii - r
        return bool(np.any((gap < 0.0) & world.alive))

    def _set(self, name: str, value: float) -> None:
        world = self.world
        if name == "gravity":
            world.set_gravity(value * self._down)
        elif name == "substeps":
            if not self.rigid:
                raise Refused("set: the event-driven engine has no substeps")
            world.engine_settings["rigid"] = dataclasses.replace(
                world.rigid_settings, substeps=int(value)
            )
        else:
            if name == "friction" and not self.rigid:
                raise Refused("set: friction is the rigid engines' (the gas's spheres are smooth)")
            for i, material in enumerate(world.materials):
                world.set_material(i, _retuned(material, name, value))
        self.settings[name] = value

    # -- what the page draws ----------------------------------------------------------------

    def shapes(self) -> bytes:
        """The shapes message: every body's shape in its frame, and the scene's facts."""
        world = self.world
        if self._shape_cache is None:
            b = world.bodies
            still = b.kind != KIND_DYNAMIC
            self._shape_cache = shape_arrays(self.dim, b.pieces, b.radius, b.mass, still)
        lo, hi = _extent(world)
        header = {
            "type": "shapes",
            "version": self.version,
            "dim": self.dim,
            "scene": self.scene_name,
            "title": self.title,
            "description": self.description,
            "catalog": self.catalog,
            "engine": world.engine_name,
            "box": [[float(v) for v in lo], [float(v) for v in hi]],
            "boundary": world.boundary,
            "down": [float(v) for v in self._down],
            "size": self.size,
            "top_speed": self.top_speed,
            "settings": self.settings,
            "dt": self.dt,
        }
        return pack(header, self._shape_cache)

    def frame(self) -> bytes:
        """One frame: the bodies' places, turns, speeds and states, the clock and the stats."""
        world = self.world
        fr = world.frame()
        v = fr.velocities
        speed = np.sqrt(np.sum(v * v, axis=1))
        alive = np.ones(len(v), bool) if fr.alive is None else fr.alive
        engine = world.engine
        # (a rigid engine's bodies come first, then the walls and planes it made bodies of)
        awake = (
            engine.memory.awake[: len(v)]
            if isinstance(engine, SteppedEngine)
            else np.ones(len(v), bool)
        )
        state = alive.astype(np.uint8) | (awake.astype(np.uint8) << 1)
        kinetic, potential = self._energies(fr)
        counters = world.counters()
        header = {
            "type": "frame",
            "version": self.version,
            "time": fr.time,
            "steps": world.steps,
            "paused": self.paused,
            "slow": self.slow,
            "step_ms": 1e3 * self.step_seconds,
            "stages": (
                {name: 1e3 * float(t) for name, t in zip(STAGES, self.stage_seconds, strict=True)}
                if self.rigid
                else {}
            ),
            "behind": self.behind,
            "bodies": int(np.count_nonzero(alive)),
            "contacts": int(engine.n_contacts) if isinstance(engine, SteppedEngine) else 0,
            "awake": int(np.count_nonzero(alive & awake)),
            "islands": engine.awake_islands() if isinstance(engine, SteppedEngine) else 0,
            "energy": {
                "kinetic": kinetic,
                "potential": potential,
                "lost": counters.energy_lost,
                "given": counters.energy_given,
                "work": counters.work_done,
                "start": self._e0,
            },
            "held": -1 if self._held is None else self._held[0],
        }
        turn = fr.orientations
        arrays: dict[str, NDArray[Any]] = {
            "x": fr.positions.astype(np.float32),
            "turn": np.asarray(turn, np.float32),
            "speed": speed.astype(np.float32),
            "state": state,
        }
        arrays.update(self._debug(engine))
        return pack(header, arrays)

    def _energies(self, fr: Any = None) -> tuple[float, float]:
        world = self.world
        fr = world.frame() if fr is None else fr
        turn = fr.orientations if self.dim == 3 else None
        kinetic = kinetic_energy(world.bodies, fr.velocities, fr.angular_velocities, turn)
        potential = potential_energy(world.bodies, fr.positions, np.asarray(world.gravity))
        return float(kinetic), float(potential)

    def _debug(self, engine: Any) -> dict[str, NDArray[Any]]:
        if not self.drawings or not isinstance(engine, SteppedEngine):
            return {}
        out: dict[str, NDArray[Any]] = {}
        if self.drawings & {"contacts", "normals", "impulses"}:
            out["contacts"] = engine.contact_points().astype(np.float32)
        if "joints" in self.drawings and self.world.joint_rows[0].shape[0]:
            anchors = self.world.joint_anchors()
            live = np.all(np.isfinite(anchors.reshape(len(anchors), -1)), axis=1)
            out["joints"] = anchors[live].astype(np.float32)
        if "boxes" in self.drawings:
            boxes = engine.fat_boxes()
            out["boxes"] = boxes[np.all(np.isfinite(boxes), axis=1)].astype(np.float32)
        if "sleeping" in self.drawings:
            out["island"] = engine.memory.island[: self.world.n_bodies].astype(np.int32)
        return out


# -- helpers ------------------------------------------------------------------------------


def _down(dim: int) -> FloatArray:
    out = np.zeros(dim)
    out[1 if dim == 2 else 2] = -1.0
    return out


def _extent(world: World) -> tuple[FloatArray, FloatArray]:
    """The box's corners [m] (the world's box spans 0 to its edges)."""
    return np.zeros(world.dim), np.asarray(world.box, float)


def _body_size(world: World) -> float:
    """A typical dynamic body's size [m]: the median of their radii (reaches)."""
    b = world.bodies
    moving = np.isfinite(b.mass)
    radii = b.radius[moving] if np.any(moving) else b.radius
    return float(2.0 * np.median(radii)) if radii.size else 1.0


def _typical_density(world: World) -> float:
    b = world.bodies
    moving = np.isfinite(b.mass)
    if not np.any(moving):
        return 1.0
    volume = (
        (math.pi * b.radius[moving] ** 2)
        if world.dim == 2
        else (4.0 / 3.0 * math.pi * b.radius[moving] ** 3)
    )
    return float(np.median(b.mass[moving] / volume))


def _typical(world: World, name: str) -> float:
    values = [getattr(m, name) for m in world.materials]
    numbers = [float(v) for v in values if v is not None]
    return float(np.median(numbers)) if numbers else 0.0


def _retuned(material: Material, name: str, value: float) -> Material:
    """``material`` with its restitution or friction ``value`` (its law follows from the
    coefficients, as when it was made)."""
    restitution = value if name == "restitution" else material.restitution
    friction = value if name == "friction" else material.friction
    return Material(
        restitution,
        beta=material.beta,
        friction=friction,
        beta0=material.beta0,
        rolling=material.rolling,
    )


def _sphere_ray(world: World, origin: FloatArray, direction: FloatArray) -> tuple[int, FloatArray]:
    """The first sphere a ray meets (the event-driven engine's pick in 3D): its index (-1:
    none) and the point."""
    x, r = world.positions, world.radii
    rel = x - origin
    along = rel @ direction
    miss = np.sum(rel * rel, axis=1) - along**2
    hit = (miss <= r**2) & (along > 0.0) & world.alive
    if not np.any(hit):
        return -1, origin
    depth = along - np.sqrt(np.maximum(r**2 - miss, 0.0))
    depth[~hit] = np.inf
    i = int(np.argmin(depth))
    return i, origin + depth[i] * direction
