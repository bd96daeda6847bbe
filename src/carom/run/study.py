"""What ``carom cases`` writes: the two-sphere study as JSON, CSV and one figure per case."""

from __future__ import annotations

import csv
import json
from pathlib import Path
from typing import Any

from carom import __version__
from carom.studies.two_spheres import MODELS, ROUND_OFF, Record, conclusions

__all__ = ["case_document", "write_case_study", "write_cases_csv"]


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
