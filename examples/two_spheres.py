"""Two spheres, every law: smooth, rough, Walton friction, and Hecker's two readings.

Run: python examples/two_spheres.py
"""

from __future__ import annotations

import math

import numpy as np

import carom
from carom.studies import hecker


def main() -> None:
    # a cut shot between two 0.17 kg billiard balls (radius 28.6 mm), cue ball at 2 m/s
    a = 0.0286
    x1 = np.array([-math.sqrt(3) * a, -a])  # impact parameter a: half the sum of the radii
    x2 = np.zeros(2)
    v1, v2, m = np.array([2.0, 0.0]), np.zeros(2), 0.17

    for e in (1.0, 0.9, 0.0):
        r = carom.collide(x1, v1, m, x2, v2, m, e=e)
        angle = math.degrees(math.acos(r.v1 @ r.v2 / (np.hypot(*r.v1) * np.hypot(*r.v2))))
        print(
            f"smooth e={e:3.1f}: v1'={r.v1.round(4)} v2'={r.v2.round(4)} "
            f"angle={angle:5.1f} deg  KE lost={r.ke_lost:.4f} J"
        )

    rough = carom.collide(x1, v1, m, x2, v2, m, e=0.9, beta=0.3, radius1=a, radius2=a)
    print(f"rough beta=0.3:  v1'={rough.v1.round(4)} spins={rough.w1:.2f}, {rough.w2:.2f} rad/s")
    walton = carom.collide(x1, v1, m, x2, v2, m, e=0.9, friction=0.06, radius1=a, radius2=a)
    print(f"Walton mu=0.06:  v1'={walton.v1.round(4)} beta used={walton.beta:.3f}")

    for reading in ("contact", "head-on"):
        h = hecker.collide(x1, v1, m, x2, v2, m, e=1.0, reading=reading)
        print(f"Hecker {reading:8s}: v1'={h.v1.round(4)} v2'={h.v2.round(4)}")

    # a batch: one cue ball against a million object balls at random cut angles
    n = 1_000_000
    rng = np.random.default_rng(1)
    angle = rng.uniform(-0.9, 0.9, n) * math.pi / 2
    x1s = -2 * a * np.stack([np.cos(angle), np.sin(angle)], axis=1)
    batch = carom.collide(x1s, v1, m, x2, v2, m, e=0.95)
    print(
        f"batch of {n:,}: mean KE lost {batch.ke_lost.mean():.5f} J, "
        f"all applied: {bool(batch.applied.all())}"
    )


if __name__ == "__main__":
    main()
