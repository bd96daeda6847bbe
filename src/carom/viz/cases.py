"""One figure per case of the seven-case study: the spheres and their velocity vectors."""

from __future__ import annotations

import math
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from carom.studies.two_spheres import MODELS, ROUND_OFF, Record
from carom.viz import require_matplotlib

if TYPE_CHECKING:
    from matplotlib.axes import Axes

__all__ = ["plot_case"]

COLOURS = ("#1f77b4", "#d62728")  # sphere 1, sphere 2


def _point(p: np.ndarray) -> tuple[float, float]:
    return (float(p[0]), float(p[1]))


def _panel(
    ax: Axes,
    record: Record,
    v1: Sequence[float],
    v2: Sequence[float],
    title: str,
    note: str,
    scale: float,
) -> None:
    """Both spheres, the line of centres, and each velocity as an arrow ``v * scale`` long."""
    from matplotlib.patches import Circle, FancyArrowPatch

    x1, x2 = np.array(record.x1), np.array(record.x2)
    a = record.radius
    ax.plot(*np.stack([x1, x2]).T, ls=":", color="0.6", lw=1, zorder=1)
    for x, v, colour, label in ((x1, v1, COLOURS[0], "1"), (x2, v2, COLOURS[1], "2")):
        ax.add_patch(Circle(_point(x), a, facecolor=colour, alpha=0.18, edgecolor=colour, lw=1.5))
        ax.text(
            x[0], x[1], label, ha="center", va="center", fontsize=9, color=colour, weight="bold"
        )
        tip = x + np.asarray(v) * scale
        if np.hypot(*(tip - x)) > 1e-9:
            ax.add_patch(
                FancyArrowPatch(
                    _point(x),
                    _point(tip),
                    arrowstyle="-|>",
                    mutation_scale=12,
                    color=colour,
                    lw=2,
                    zorder=3,
                )
            )
        else:
            ax.plot(*x, marker="o", ms=3, color=colour)
    ax.set_title(title, fontsize=9)
    ax.text(0.5, -0.02, note, transform=ax.transAxes, ha="center", va="top", fontsize=8)
    ax.set_aspect("equal")
    ax.set_xticks([])
    ax.set_yticks([])
    for side in ax.spines.values():
        side.set_visible(False)


def plot_case(records: list[Record], path: Path) -> Path:
    """Draw one case at each of its restitutions: before, and after for each model.

    Parameters
    ----------
    records : list of Record
        The records of one case (one per restitution), from
        :func:`carom.studies.two_spheres.run_study`.
    path : Path
        Where to write the PNG.

    Returns
    -------
    Path
        ``path``.
    """
    require_matplotlib()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    first = records[0]
    speeds = [math.hypot(*v) for r in records for v in (r.v1, r.v2)]
    speeds += [math.hypot(*m.v1_after) for r in records for m in r.models.values()]
    speeds += [math.hypot(*m.v2_after) for r in records for m in r.models.values()]
    # the longest arrow spans three radii
    scale = 3 * first.radius / max(max(speeds), 1e-12)
    columns = 1 + len(MODELS)
    fig, axes = plt.subplots(
        len(records), columns, figsize=(3.0 * columns, 2.7 * len(records)), squeeze=False
    )
    extent = 4.2 * first.radius  # centre offset (1 radius) + longest arrow (3 radii)
    centre = (np.array(first.x1) + np.array(first.x2)) / 2
    for row, record in zip(axes, records, strict=True):
        _panel(
            row[0],
            record,
            record.v1,
            record.v2,
            f"before (e = {record.e:g})",
            f"|v1 - v2| = {np.hypot(*np.subtract(record.v1, record.v2)):.3g} m/s",
            scale,
        )
        for ax, (name, label) in zip(row[1:], MODELS.items(), strict=True):
            m = record.models[name]
            verdict = "exact" if m.error <= ROUND_OFF else f"error {100 * m.error:.0f}%"
            angle = "" if math.isnan(m.angle_deg) else f", angle {m.angle_deg:.1f}°"
            _panel(
                ax,
                record,
                m.v1_after,
                m.v2_after,
                f"after: {label}",
                f"{verdict}; KE lost {m.ke_lost_shown:.3g} J{angle}",
                scale,
            )
        for ax in row:
            ax.set_xlim(centre[0] - extent, centre[0] + extent)
            ax.set_ylim(centre[1] - extent, centre[1] + extent)
    fig.suptitle(
        f"Case {first.case}: {first.title}  (m1 = {first.m1:g} kg, m2 = {first.m2:g} kg; "
        f"arrows: velocity)",
        fontsize=11,
    )
    fig.tight_layout(rect=(0, 0, 1, 0.96))
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path
