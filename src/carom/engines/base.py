"""What every engine offers a :class:`carom.World`: the Engine protocol, the collision record
and the running counters.

A World owns the bodies, materials and boundaries (engine-neutral); an engine is built from
them, advances to a time, samples the bodies' state, hands over the collisions it logged, and
saves and restores its own arrays for checkpoints. Bodies are numbered as the caller added
them in everything an engine returns.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Any, NamedTuple, Protocol

import numpy as np
from numpy.typing import NDArray

__all__ = [
    "COLLISION_DTYPE",
    "PARTNER_BODY",
    "PARTNER_PLANE",
    "PARTNER_WALL",
    "STOP_CHECK_EVENTS",
    "Counters",
    "Engine",
    "FrameArrays",
    "Partners",
    "Sink",
    "WorldView",
    "describe_partner",
]

if TYPE_CHECKING:
    from carom.bodies import Bodies
    from carom.materials import CombineRule, Material

FloatArray = NDArray[np.float64]

#: what a collision's partner is (a collision record's ``kind``), not to be confused with a
#: body's kind (:data:`carom.laws.kinds.BODY_KINDS`: dynamic, static, kinematic)
PARTNER_BODY = 0  # partner is a body
PARTNER_WALL = 1  # partner is a wall face: 2k lower, 2k + 1 upper wall of axis k
PARTNER_PLANE = 2  # partner is a static plane, by index


def describe_partner(kind: int, partner: int) -> str:
    """A readable name for a collision's partner: ``body 3``, ``wall x-``, ``plane 0``."""
    if kind == PARTNER_BODY:
        return f"body {partner}"
    if kind == PARTNER_WALL:
        return f"wall {'xyz'[partner // 2]}{'-' if partner % 2 == 0 else '+'}"
    return f"plane {partner}"


class Partners(NamedTuple):
    """What each of an engine's bodies is to a collision record, when the engine holds more
    bodies than the caller's (walls and planes as static bodies): ``kind`` (N_engine,) int8
    (``PARTNER_BODY``, ``PARTNER_WALL``, ``PARTNER_PLANE``) and ``number`` (N_engine,) int64 (the
    body, wall face or plane)."""

    kind: NDArray[np.int8]
    number: NDArray[np.int64]


#: One logged collision: ``time`` [s]; ``body``; the ``kind`` of partner (``PARTNER_BODY``,
#: ``PARTNER_WALL``, ``PARTNER_PLANE``) and its index ``partner`` (a body, a wall face, a plane);
#: the ``impulse`` on ``body`` [N s] (3 components, z = 0 in 2D); the normal relative speeds
#: ``un_before`` and ``un_after`` [m/s] (negative: approaching); the contact ``point`` [m] (3
#: components; with the impulse it gives each body's angular impulse, ``(point - x) x J``).
COLLISION_DTYPE = np.dtype(
    [
        ("time", np.float64),
        ("body", np.int64),
        ("kind", np.int8),
        ("partner", np.int64),
        ("impulse", np.float64, (3,)),
        ("un_before", np.float64),
        ("un_after", np.float64),
        ("point", np.float64, (3,)),
    ]
)

#: Receives each block of collisions as the engine hands them over (a structured array of
#: ``COLLISION_DTYPE``, time-ordered); it may keep, write or drop them.
Sink = Callable[[NDArray[Any]], None]
#: an engine hands control back to Python at least this often (events, or steps), so that
#: Ctrl-C and a run's stop request are seen: 65536 events take 0.05 to 0.5 s at the
#: 1e5 to 1e6 events/s of the event-driven engine, and the return costs microseconds
STOP_CHECK_EVENTS = 1 << 16


class Counters(NamedTuple):
    """An engine's running totals since it was built (the World's :class:`carom.Stats` takes
    differences of them).

    Attributes
    ----------
    events : int
        Events processed: collisions, and the engine's own bookkeeping events.
    collisions, wall_collisions : int
        Impacts between two bodies; of a body with a wall or plane.
    tc_collisions : int
        Impacts the TC model made elastic (event-driven engine).
    rests : int
        Bodies brought to rest on a wall or plane.
    virial : float
        Sum over impacts of ``J . r`` [J s] (pairs: ``r = x1 - x2``; walls: ``r = x``).
    energy_lost : float
        Kinetic energy dissipated by the impact laws [J] (never decreases).
    floor_collisions : int
        Impacts whose parting speed the engine raised to a floor so that the bodies part
        (event-driven engine; ``docs/engine.md``, "Minimum parting speed").
    energy_given : float
        Kinetic energy those raised speeds gave [J] (the rigid engine: what its solver gave).
    work_done : float
        Work done on the bodies by kinematic bodies (a turning drum, a paddle) [J]; the
        energy ledger closes as ``E0 + work_done = E + energy_lost - energy_given``.
    """

    events: int
    collisions: int
    wall_collisions: int
    tc_collisions: int
    rests: int
    virial: float
    energy_lost: float
    floor_collisions: int
    energy_given: float
    work_done: float = 0.0

    def plus(self, other: Counters) -> Counters:
        """These totals and ``other``'s, added."""
        return Counters(*(a + b for a, b in zip(self, other, strict=True)))  # type: ignore[arg-type]

    def minus(self, other: Counters) -> Counters:
        """These totals less ``other``'s."""
        return Counters(*(a - b for a, b in zip(self, other, strict=True)))  # type: ignore[arg-type]


