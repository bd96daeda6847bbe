"""A ball on a static terrain of many triangles: the engine's build and its steps against the
terrain's size (issue 45, item 2: a ball on 2e6 triangles steps in about the time it takes on
2e3; static pieces never paired with each other, the terrain's triangles found through the
tree of :mod:`carom.geometry.bvh`).

The terrain is a square heightfield of gentle waves, 2 k^2 triangles over 20 m x 20 m, a static
:class:`carom.meshes.Mesh`; a 0.2 m ball is dropped on it and rolls. For each size, in this
process (kernels warm after a first small run): seconds to build the engine
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
from carom.meshes import Mesh
from carom.shapes3d import Sphere


def terrain(triangles: int, side: float = 20.0) -> Mesh:
    """A heightfield of about ``triangles`` triangles over ``side`` x ``side`` [m]."""
    k = max(1, round(math.sqrt(triangles / 2)))
    x, y = np.meshgrid(np.linspace(0.0, side, k + 1), np.linspace(0.0, side, k + 1), indexing="ij")
    z = 1.0 + 0.2 * np.sin(x / 3.0) * np.cos(y / 4.0)
    vertices = np.column_stack([x.ravel(), y.ravel(), z.ravel()])
    i, j = np.meshgrid(np.arange(k), np.arange(k), indexing="ij")
    a = (i * (k + 1) + j).ravel()
    b, c, d = a + (k + 1), a + 1, a + (k + 1) + 1
    faces = np.concatenate([np.stack([a, b, c], 1), np.stack([c, b, d], 1)])
    return Mesh(vertices, faces)


def world_on(mesh: Mesh) -> carom.World:
    world = carom.World(3, [20.0, 20.0, 4.0], gravity=[0.0, 0.0, -9.81])
    world.add_body(mesh, [0.0, 0.0, 0.0], kind="static")
    world.add_body(Sphere(0.2), [10.0, 10.0, 2.0], velocity=[1.0, 0.5, 0.0], density=1000.0)
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
    print("| triangles | build [s] | step [ms] (min-max) | peak RSS [MB] |")
    print("|---|---|---|---|")
    for size in args.sizes:
        mesh = terrain(size)
        world = world_on(mesh)
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
            f"| {len(np.asarray(mesh.triangles))} | {built:.2f} | {statistics.median(ms):.3f} "
            f"({min(ms):.3f}-{max(ms):.3f}) | {peak_mb():.0f} |",
            flush=True,
        )


if __name__ == "__main__":
    main()
