"""What ``carom run`` writes besides the trajectory: the event table and the run's summary."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

from carom.world import World

__all__ = ["summary", "write_events_csv", "write_summary"]


def write_events_csv(world: World, path: Path) -> int:
    """Write every logged collision of ``world`` to ``path``; return how many.

    Columns: ``time_s``, ``body``, ``partner`` (``body N``, ``wall x-`` ... or ``plane K``),
    the impulse on ``body`` per axis ``impulse_x_Ns`` ..., and the normal relative speed
    before and after, ``un_before_m_s`` and ``un_after_m_s`` (negative: approaching).
    """
    events = world.events
    axes = "xyz"[: world.dim]
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        impulse = [f"impulse_{a}_Ns" for a in axes]
        writer.writerow(["time_s", "body", "partner", *impulse, "un_before_m_s", "un_after_m_s"])
        for e in events:
            writer.writerow(
                [
                    repr(float(e["time"])),
                    int(e["a"]),
                    world.describe_partner(int(e["b"])),
                    *(repr(float(j)) for j in e["impulse"][: world.dim]),
                    repr(float(e["un_before"])),
                    repr(float(e["un_after"])),
                ]
            )
    return len(events)


def summary(
    world: World,
    *,
    scene: str,
    start: dict[str, Any],
    wall_seconds: float,
) -> dict[str, Any]:
    """The run's observables, conservation errors, counts and speed, as plain JSON data.

    ``start`` holds ``kinetic_energy`` [J], ``potential_energy`` [J] and ``momentum`` [kg m/s]
    taken before the run. The energy balance is ``E0 - E - dissipated`` over ``E0`` (kinetic
    plus gravitational potential energy): round-off when the physics is right.
    """
    stats = world.stats
    now = world.frame()
    ke, pe = (
        world.kinetic_energy_of(now.velocities, now.spins),
        world.potential_energy_of(now.positions),
    )
    e0 = start["kinetic_energy"] + start["potential_energy"]
    balance = (e0 - (ke + pe) - stats.energy_lost) / e0 if e0 else 0.0
    events = stats.events
    data: dict[str, Any] = {
        "scene": scene,
        "bodies": world.n_bodies,
        "dimension": world.dim,
        "boundary": world.boundary,
        "simulated_time_s": world.time,
        "collisions": stats.collisions,
        "wall_collisions": stats.wall_collisions,
        "events": events,
        "energy": {
            "kinetic_start_J": start["kinetic_energy"],
            "kinetic_end_J": ke,
            "potential_start_J": start["potential_energy"],
            "potential_end_J": pe,
            "dissipated_J": stats.energy_lost,
            "balance_error_relative": balance,
        },
        "momentum": {
            "start_kg_m_s": list(start["momentum"]),
            "end_kg_m_s": world.momentum_of(now.velocities).tolist(),
        },
        "temperature_J": stats.temperature,
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
