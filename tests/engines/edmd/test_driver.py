"""The event-driven engine's driver (carom.engines.edmd.driver) through a World: same input,
same bits; checkpoints that resume bit for bit; frames at exact times; lists and cell rows that
grow without changing a bit of the physics."""

from __future__ import annotations

import numpy as np
import pytest

import carom
from tests.worlds import gas

EPS = float(np.finfo(np.float64).eps)


def test_same_input_gives_bit_identical_results() -> None:
    runs = []
    for _ in range(2):
        world = gas(3, 6, 0.3, seed=5, e=0.9)
        world.run(until=20.0, log=True)
        runs.append((world.positions, world.velocities, world.collisions))
    np.testing.assert_array_equal(runs[0][0], runs[1][0])
    np.testing.assert_array_equal(runs[0][1], runs[1][1])
    assert runs[0][2].tobytes() == runs[1][2].tobytes()


def test_checkpoint_resume_is_bit_identical(tmp_path) -> None:  # type: ignore[no-untyped-def]
    straight = gas(2, 12, 0.4, seed=2, boundary="walls", e=0.95)
    straight.run(until=30.0, log=True)
    first = gas(2, 12, 0.4, seed=2, boundary="walls", e=0.95)
    first.run(until=12.0, log=True)
    first.save(tmp_path / "mid.npz")
    resumed = carom.World.load(tmp_path / "mid.npz")
    resumed.run(until=30.0, log=True)
    assert resumed.time == straight.time
    np.testing.assert_array_equal(resumed.positions, straight.positions)
    np.testing.assert_array_equal(resumed.velocities, straight.velocities)
    # the checkpoint keeps the log too: the resumed world holds every collision since t = 0
    assert resumed.collisions.tobytes() == straight.collisions.tobytes()
    assert resumed.stats.collisions == straight.stats.collisions
    assert not list(tmp_path.glob("*.partial"))


def test_frames_are_at_exact_output_times() -> None:
    world = gas(2, 5, 0.2, seed=0)
    seen: list[float] = []
    frames = world.run(until=1.0, frame_interval=0.25, callback=lambda f: seen.append(f.time))
    assert frames is not None
    assert [f.time for f in frames] == [0.25, 0.5, 0.75, 1.0]
    assert seen == [0.25, 0.5, 0.75, 1.0]
    assert frames[-1].positions.shape == (25, 2)


def test_neighbour_lists_grow_without_changing_the_physics() -> None:
    # Lists that start far too small overflow at once and again during the run; growing them
    # rebuilds every list but keeps the schedule, so the events are exactly those of a world
    # whose lists were large enough from the start.
    roomy = gas(3, 7, 0.45, seed=8, e=0.9)
    roomy.run(until=5.0, log=True)
    cramped = gas(3, 7, 0.45, seed=8, e=0.9)
    engine = cramped.build()
    tight = int(engine.neighbour_counts().max())
    engine.resize_grid(tight, engine.cell_capacity)  # the first denser neighbourhood overflows
    cramped.run(until=5.0, log=True)
    assert engine.capacity > tight  # it did overflow during the run, and grew
    assert cramped.collisions.tobytes() == roomy.collisions.tobytes()
    np.testing.assert_array_equal(cramped.positions, roomy.positions)


def test_cell_rows_grow_without_changing_the_physics() -> None:
    # The same for the cell grid's rows: cells filled to the brim at the start overflow as a
    # dissipative gas clusters.
    roomy = gas(3, 10, 0.3, seed=8, e=0.8)
    roomy.run(until=5.0, log=True)
    cramped = gas(3, 10, 0.3, seed=8, e=0.8)
    engine = cramped.build()
    tight = engine.max_cell_occupancy()
    engine.resize_grid(engine.capacity, tight)
    cramped.run(until=5.0, log=True)
    assert engine.cell_capacity > tight
    assert cramped.collisions.tobytes() == roomy.collisions.tobytes()
    np.testing.assert_array_equal(cramped.positions, roomy.positions)


def test_collisions_carry_the_contact_point() -> None:
    # two spheres touch at the point on the line of centres a_j from j's centre (and a_i from
    # i's): with the impulse, each body's angular impulse (p - x) x J; a wall contact is the
    # sphere's centre less its radius along the wall's normal. Positions at the collision come
    # from the log's time and the (straight) free flight, to round-off of the 1 m box.
    world = carom.World(3, [1.0, 1.0, 1.0])
    x0 = np.array([[0.3, 0.5, 0.5], [0.7, 0.55, 0.5]])
    v0 = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    world.add_spheres(x0, v0, radius=[0.1, 0.05])
    world.run(until=1.0, log=True)  # (the pair meets at 0.125 s, then each reaches a wall)
    pair = world.collisions[world.collisions["kind"] == 0][0]
    t = pair["time"]
    xi, xj = x0[pair["body"]] + v0[pair["body"]] * t, x0[pair["partner"]] + v0[pair["partner"]] * t
    ai, aj = (0.1, 0.05) if pair["body"] == 0 else (0.05, 0.1)
    n = (xi - xj) / np.linalg.norm(xi - xj)
    # (coordinates below 1 m through a few operations each: 8 eps of 1 m)
    np.testing.assert_allclose(pair["point"], xj + aj * n, rtol=0, atol=8 * EPS)
    np.testing.assert_allclose(pair["point"], xi - ai * n, rtol=0, atol=8 * EPS)
    wall = world.collisions[world.collisions["kind"] == 1][0]
    face = int(wall["partner"])  # 2 k + 1: the upper wall of axis k
    axis = face // 2
    # on the wall itself, to round-off of the 1 m box (the centre touches it to a few eps)
    expected = 0.0 if face % 2 == 0 else 1.0
    assert wall["point"][axis] == pytest.approx(expected, abs=8 * EPS)


def test_periodic_contact_points_lie_in_the_box() -> None:
    world = gas(2, 12, 0.4, seed=2)
    world.run(until=5.0, log=True)
    points = world.collisions["point"][:, :2]
    assert len(points) > 1000
    assert np.all((points >= 0.0) & (points < world.box))
