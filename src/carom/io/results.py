"""What ``carom run`` writes besides the trajectory: the event table and the run's summary."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

from numpy.typing import NDArray

from carom.engines.base import PARTNER_BODY, PARTNER_PLANE, PARTNER_WALL
from carom.observables import (
    angular_momentum,
    kinetic_energy,
    momentum,
    potential_energy,
    rotational_energy,
)
from carom.world import World

#: the ``partner_kind`` column of events.csv, by kind code
PARTNER_KINDS = {PARTNER_BODY: "body", PARTNER_WALL: "wall", PARTNER_PLANE: "plane"}

__all__ = [
    "PARTNER_KINDS",
    "EventsWriter",
    "summary",
    "write_summary",
]


class EventsWriter:
    """Write collisions to a CSV file as they come (memory flat however long the run).

    Columns: ``time_s``; ``body``; ``partner_kind`` (``body``, ``wall`` or ``plane``) and
    ``partner``, a number: the other body, the wall face (``2 k`` the lower and ``2 k + 1``
    the upper wall of axis ``k``: 0 is x-, 1 is x+, 2 is y-, ...), or the plane; the impulse
    on ``body`` per axis ``impulse_x_Ns`` ...; the normal relative speed before and after,
    ``un_before_m_s`` and ``un_after_m_s`` (negative: approaching); the contact point
    ``point_x_m`` ... (periodic: in the box). Every number is written
    in full (``repr``), so the file reads back to the same bits.

    Parameters
    ----------
    path : Path
        The file; created (``keep=None``), or reopened with its first ``keep`` bytes kept and
        anything after them dropped (resuming a run from its checkpoint).
    dim : int
        The world's dimension.
    """

    def __init__(self, path: Path, dim: int, keep: int | None = None) -> None:
        self.dim = dim
        if keep is None:
            self.file = path.open("w", newline="")
            axes = "xyz"[:dim]
            header = ["time_s", "body", "partner_kind", "partner"]
            header += [f"impulse_{a}_Ns" for a in axes] + ["un_before_m_s", "un_after_m_s"]
            header += [f"point_{a}_m" for a in axes]
            csv.writer(self.file).writerow(header)
        else:
            self.file = path.open("r+", newline="")
            self.file.truncate(keep)
            self.file.seek(keep)
        self.writer = csv.writer(self.file)

    def write(self, block: NDArray[Any]) -> None:
        """Append a block of collisions (:data:`carom.engines.base.COLLISION_DTYPE`)."""
        d = self.dim
        for e in block:
            self.writer.writerow(
                [
                    repr(float(e["time"])),
                    int(e["body"]),
                    PARTNER_KINDS[int(e["kind"])],
                    int(e["partner"]),
                    *(repr(float(j)) for j in e["impulse"][:d]),
                    repr(float(e["un_before"])),
                    repr(float(e["un_after"])),
                    *(repr(float(p)) for p in e["point"][:d]),
                ]
            )

    def flush(self) -> int:
        """Push what was written to the file; return its size in bytes (for a checkpoint)."""
        self.file.flush()
        return self.file.tell()

    def close(self) -> None:
        self.file.close()


def summary(
    world: World,
    *,
    scene: str,
    start: dict[str, Any],
    wall_seconds: float,
) -> dict[str, Any]:
    """The run's observables, conservation errors, counts and speed, as plain JSON data.

    ``start`` holds ``kinetic_energy`` [J], ``potential_energy`` [J] and ``momentum`` [kg m/s]
    taken before the run, and may hold ``rotational_energy`` [J] and ``angular_momentum``
    [kg m^2/s]. The energy balance is ``E0 + work - E - dissipated + given`` over ``E0``
    (kinetic plus gravitational potential energy; ``given`` by the parting-speed floor, or by
    the rigid engine's solver; ``work`` by kinematic bodies): round-off when the physics is
    right.
    """
    stats = world.stats
    now = world.frame()
    b, x, v, w = world.bodies, now.positions, now.velocities, now.angular_velocities
    q = now.orientations
    ke = kinetic_energy(b, v, w, q)
    pe = potential_energy(b, x, world.gravity)
    e0 = start["kinetic_energy"] + start["potential_energy"]
    closed = e0 + stats.work_done - (ke + pe) - stats.energy_lost + stats.energy_given
    balance = closed / e0 if e0 else 0.0
    events = stats.events_processed
    entry = world.engine_entry
    giver = f"given_by_{entry.gives_energy.replace(' ', '_')}_J"
    data: dict[str, Any] = {
        "scene": scene,
        "bodies": world.n_bodies,
        "dimension": world.dim,
        "boundary": world.boundary,
        "simulated_time_s": world.time,
        "collisions": stats.collisions,
        "wall_collisions": stats.wall_collisions,
        "parting_floor_collisions": stats.floor_collisions,
        "events": events,
        "energy": {
            "kinetic_start_J": start["kinetic_energy"],
            "kinetic_end_J": ke,
            "potential_start_J": start["potential_energy"],
            "potential_end_J": pe,
            "rotational_start_J": start.get("rotational_energy"),
            "rotational_end_J": rotational_energy(b, w, q),
            "dissipated_J": stats.energy_lost,
            giver: stats.energy_given,
            **({"work_by_kinematic_bodies_J": stats.work_done} if entry.kinematic else {}),
            "balance_error_relative": balance,
        },
        "momentum": {
            "start_kg_m_s": list(start["momentum"]),
            "end_kg_m_s": momentum(b, v).tolist(),
        },
        "angular_momentum": {
            "about": "origin",
            "start_kg_m2_s": list(start.get("angular_momentum", [])) or None,
            "end_kg_m2_s": angular_momentum(b, x, v, w, q).tolist(),
        },
        "temperature_J": stats.temperature,
        "rotational_temperature_J": stats.rotational_temperature,
        "performance": {
            "wall_time_s": wall_seconds,
            "collisions_per_s": stats.collisions / wall_seconds if wall_seconds > 0 else None,
            "events_per_s": events / wall_seconds if wall_seconds > 0 else None,
        },
    }
    if world.boundary == "periodic":
        data["pressure_Pa"] = stats.pressure
        data["mean_free_time_s"] = stats.mean_free_time
    return data


def write_summary(data: dict[str, Any], path: Path) -> None:
    """``data`` as indented JSON (non-finite numbers as null)."""

    def clean(value: Any) -> Any:
        if isinstance(value, float) and not math.isfinite(value):
            return None
        if isinstance(value, dict):
            return {k: clean(v) for k, v in value.items()}
        if isinstance(value, list):
            return [clean(v) for v in value]
        return value

    path.write_text(json.dumps(clean(data), indent=2) + "\n")
