"""Bounded cost whatever the size (issue 45, item 2): what the steps and the build look at
does not grow with static scenery the moving bodies never reach. Not timed here (timings are
benchmarks/terrain.py's and benchmarks/hulls.py's, RESULTS.md); counted.
"""

from __future__ import annotations

import pytest

import carom
from carom.meshes import terrain_mesh
from carom.shapes3d import Sphere, TrianglePieces

SQUARE = 0.625  # a terrain square's side [m] (two triangles)


def _pairs_per_step(k: int) -> list[int]:
    side = k * SQUARE
    world = carom.World(3, [side, side, 4.0], gravity=[0.0, 0.0, -9.81])
    world.add_body(terrain_mesh(k, SQUARE), [0.0, 0.0, 0.0], kind="static")
    # the same place on every terrain (the waves are the same there), away from its edges
    world.add_body(Sphere(0.2), [2.6, 2.5, 1.6], velocity=[0.3, 0.2, 0.0], density=1000.0)
    assert isinstance(world.bodies.pieces[0], TrianglePieces)  # one block, not 2 k^2 objects
    engine = world.build()
    counts = []
    for _ in range(60):
        engine.step()
        counts.append(engine._n_pairs)
    return counts


@pytest.mark.parametrize("k", [8, 64])
def test_a_ball_on_a_terrain_meets_the_same_triangles_whatever_its_size(k: int) -> None:
    # 128 and 8192 triangles: the ball falls, lands and rolls on the same few triangles; the
    # broad phase gives the same pairs a step (a static triangle is never
    # paired with another: that was k^2 pairs and more a step)
    small, large = _pairs_per_step(8), _pairs_per_step(k)
    assert large == small
    assert max(large) <= 12  # the ball's swept box over a few 0.625 m squares
    assert max(large) > 0  # it did land