class FrameArrays(NamedTuple):
    """Room for ``F`` frames of ``N`` bodies in ``d`` dimensions, written by
    :meth:`Engine.advance_frames`; frame ``f`` is row ``f`` of each array.

    Attributes
    ----------
    times : (F,) float64
        The engine's clock at each frame [s].
    positions, velocities : (F, N, d) float64
        [m], [m/s].
    orientations : (F, N, 1) float64 in 2D, (F, N, 4) float64 in 3D
        The angle about z [rad]; the unit quaternion ``w, x, y, z``.
    angular_velocities : (F, N, 3) float64
        [rad/s], world frame (2D: about z, column 2).
    """

    times: FloatArray
    positions: FloatArray
    velocities: FloatArray
    orientations: FloatArray
    angular_velocities: FloatArray

    @staticmethod
    def frame_bytes(n: int, dim: int) -> int:
        """The memory [bytes] one frame of ``n`` bodies in ``dim`` dimensions takes."""
        return 8 * (1 + n * (2 * dim + (1 if dim == 2 else 4) + 3))

    @classmethod
    def empty(cls, frames: int, n: int, dim: int) -> FrameArrays:
        """Uninitialised room for ``frames`` frames of ``n`` bodies in ``dim`` dimensions."""
        return cls(
            np.empty(frames),
            np.empty((frames, n, dim)),
            np.empty((frames, n, dim)),
            np.empty((frames, n, 1 if dim == 2 else 4)),
            np.empty((frames, n, 3)),
        )


class WorldView(Protocol):
    """What an engine reads of a :class:`carom.World` to build or restore itself: the
    engine-neutral body table, what surrounds the bodies, the materials, the clock, and the
    engine's own settings. Engines import nothing of the World itself."""

    dim: int
    #: box sides (d,) [m]
    box: FloatArray
    #: "walls", "periodic" or "open"
    boundary: str
    #: (d,) [m/s^2]
    gravity: FloatArray
    #: the walls' materials, lower and upper wall of each axis in turn (2 d)
    walls: tuple[Material, ...]
    #: static planes: point (d,) [m], unit normal (d,), material
    planes: list[tuple[FloatArray, FloatArray, Material]]
    materials: list[Material]
    combine: CombineRule
    bodies: Bodies

    @property
    def pair_overrides(self) -> dict[tuple[int, int], float]: ...

    @property
    def time(self) -> float: ...

    def settings_of(self, engine: str) -> Any:
        """The settings the world keeps for the engine called ``engine`` (its entry's
        dataclass)."""
        ...


class Engine(Protocol):
    """An engine that advances bodies in time (built by its plug, :mod:`.registry`)."""

    name: str
    #: the engine's clock [s]
    time: float

    def warm_up(self) -> None:
        """Compile or load from the cache every kernel a run may call, so that a timed run
        times the simulation alone; changes nothing."""
        ...

    def advance(
        self,
        until: float,
        max_events: int,
        sink: Sink | None,
        stop: Callable[[], bool] | None = None,
    ) -> bool:
        """Advance to ``until`` [s] (or by ``max_events`` events, for an event-driven engine);
        logged collisions go to ``sink`` (None: none are logged). ``stop`` is asked at least
        every :data:`STOP_CHECK_EVENTS` events (or steps); when it says True the engine stops
        where it is, consistent, and returns False. Returns True when it got there."""
        ...

    def advance_frames(
        self,
        times: FloatArray,
        sink: Sink | None,
        stop: Callable[[], bool] | None,
        out: FrameArrays,
    ) -> int:
        """Advance to each of ``times`` [s] in turn (non-decreasing, from the engine's clock
        on) and write the state there into frame ``f`` of ``out``; ``sink`` and ``stop`` as
        for :meth:`advance`. Returns the number of frames written: all, unless ``stop`` said
        True (the engine then stands where it stopped)."""
        ...

    def sample(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        """Positions (N, d) [m], velocities (N, d) [m/s], orientations ((N,) angles [rad] in
        2D, (N, 4) unit quaternions ``w, x, y, z`` in 3D) and angular velocities (N, 3)
        [rad/s], now."""
        ...

    def sample_motion(self) -> tuple[FloatArray, FloatArray]:
        """:meth:`sample`'s positions (N, d) [m] and velocities (N, d) [m/s] alone."""
        ...

    def counters(self) -> Counters:
        """The running totals."""
        ...

    def resting(self) -> NDArray[np.int64]:
        """The wall face or plane each body rests on (-1: none), (N,)."""
        ...

    def arrays(self) -> dict[str, NDArray[Any]]:
        """Everything needed to continue bit for bit, as named arrays (for checkpoints)."""
        ...
