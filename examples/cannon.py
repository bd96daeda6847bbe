"""A small 2D game on carom's game loop: a cannon, targets that report hits, an aim line.

Each second the cannon aims at the next target standing, casts a ray to see whether its line
of sight is clear, and fires. Contact events say which target was hit, when and how hard.

Run: python examples/cannon.py
"""

from __future__ import annotations

import math

import numpy as np

import carom
from carom.shapes import Box, Circle

G = 9.81
POSTS = [(14.0, 1.0), (18.0, 2.0), (22.0, 3.0)]  # each target's post: x, height [m]


def build() -> tuple[carom.World, list[int]]:
    world = carom.World(2, [30.0, 15.0], gravity=[0.0, -G], boundary="open")
    world.add_body(Box(30.0, 1.0), [15.0, -0.5], kind="static", restitution=0.2)
    targets = []
    for x, h in POSTS:
        world.add_body(Box(0.4, h), [x, h / 2], kind="static", restitution=0.2)
        targets.append(world.add_body(Box(0.6, 0.6), [x, h + 0.3], restitution=0.2))
    world.hit_threshold = 2.0  # [m/s]: a graze is not a hit
    return world, targets


def aim(muzzle: np.ndarray, goal: np.ndarray, speed: float) -> float:
    """The low angle that lands a shot of ``speed`` on ``goal`` (projectile range)."""
    dx, dy = goal - muzzle
    root = math.sqrt(speed**4 - G * (G * dx * dx + 2 * dy * speed * speed))
    return math.atan2(speed * speed - root, G * dx)


def main() -> None:
    world, targets = build()
    muzzle, speed, score = np.array([2.0, 1.0]), 16.0, 0
    down = set()
    for frame in range(6 * 60):
        if frame % 60 == 0:
            standing = [t for t in targets if t not in down]
            if not standing:
                break
            goal = world.body(standing[0]).position
            angle = aim(muzzle, goal, speed)
            heading = np.array([math.cos(angle), math.sin(angle)])
            sight = world.ray_cast(muzzle, goal - muzzle)
            clear = sight is not None and sight.body == standing[0]
            print(
                f"t={world.time:4.2f} s  aim {math.degrees(angle):4.1f} deg at {standing[0]}, "
                f"sight {'clear' if clear else 'blocked'}"
            )
            world.add_body(Circle(0.15), muzzle, velocity=speed * heading, restitution=0.2)
        world.step()
        for hit in world.contact_events().hit:
            struck = {int(hit["a"]), int(hit["b"])} & set(targets)
            if struck:
                print(f"  hit {struck.pop()} at t={hit['time']:.3f} s, {hit['speed']:.1f} m/s")
        for t, (_, h) in zip(targets, POSTS, strict=True):
            if t not in down and world.body(t).position[1] < h - 0.1:
                down.add(t)
                score += 1
                print(f"  target {t} is down: score {score}")
    print(f"score {score} of {len(targets)} in {world.time:.2f} s")


if __name__ == "__main__":
    main()
