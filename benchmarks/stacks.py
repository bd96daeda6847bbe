"""Resting stacks, sleep off: how far the energy rises as they settle, carom beside its peers.

A stack of n unit boxes (1 kg, friction 0.6) placed exactly touching on a static floor,
gravity 9.81 m/s^2, 60 Hz and 4 substeps, run for ``--until`` seconds with sleep off. For each
engine and n: the largest rise of the mechanical energy (kinetic, rotational and potential)
above an earlier minimum [J], the largest sideways move of any box [m] and the top box's sink
at the end [m]. Issue 45 asked that the rise stay under 1e-6 J; this measures where carom and
the engines a game developer would pick stand. The motion is deterministic, so nothing here
is timed: one run of each engine and n.

* carom 2D and 3D (the rigid engines, their default settings);
* Box2D v3 in C (2D), given its source tree: ``--box2d-v3 DIR`` builds it with cmake and runs
  benchmarks/box2d_v3/stack.c on it (float arithmetic; the energy summed in double);
* Rapier (3D) through ``rapier3d`` from PyPI (``pip install -e '.[compare]'``), its default
  integration parameters, one thread, f32.

Usage::

    python benchmarks/stacks.py --box2d-v3 ~/src/box2d
    python benchmarks/stacks.py --boxes 10 15 20 --until 60
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

import carom
from carom.engines.stepped.settings import RigidSettings

G = 9.81
GRIP = 0.6


def carom_stack(dim: int, n: int, until: float) -> dict[str, float]:
    """The stack in carom's rigid engine of dimension ``dim``."""
    grip = carom.Material(0.0, friction=GRIP)
    settings = RigidSettings(sleep=False)
    if dim == 2:
        from carom.shapes import Box

        world = carom.World(2, [10.0, n + 2.0], gravity=[0.0, -G], boundary="open", rigid=settings)
        world.add_body(Box(20.0, 1.0), [5.0, -0.5], kind="static", material=grip)
        for k in range(n):
            world.add_body(Box(1.0, 1.0), [5.0, 0.5 + k], material=grip)
    else:
        from carom.shapes3d import Box as Box3D

        world = carom.World(
            3, [10.0, 10.0, n + 2.0], gravity=[0.0, 0.0, -G], boundary="open", rigid=settings
        )
        world.add_body(Box3D([20.0, 20.0, 1.0]), [5.0, 5.0, -0.5], kind="static", material=grip)
        for k in range(n):
            world.add_body(Box3D([1.0, 1.0, 1.0]), [5.0, 5.0, 0.5 + k], material=grip)
    engine = world.build()
    energy = [engine.energy()]
    sway = 0.0
    while engine.time < until - 1e-9:
        engine.step()
        energy.append(engine.energy())
        sway = max(sway, float(np.abs(engine.state.x[1:, : dim - 1] - 5.0).max()))
    e = np.array(energy)
    rise = float((e - np.minimum.accumulate(e)).max())
    return {"rise_J": rise, "sway_m": sway, "sink_m": float(engine.state.x[-1, -1] - (n - 0.5))}


def rapier_stack(n: int, until: float) -> dict[str, float]:
    """The stack in Rapier (3D), its defaults: 60 Hz, 4 solver iterations."""
    import rapier3d as r

    world = r.PhysicsWorld(gravity=(0.0, 0.0, -G))
    world.set_num_threads(1)
    floor = r.Collider.cuboid(10.0, 10.0, 0.5).friction(GRIP)
    world.add_body(r.RigidBody.fixed().position(((5.0, 5.0, -0.5), (0.0, 0.0, 0.0, 1.0))), [floor])
    boxes = []
    for k in range(n):
        body = r.RigidBody.dynamic().position(((5.0, 5.0, 0.5 + k), (0.0, 0.0, 0.0, 1.0)))
        body = body.can_sleep(False).linear_damping(0.0).angular_damping(0.0)
        boxes.append(world.add_body(body, [r.Collider.cuboid(0.5, 0.5, 0.5).friction(GRIP)]))
    lowest, rise, sway, top = np.inf, 0.0, 0.0, 0.0
    for step in range(round(until * 60.0) + 1):
        if step:
            world.step()
        energy = 0.0
        for handle in boxes:
            b = world.rigid_bodies[handle]
            x = np.array(tuple(b.translation), float)
            v = np.array(tuple(b.linvel), float)
            w = np.array(tuple(b.angvel), float)
            # a unit cube of 1 kg: I = 1/6 kg m^2 about every axis
            energy += 0.5 * v @ v + (w @ w) / 12.0 + G * x[2]
            sway = max(sway, float(np.abs(x[:2] - 5.0).max()))
            top = x[2]
        rise = max(rise, energy - lowest)
        lowest = min(lowest, energy)
    return {"rise_J": rise, "sway_m": sway, "sink_m": top - (n - 0.5)}


def box2d_stacks(source: Path, boxes: list[int], until: float) -> dict[int, dict[str, float]]:
    """The stacks in Box2D v3 (2D, its default build), built from ``source``."""
    from steppers import Box2DV3

    with tempfile.TemporaryDirectory(prefix="box2d-v3-") as build:
        v3 = Box2DV3(source, Path(build), "stack")
        return {n: v3.run("sse2", str(n), str(until)) for n in boxes}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--boxes", type=int, nargs="+", default=list(range(4, 13)))
    parser.add_argument("--until", type=float, default=30.0, help="simulated time [s]")
    parser.add_argument("--box2d-v3", type=Path, metavar="DIR", help="a Box2D v3 source tree")
    args = parser.parse_args()
    rows: dict[str, dict[int, dict[str, Any]]] = {"carom 2D": {}, "carom 3D": {}}
    for n in args.boxes:
        rows["carom 2D"][n] = carom_stack(2, n, args.until)
        rows["carom 3D"][n] = carom_stack(3, n, args.until)
    if args.box2d_v3 is not None:
        rows["Box2D v3 (2D)"] = box2d_stacks(args.box2d_v3.expanduser(), args.boxes, args.until)
    try:
        rows["Rapier (3D)"] = {n: rapier_stack(n, args.until) for n in args.boxes}
    except ImportError:
        print("(rapier3d is not installed: pip install -e '.[compare]')")
    print(f"stacks of unit boxes, sleep off, {args.until:g} s; rise of the energy above an "
          "earlier minimum [J] (sway [m])")  # fmt: skip
    print("| engine | " + " | ".join(f"n = {n}" for n in args.boxes) + " | worst |")
    print("|---" * (len(args.boxes) + 2) + "|")
    for name, found in rows.items():
        cells = [f"{found[n]['rise_J']:.2g} ({found[n]['sway_m']:.2g})" for n in args.boxes]
        worst = max(found[n]["rise_J"] for n in args.boxes)
        print(f"| {name} | " + " | ".join(cells) + f" | {worst:.3g} |")


if __name__ == "__main__":
    main()
