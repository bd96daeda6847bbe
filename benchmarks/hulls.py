"""Building convex hulls of many points: qhull, then the faces and edges contact needs
(issue 45, item 2: a hull of 10^5 points built in under a second).

For each size, points on a unit sphere (every point a corner: the worst case, about 2 k
triangles for k points) become a :class:`carom.shapes3d.Hull` (qhull through SciPy, the
triangles turned outward, the surface checked closed), then its faces and edges
(:func:`carom.geometry.polyhedron.polyhedron_features`, what the 3D engine builds for each
hull piece). Each size is timed ``--rounds`` times; the median and the spread are printed.

Run:  python benchmarks/hulls.py
      python benchmarks/hulls.py --sizes 1000 100000 --rounds 3
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

from carom.geometry.polyhedron import polyhedron_features
from carom.shapes3d import Hull


def sphere_points(count: int, seed: int = 1) -> np.ndarray:
    """``count`` points uniform on the unit sphere (count, 3)."""
    p = np.random.default_rng(seed).normal(size=(count, 3))
    return p / np.linalg.norm(p, axis=1)[:, None]


def time_one(points: np.ndarray) -> tuple[float, float, int]:
    """Seconds for the hull, seconds for its features, and its face count."""
    began = time.perf_counter()
    hull = Hull(points)
    built = time.perf_counter()
    features = polyhedron_features(hull.vertices, hull.triangles)
    done = time.perf_counter()
    return built - began, done - built, int(features.normals.shape[0])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[1000, 10_000, 100_000])
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    time_one(sphere_points(100))  # imports and SciPy's first call, not timed
    print("| points | faces | hull [s] | features [s] | total [s] (min-max) |")
    print("|---|---|---|---|---|")
    for size in args.sizes:
        points = sphere_points(size)
        runs = [time_one(points) for _ in range(args.rounds)]
        hull = statistics.median(r[0] for r in runs)
        features = statistics.median(r[1] for r in runs)
        totals = [r[0] + r[1] for r in runs]
        print(
            f"| {size} | {runs[0][2]} | {hull:.3f} | {features:.3f} | "
            f"{statistics.median(totals):.3f} ({min(totals):.3f}-{max(totals):.3f}) |"
        )


if __name__ == "__main__":
    main()
