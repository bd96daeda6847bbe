"""The event-driven engine's driver (carom.engines.edmd.driver) through a World: same input,
same bits; checkpoints that resume bit for bit; frames at exact times; lists and cell rows that
grow without changing a bit of the physics."""

from __future__ import annotations

import numpy as np

import carom
from tests.worlds import gas


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
