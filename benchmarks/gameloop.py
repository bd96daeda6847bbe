"""A game's frame loop, carom beside pymunk and Box2D 2.3 (pybox2d), in one run (issue 43, item 7).

Each engine holds N unit-half boxes (0.5 m) dropped in a grid into a walled pit (2D, 60 Hz),
settled for a second, then runs frames that each: apply an impulse to 10 bodies (a rotating
set), step once, read every body's position and angle, and read the step's contact events
(carom: ``contact_events()``; pymunk: a begin handler; Box2D: a contact listener's
BeginContact). Each engine first settles for a second and runs a second of the timed frames
untimed (one-time costs out of the rounds: first calls, lazy loads). Rounds interleave the
engines, their order rotating; each engine is set up as
its documentation recommends (pymunk: ``Space.step`` at 1/60 with its default iterations;
Box2D 2.3: ``Step(1/60, 8, 3)``). Reported: each engine's ms a frame (median of the rounds),
the ratio carom / peer (median and spread over the rounds), and carom's own cost beyond its
engine step: the frame's time less the time inside ``SteppedEngine.step`` (the Python of
``World.step``, the impulses, the reads and the events), in microseconds a frame.

Target: carom's Python beyond the step under 50 us a frame at 1000 bodies; carom's whole frame
at most pymunk's.

Run:  python benchmarks/gameloop.py [--bodies 100 1000 10000] [--rounds 5] [--frames 120]
Needs the compare extra (pymunk, Box2D): pip install -e '.[compare]'.
"""

from __future__ import annotations

import argparse
import statistics
import time
from collections.abc import Callable
from typing import Any

import numpy as np

DT = 1.0 / 60.0
HALF = 0.25  # the boxes' half side [m]
KICK = 10  # bodies pushed a frame


