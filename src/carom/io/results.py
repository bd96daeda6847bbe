"""What ``carom run`` writes besides the trajectory: the event table and the run's summary."""

from __future__ import annotations

import csv
import json
import math
from pathlib import Path
from typing import Any

from carom import __version__
from carom.studies.two_spheres import MODELS, ROUND_OFF, Record, conclusions
from carom.world import World

__all__ = [
    "case_document",
    "summary",
    "write_case_study",
    "write_cases_csv",
    "write_events_csv",
    "write_summary",
]


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


def case_document(records: list[Record]) -> dict[str, Any]:
    """The two-sphere study as JSON data: models, round-off bound, records, conclusions."""
    return {
        "carom_version": __version__,
        "models": MODELS,
        "round_off": ROUND_OFF,
        "records": [r.to_dict() for r in records],
        "conclusions": conclusions(records),
    }


def write_case_study(folder: Path, records: list[Record], *, figures: bool = True) -> list[str]:
    """Write ``cases.json``, ``cases.csv`` and (with ``figures``) ``case-N.png`` to ``folder``;
    return the file names."""
    document = case_document(records)
    (folder / "cases.json").write_text(json.dumps(document, indent=2) + "\n")
    write_cases_csv(folder / "cases.csv", document["records"])
    written = ["cases.json", "cases.csv"]
    if figures:
        from carom.viz.cases import plot_case

        for number in sorted({r.case for r in records}):
            plot_case([r for r in records if r.case == number], folder / f"case-{number}.png")
            written.append(f"case-{number}.png")
    return written


def write_cases_csv(path: Path, records: list[dict[str, Any]]) -> None:
    """One row per case, restitution and model (the exact answer is the model 'exact')."""
    columns = [
        "case",
        "title",
        "e",
        "model",
        "m1",
        "m2",
        "x1_x",
        "x1_y",
        "x2_x",
        "x2_y",
        "v1_x",
        "v1_y",
        "v2_x",
        "v2_y",
        "v1_after_x",
        "v1_after_y",
        "v2_after_x",
        "v2_after_y",
        "error",
        "momentum_error",
        "ke_before",
        "ke_after",
        "ke_lost",
        "energy_error",
        "separation_speed",
        "relative_speed_after",
        "angle_deg",
        "gap_after_1s",
    ]
    with path.open("w", newline="") as handle:
        writer = csv.writer(handle)
        writer.writerow(columns)
        for rec in records:
            outcomes = {"exact": rec["exact"], **rec["models"]}
            for model, out in outcomes.items():
                row = [
                    rec["case"],
                    rec["title"],
                    rec["e"],
                    model,
                    rec["m1"],
                    rec["m2"],
                    *rec["x1"],
                    *rec["x2"],
                    *rec["v1"],
                    *rec["v2"],
                    *out["v1_after"],
                    *out["v2_after"],
                ]
                row += [out[c] for c in columns[len(row) :]]
                writer.writerow(
                    ["" if v is None else repr(v) if isinstance(v, float) else v for v in row]
                )
