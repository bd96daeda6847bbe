"""Regression: adding bodies to a world that had already run raised a shape mismatch.

World._append grew the arrays first and then copied the engine's state (one row short) back
into them. The state is now taken out of the engine before the arrays grow.
"""

from __future__ import annotations

import numpy as np
import pytest

import carom


def test_bodies_can_be_added_after_a_run() -> None:
    world = carom.World(2, [1.0, 1.0])
    world.add_spheres([[0.3, 0.5]], [[1.0, 0.0]], radius=0.05)
    world.run(until=0.1)
    new = world.add_spheres([[0.7, 0.2]], radius=0.05)
    assert new.tolist() == [1]
    world.run(until=0.2)
    # the first sphere kept flying at 1 m/s (no collision yet: it reaches x = 0.5 at t = 0.2)
    np.testing.assert_allclose(world.positions, [[0.5, 0.5], [0.7, 0.2]], atol=1e-15)
    assert world.time == pytest.approx(0.2, abs=0)