def _grid(n: int) -> tuple[np.ndarray, float]:
    """N box centres in a grid 0.6 m apart above a pit floor at y = 0, and the pit's width."""
    per_row = max(4, int(np.ceil(np.sqrt(n))))
    k = np.arange(n)
    width = per_row * 0.6 + 0.6
    return np.column_stack((0.6 + 0.6 * (k % per_row), 0.5 + 0.6 * (k // per_row))), width


class Carom:
    name = "carom"

    def __init__(self, n: int) -> None:
        import carom
        from carom.materials import Material
        from carom.shapes import Box

        at, width = _grid(n)
        height = float(at[-1, 1]) + 2.0
        # the peers' surfaces: friction 0.6, no bounce (pymunk's and Box2D's default
        # restitution is 0, walls included)
        surface = Material(restitution=0.0, friction=0.6)
        world = carom.World(
            2, [width, height], gravity=[0.0, -9.81], boundary="walls", walls=surface
        )
        world.add_bodies(Box(2 * HALF, 2 * HALF), at, material=surface)
        world.prepare()
        self.world, self.n, self.inside = world, n, 0.0
        engine = world.build()
        step = engine.step

        def timed(*args: Any) -> None:
            start = time.perf_counter()
            step(*args)
            self.inside += time.perf_counter() - start

        engine.step = timed  # type: ignore[method-assign]

    def frame(self, kick: np.ndarray) -> int:
        world = self.world
        if kick.size:
            world.apply_impulses(kick, [0.0, 0.5])
        world.step()
        x, angle = world.positions, world.orientations  # every body's pose
        assert x.shape[0] == self.n
        assert angle.shape[0] == self.n
        return int(world.contact_events().begin.size)


class Pymunk:
    name = "pymunk"

    def __init__(self, n: int) -> None:
        import pymunk

        at, width = _grid(n)
        space = pymunk.Space()
        space.gravity = (0.0, -9.81)
        top = float(at[-1, 1]) + 2.0
        for a, b in (((0, 0), (width, 0)), ((0, 0), (0, top)), ((width, 0), (width, top))):
            wall = pymunk.Segment(space.static_body, a, b, 0.0)
            wall.friction = 0.6
            space.add(wall)
        self.bodies = []
        for p in at:
            body = pymunk.Body(1.0, pymunk.moment_for_box(1.0, (2 * HALF, 2 * HALF)))
            body.position = (float(p[0]), float(p[1]))
            shape = pymunk.Poly.create_box(body, (2 * HALF, 2 * HALF))
            shape.friction = 0.6
            space.add(body, shape)
            self.bodies.append(body)
        self.began = 0

        def begin(arbiter: Any, space: Any, data: Any) -> None:
            self.began += 1

        space.on_collision(begin=begin)
        self.space = space

    def frame(self, kick: np.ndarray) -> int:
        for i in kick.tolist():
            self.bodies[i].apply_impulse_at_local_point((0.0, 0.5))
        self.began = 0
        self.space.step(DT)
        poses = [(b.position, b.angle) for b in self.bodies]
        assert len(poses) == len(self.bodies)
        return self.began


class Box2D23:
    name = "Box2D 2.3"

    def __init__(self, n: int) -> None:
        import Box2D

        at, width = _grid(n)
        outer = self

        class Listener(Box2D.b2ContactListener):  # type: ignore[misc]
            def BeginContact(self, contact: Any) -> None:
                outer.began += 1

        self.listener = Listener()
        world = Box2D.b2World(gravity=(0.0, -9.81), contactListener=self.listener)
        top = float(at[-1, 1]) + 2.0
        ground = world.CreateStaticBody()
        for a, b in (((0, 0), (width, 0)), ((0, 0), (0, top)), ((width, 0), (width, top))):
            ground.CreateEdgeFixture(vertices=[a, b], friction=0.6)
        self.bodies = []
        for p in at:
            body = world.CreateDynamicBody(position=(float(p[0]), float(p[1])))
            body.CreatePolygonFixture(box=(HALF, HALF), density=4.0, friction=0.6)
            self.bodies.append(body)
        self.world, self.began = world, 0

    def frame(self, kick: np.ndarray) -> int:
        for i in kick.tolist():
            body = self.bodies[i]
            body.ApplyLinearImpulse((0.0, 0.5), body.worldCenter, True)
        self.began = 0
        self.world.Step(DT, 8, 3)
        poses = [(b.position, b.angle) for b in self.bodies]
        assert len(poses) == len(self.bodies)
        return self.began


PEERS: list[Callable[[int], Any]] = [Carom, Pymunk, Box2D23]


def measure(n: int, rounds: int, frames: int) -> dict[str, list[float]]:
    """ms a frame for each engine, ``rounds`` interleaved rounds of ``frames`` frames, after a
    settling second; for carom also the us a frame beyond its engine step."""
    engines = [make(n) for make in PEERS]
    rng = np.random.default_rng(0)
    for engine in engines:  # settle: one second, untimed; then a second of the timed frames
        for _ in range(60):
            engine.frame(np.zeros(0, np.int64))
        warm = np.random.default_rng(1)  # (the same kicks for every engine)
        for _ in range(60):
            engine.frame(warm.choice(n, size=min(KICK, n), replace=False))
    times: dict[str, list[float]] = {e.name: [] for e in engines} | {"carom beyond": []}
    for r in range(rounds):
        order = engines[r % len(engines) :] + engines[: r % len(engines)]
        for engine in order:
            kicks = [rng.choice(n, size=min(KICK, n), replace=False) for _ in range(frames)]
            if engine.name == "carom":
                engine.inside = 0.0
            start = time.perf_counter()
            for kick in kicks:
                engine.frame(kick)
            spent = time.perf_counter() - start
            times[engine.name].append(1e3 * spent / frames)
            if engine.name == "carom":
                times["carom beyond"].append(1e6 * (spent - engine.inside) / frames)
    return times


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--bodies", type=int, nargs="+", default=[100, 1000, 10000])
    parser.add_argument("--rounds", type=int, default=5)
    parser.add_argument("--frames", type=int, default=120)
    args = parser.parse_args()
    print(
        "| bodies | carom ms/frame | pymunk | Box2D 2.3 | carom / pymunk (median, range) "
        "| carom / Box2D 2.3 | carom beyond its step, us/frame |"
    )
    print("|---|---|---|---|---|---|---|")
    for n in args.bodies:
        t = measure(n, args.rounds, args.frames if n < 10000 else max(20, args.frames // 4))
        c = np.array(t["carom"])
        cells = [f"{statistics.median(t[name]):.3f}" for name in ("carom", "pymunk", "Box2D 2.3")]
        ratios = []
        for name in ("pymunk", "Box2D 2.3"):
            q = c / np.array(t[name])
            ratios.append(f"{np.median(q):.2f} ({q.min():.2f}-{q.max():.2f})")
        beyond = t["carom beyond"]
        print(
            f"| {n} | {' | '.join(cells)} | {' | '.join(ratios)} | "
            f"{statistics.median(beyond):.1f} ({min(beyond):.1f}-{max(beyond):.1f}) |"
        )


if __name__ == "__main__":
    main()
