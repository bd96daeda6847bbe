"""A billiards run seen from above: each ball's path drawn on the table (``table.png``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np
from numpy.typing import NDArray

from carom.bodies import PIECE_ARRAYS, pieces_from_arrays
from carom.geometry.rotation import rotation_matrices
from carom.viz import require_matplotlib
from carom.world import World

__all__ = ["billiards_table", "write_table_plot"]

#: a ball is on the cloth when its centre stays within this many radii of one radius above
#: the cloth (z = its lowest point's height over the run)
ON_CLOTH = 0.05
#: ball colours, in body order: white (the cue ball), yellow, red (a carom set), then the
#: rest of a pool set's and their paler stripes
COLOURS = (
    "#f4f4f0", "#f2c200", "#c8102e", "#1f4fa8", "#6b2c91", "#f26b21", "#0b7a3b", "#7a1e1e",
    "#111111", "#f7dc6f", "#e8707f", "#7f9fd6", "#a77bc0", "#f6a06b", "#5fb07e", "#b36a6a",
)  # fmt: skip


def billiards_table(world: World) -> tuple[float, float, float, float] | None:
    """The playing area ``(x0, y0, x1, y1)`` [m] of a 3D world whose moving bodies are all
    balls on one level (gravity along -z): the cushions' noses when there are static rails
    (their bodies' extent towards the balls), else the box; None for any other world."""
    if world.dim != 3 or world.engine_name != "rigid":
        return None
    gravity = np.asarray(world.gravity, float)
    if not (gravity[2] < 0.0 and gravity[0] == 0.0 and gravity[1] == 0.0):
        return None
    moving = world.bodies.mobile
    if not moving.any():
        return None
    z = world.positions[moving, 2]
    r = world.radii[moving]
    if not np.all(np.abs(z - r) <= ON_CLOTH * r):
        return None
    box = np.asarray(world.box, float)
    return 0.0, 0.0, float(box[0]), float(box[1])


def _outline(points: NDArray[np.float64]) -> NDArray[np.float64]:
    """The convex outline of ``points`` (k, 2), anticlockwise (Andrew's monotone chain)."""
    ordered = sorted({(float(x), float(y)) for x, y in points})
    if len(ordered) < 3:
        return np.array(ordered)

    def half(seq: list[tuple[float, float]]) -> list[tuple[float, float]]:
        chain: list[tuple[float, float]] = []
        for p in seq:
            while len(chain) >= 2:
                (ax, ay), (bx, by) = chain[-2], chain[-1]
                if (bx - ax) * (p[1] - ay) - (by - ay) * (p[0] - ax) > 0.0:
                    break
                chain.pop()
            chain.append(p)
        return chain

    lower, upper = half(ordered), half(ordered[::-1])
    return np.array(lower[:-1] + upper[:-1])


def write_table_plot(folder: Path, world: World, trajectory: Path) -> list[str]:
    """Write ``table.png``: the table from above (the cloth, and the static bodies on it: a
    table's rails), each ball's path over the run from the trajectory's frames, where it
    started (a ring) and where it ended (the ball, to scale); return the file names written
    (none unless :func:`billiards_table` finds a table)."""
    area = billiards_table(world)
    if area is None or not trajectory.exists():
        return []
    require_matplotlib()
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle, Polygon, Rectangle

    from carom.io.h5md import read_trajectory

    with read_trajectory(trajectory) as f:
        paths: NDArray[np.float64] = np.asarray(f["particles/all/position/value"][:], float)
        radius = np.asarray(f["particles/all/radius"][:], float)
        turns = np.asarray(f["particles/all/orientation/value"][0], float)
        stored = f["particles/all"].get("pieces")
        pieces = (
            [()] * radius.shape[0]
            if stored is None
            else pieces_from_arrays(
                {k: stored[k][:] for k in PIECE_ARRAYS if k in stored}, radius.shape[0]
            )
        )
    moving = np.flatnonzero(world.bodies.mobile)
    x0, y0, x1, y1 = area
    width = 9.0
    fig, ax = plt.subplots(figsize=(width, width * (y1 - y0) / (x1 - x0) + 0.6))
    ax.add_patch(Rectangle((x0, y0), x1 - x0, y1 - y0, facecolor="#1d6b3a", edgecolor="#5a3a1a",
                           linewidth=6))  # fmt: skip
    # the static bodies (a table's rails) from above: each piece's outline
    turned = rotation_matrices(turns)
    for i in np.flatnonzero(~world.bodies.mobile):
        for piece in pieces[i]:
            corners = np.asarray(piece.vertices, float) @ turned[i].T + paths[0, i]
            if corners.shape[0] < 3:
                continue
            outline = _outline(corners[:, :2])
            ax.add_patch(Polygon(outline, facecolor="#5a3a1a", edgecolor="#3a2510", lw=0.8))
    for k, i in enumerate(moving):
        colour = COLOURS[k % len(COLOURS)]
        xy = paths[:, i, :2]
        ax.plot(xy[:, 0], xy[:, 1], color=colour, linewidth=1.4, alpha=0.9)
        ax.add_patch(Circle(tuple(xy[0]), radius[i], fill=False, edgecolor=colour, lw=1.0))
        ax.add_patch(Circle(tuple(xy[-1]), radius[i], facecolor=colour, edgecolor="black",
                            lw=0.6))  # fmt: skip
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.set_xlabel("x [m]")
    ax.set_ylabel("y [m]")
    ax.set_title(
        f"{len(moving)} balls from above, t = 0 to {world.time:g} s: paths (lines), starts "
        "(rings), ends (balls)",
        fontsize=9,
    )
    fig.tight_layout()
    fig.savefig(folder / "table.png", dpi=110)
    plt.close(fig)
    return ["table.png"]
