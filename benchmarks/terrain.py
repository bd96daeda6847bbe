"""A ball on a static terrain of many triangles: the engine's build and its steps against the
terrain's size (issue 45, item 2: a ball on 2e6 triangles steps in about the time it takes on
2e3; static pieces never paired with each other, the terrain's triangles found through the
tree of :mod:`carom.geometry.bvh`).

The terrain is a square heightfield of gentle waves, 2 k^2 triangles of the same size (0.63 m
on a side: 2,000 of them cover 20 m x 20 m, 2e6 of them 632 m x 632 m), a static
:class:`carom.meshes.Mesh`; a 0.2 m ball is dropped on it near the middle and rolls, meeting
the same few triangles whatever the terrain's size. For each size, in this
process (kernels warm after a first small run): seconds to add the mesh to a World
(``World.add_body``: the mesh checked, its triangles kept as one block), to build the engine
(``World.prepare``: the model, every piece placed, the tree), then the median seconds of a step
over ``--steps`` steps, and the peak resident memory so far.

Run:  python benchmarks/terrain.py
      python benchmarks/terrain.py --sizes 2000 200000 2000000 --steps 200
"""

from __future__ import annotations

import argparse
import math
import resource
import statistics
import time

import numpy as np

import carom
from carom.meshes import Mesh, terrain_mesh
from carom.shapes3d import Sphere

#: the side of a terrain square (two triangles) [m]
SQUARE = 20.0 / 32.0


def terrain(triangles: int) -> Mesh:
    """A heightfield of about ``triangles`` triangles, each square :data:`SQUARE` [m]."""
    return terrain_mesh(max(1, round(math.sqrt(triangles / 2))), SQUARE)


def world_on(mesh: Mesh) -> carom.World:
    side = float(np.max(np.asarray(mesh.vertices)[:, 0]))
    world = carom.World(3, [side, side, 4.0], gravity=[0.0, 0.0, -9.81])
    world.add_body(mesh, [0.0, 0.0, 0.0], kind="static")
    middle = 0.5 * side + 0.1
    world.add_body(Sphere(0.2), [middle, middle, 2.0], velocity=[1.0, 0.5, 0.0], density=1000.0)
    return world


def peak_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--sizes", type=int, nargs="+", default=[2000, 200_000, 2_000_000])
    parser.add_argument("--steps", type=int, default=200)
    args = parser.parse_args()
    warm = world_on(terrain(200))
    warm.prepare()
    warm.run(0.1)
    print("| triangles | add [s] | build [s] | step [ms] (min-max) | peak RSS [MB] |")
    print("|---|---|---|---|---|")
    for size in args.sizes:
        mesh = terrain(size)
        began = time.perf_counter()
        world = world_on(mesh)
        added = time.perf_counter() - began
        began = time.perf_counter()
        world.prepare()
        built = time.perf_counter() - began
        engine = world.engine
        assert engine is not None
        dt = float(world.fixed_step or 1.0 / 60.0)
        times = []
        for k in range(args.steps):
            began = time.perf_counter()
            world.run((k + 1) * dt)
            times.append(time.perf_counter() - began)
        ms = [1e3 * t for t in times[10:]]  # the ball falling onto the terrain first
        print(
            f"| {len(np.asarray(mesh.triangles))} | {added:.2f} | {built:.2f} | "
            f"{statistics.median(ms):.3f} "
            f"({min(ms):.3f}-{max(ms):.3f}) | {peak_mb():.0f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
