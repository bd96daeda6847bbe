"""The event-driven engine's driver (carom.engines.edmd.driver) through a World: same input,
same bits; checkpoints that resume bit for bit; frames at exact times; lists and cell rows that
grow without changing a bit of the physics."""

from __future__ import annotations

from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import carom
from carom.engines.edmd import state
from carom.engines.edmd.assemble import environment
from carom.engines.edmd.driver import EdmdEngine
from carom.scene import find_scene, load_scene
from carom.scene.layouts import lattice_gas
from tests.processes import fresh_python
from tests.worlds import gas, rough_disks

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


def test_records_and_lists_start_on_cache_lines(tmp_path) -> None:  # type: ignore[no-untyped-def]
    # Each body's kinematic record is one 64-byte line and its neighbour list whole lines
    # (the loop asks for a list's second line where its 17th entry starts), after a build,
    # after the lists grow, and after a checkpoint is read (numpy reads them anywhere).
    def on_lines(engine: EdmdEngine) -> bool:
        kin, nbr = engine.state.kin, engine.state.nbr
        return kin.ctypes.data % 64 == 0 and nbr.ctypes.data % 64 == 0

    world = gas(3, 6, 0.3, seed=3)
    engine = world.build()
    assert on_lines(engine)
    engine.resize_grid(engine.capacity + 3, engine.cell_capacity)  # (an odd row length)
    assert engine.state.nbr.shape[1] == engine.capacity
    world.run(until=2.0)
    assert on_lines(engine)
    world.save(tmp_path / "gas.npz")
    loaded = carom.World.load(tmp_path / "gas.npz")
    assert on_lines(loaded.build())


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


def _frames_as_arrays(frames: list[carom.Frame]) -> dict[str, np.ndarray]:
    return {
        "times": np.array([f.time for f in frames]),
        "positions": np.stack([f.positions for f in frames]),
        "velocities": np.stack([f.velocities for f in frames]),
        "orientations": np.stack([f.orientations for f in frames]),
        "angular_velocities": np.stack([f.angular_velocities for f in frames]),
    }


@pytest.mark.parametrize(
    "make",
    [
        lambda: gas(3, 6, 0.3, seed=5, e=0.9),  # periodic, dissipative
        lambda: gas(2, 8, 0.4, seed=2, boundary="walls", e=0.95),
        lambda: load_scene(find_scene("bouncing-ball")).build(),  # gravity; it comes to rest
        lambda: load_scene(find_scene("dominoes")).build(),  # the 2D rigid engine, step by step
    ],
)
def test_a_recording_is_the_frames_bit_for_bit(make) -> None:  # type: ignore[no-untyped-def]
    # World.record runs many frames in one compiled call; World.frames makes one call a frame:
    # the same events, the same samples
    streamed = make()
    until = streamed.time + 3.0
    frames = _frames_as_arrays(list(streamed.frames(until, 0.05)))
    recorded = make()
    times = recorded.frame_times(until, 0.05)
    rec = recorded.record(times, log=True)
    assert len(rec) == len(times) == len(frames["times"])
    for name, value in frames.items():
        np.testing.assert_array_equal(getattr(rec, name), value, err_msg=name)
    assert recorded.time == streamed.time == until
    np.testing.assert_array_equal(recorded.positions, streamed.positions)
    assert recorded.reached


def test_a_recording_goes_on_through_growing_lists() -> None:
    # the lists overflow mid-recording: they grow, the engine's compiled handle is made again
    # on the new arrays, and the frames are those of a world that never ran short
    roomy = gas(3, 7, 0.45, seed=8, e=0.9)
    times = roomy.frame_times(5.0, 0.1)
    expected = roomy.record(times)
    cramped = gas(3, 7, 0.45, seed=8, e=0.9)
    engine = cramped.build()
    tight = int(engine.neighbour_counts().max())
    engine.resize_grid(tight, engine.cell_capacity)
    got = cramped.record(times)
    assert engine.capacity > tight
    np.testing.assert_array_equal(got.positions, expected.positions)
    np.testing.assert_array_equal(got.velocities, expected.velocities)


def test_a_stopped_recording_returns_the_frames_before_the_stop() -> None:
    world = gas(2, 20, 0.3, seed=3)
    asked = [0]

    def stop() -> bool:
        asked[0] += 1
        return True  # at the first chance: after the first block of 65,536 events

    times = world.frame_times(200.0, 0.01)
    rec = world.record(times, stop=stop)
    assert asked[0] == 1
    assert not world.reached
    assert 0 < len(rec) < len(times)
    assert rec.times[-1] <= world.time < times[len(rec)]
    again = gas(2, 20, 0.3, seed=3)
    whole = again.record(times[: len(rec)])
    np.testing.assert_array_equal(rec.positions, whole.positions)


def test_frame_times_are_the_times_frames_yields() -> None:
    world = gas(2, 5, 0.2, seed=0)
    assert world.frame_times(1.0, 0.25).tolist() == [0.25, 0.5, 0.75, 1.0]
    assert world.frame_times(1.0, 0.3).tolist() == [0.3, 0.6, 0.8999999999999999, 1.0]
    assert [f.time for f in world.frames(1.0, 0.3)] == [0.3, 0.6, 0.8999999999999999, 1.0]


@pytest.mark.parametrize(
    ("times", "pattern"),
    [
        ([0.1, 0.3, 0.2], r"times must not decrease; got times\[1\] = 0\.3 then times\[2\] = 0\.2"),
        ([-1.0, 0.5], r"times must not start before the current time 0\.0 s; got times\[0\]"),
        ([0.1, float("nan")], r"times must be finite \[s\]; got times\[1\] = nan"),
        ([[0.1, 0.2]], r"times must be a 1-D array"),
        (["soon"], r"times must be numeric"),
    ],
)
def test_bad_recording_times_are_refused_by_name(times: object, pattern: str) -> None:
    world = gas(2, 5, 0.2, seed=0)
    with pytest.raises(carom.CaromError, match=pattern):
        world.record(times)  # type: ignore[arg-type]
    assert world.time == 0.0


def test_a_recording_too_large_for_memory_is_refused_first(monkeypatch: pytest.MonkeyPatch) -> None:
    import carom.world

    monkeypatch.setattr(carom.recording, "RECORD_BYTES", 9_000)
    # 25 disks, 8 float64 each a frame (position 2, velocity 2, angle, spin 3): 1600 bytes
    world = gas(2, 5, 0.2, seed=0)
    with pytest.raises(carom.CaromError, match=r"6 frames of 25 bodies take .* stream them"):
        world.record(np.linspace(0.1, 0.6, 6))
    assert world.time == 0.0
    assert len(world.record(np.linspace(0.1, 0.5, 5))) == 5


SAMPLER_RUN = """
import json
from carom.engines.edmd.driver import EdmdEngine
from carom.engines.edmd.handle import sample_motion_now, sample_now
from carom.scene.layouts import lattice_gas
world = lattice_gas(3, 5, 0.3, seed=2)
def loaded():
    return [len(sample_now.signatures), len(sample_motion_now.signatures)]
before = loaded()
sample, motion = EdmdEngine.sample, EdmdEngine.sample_motion
def refuse(engine):
    raise AssertionError("prepare sampled every body")
EdmdEngine.sample = EdmdEngine.sample_motion = refuse
world.prepare()
EdmdEngine.sample, EdmdEngine.sample_motion = sample, motion
prepared = loaded()
world.positions
world.frame()
print(json.dumps([before, prepared, loaded()]))
"""


@pytest.mark.needs_jit
def test_prepare_loads_the_sampler_without_sampling() -> None:
    # World.prepare loads every kernel a run and its frames call; the samplers (a frame, and
    # positions and velocities alone) are loaded by signature, without sampling (a frame of
    # 10^6 spheres would be 100 MB of arrays made and dropped). In a fresh process: no
    # sampler before prepare, one of each after it, loaded with the engine's samplers
    # refusing to run, and reading positions or a frame needs no other.
    assert fresh_python(SAMPLER_RUN) == [[0, 0], [1, 1], [1, 1]]


@pytest.mark.needs_jit
def test_a_state_filled_by_two_threads_is_the_one_filled_by_one(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    # From FILL_THREAD_BODIES bodies on, a second thread writes the state's constant arrays
    # while the first copies the bodies in (first writes to new memory overlap); below, one
    # thread does both. 65536 disks built both ways: every state array the same.
    submitted: list[str] = []

    class Spy(ThreadPoolExecutor):
        def submit(self, fn, /, *args, **kwargs):  # type: ignore[no-untyped-def]
            submitted.append(fn.__name__)
            return super().submit(fn, *args, **kwargs)

    monkeypatch.setattr(state, "ThreadPoolExecutor", Spy)
    threaded = lattice_gas(2, 256, 0.5, seed=3)
    assert threaded.n_bodies >= state.FILL_THREAD_BODIES
    two = threaded.build().state
    assert submitted == ["fill_constant"]
    monkeypatch.setattr(state, "FILL_THREAD_BODIES", threaded.n_bodies + 1)
    one = lattice_gas(2, 256, 0.5, seed=3).build().state
    assert submitted == ["fill_constant"]  # no thread the second time
    for name in state.State._fields:
        np.testing.assert_array_equal(getattr(two, name), getattr(one, name), err_msg=name)


def _walled_gas() -> carom.World:
    return gas(3, 3, 0.3, seed=1, boundary="walls")


def _galton() -> carom.World:
    return load_scene(find_scene("galton-board")).build()


def test_without_gravity_the_state_holds_no_accelerations_or_supports() -> None:
    # Model.gravity is None without gravity, and the state then has no acc (every
    # acceleration is +0.0) and no support (nothing rests): 32 bytes a sphere in 3D; under
    # gravity both are there
    flat, heavy = _walled_gas(), _galton()
    for world in (flat, heavy):
        world.run(until=world.time + 0.5)
    assert isinstance(flat.engine, EdmdEngine)
    assert isinstance(heavy.engine, EdmdEngine)
    assert flat.engine.model.gravity is None
    assert flat.engine.state.acc is None
    assert flat.engine.state.support is None
    np.testing.assert_array_equal(flat.engine.resting(), np.full(27, -1))
    assert heavy.engine.model.gravity is not None
    assert heavy.engine.state.acc is not None
    assert heavy.engine.state.support is not None


def _rough_gas() -> carom.World:
    """36 rough disks with spins, falling in a walled 2D box (tests.worlds.rough_disks)."""
    return rough_disks(6)


def _spin_of_minus_zero() -> carom.World:
    world = _walled_gas()
    world.add_spheres([[0.05, 0.05, 0.05]], angular_velocities=[[0.0, -0.0, 0.0]], radius=0.01)
    return world


def test_a_state_holds_spins_and_orientations_only_when_a_body_can_spin() -> None:
    # Model.q is None when every pair law is smooth, every spin zero and every orientation
    # the identity: the state then has no spins, orientations or their clocks (64 bytes a
    # sphere), and frames give every body the identity and no spin, as before
    flat = _walled_gas()
    flat.run(until=flat.time + 0.5)
    assert isinstance(flat.engine, EdmdEngine)
    assert flat.engine.model.q is None
    for name in ("w", "orient", "orient_t"):
        assert getattr(flat.engine.state, name) is None, name
    frame = flat.frame()
    np.testing.assert_array_equal(frame.orientations, np.tile([1.0, 0.0, 0.0, 0.0], (27, 1)))
    assert not np.signbit(frame.orientations).any()
    np.testing.assert_array_equal(frame.angular_velocities, np.zeros((27, 3)))
    assert not np.signbit(frame.angular_velocities).any()
    # a rough law, a spin, or a spin of -0.0 (given back as it was) keep them
    for world in (_rough_gas(), _spin_of_minus_zero()):
        engine = world.build()
        assert isinstance(engine, EdmdEngine)
        assert engine.model.q is not None
        assert engine.state.w is not None
        assert engine.state.orient is not None
    minus = _spin_of_minus_zero()
    minus.run(until=minus.time + 0.5)
    assert np.signbit(minus.angular_velocities[27, 1])


def test_a_turned_body_keeps_its_orientation_in_an_engine_without_spins() -> None:
    # a sphere turned (not the identity) but not spinning, smooth laws: the orientation is
    # state, so the engine keeps orientations (carom.engines.edmd.driver.spinning)
    from carom.bodies import Bodies
    from carom.engines.edmd.driver import spinning

    world = _walled_gas()
    env = environment(world)
    assert not spinning(world.bodies, env)
    for dim, turned in ((3, [0.0, 1.0, 0.0, 0.0]), (3, [-0.0, 0.0, 0.0, 0.0]), (2, [0.5])):
        bodies = Bodies(dim)
        bodies.append_spheres(np.zeros((2, dim)), np.zeros((2, dim)), np.zeros((2, 3)),
                              np.ones(2), np.ones(2), 0.4, 0)  # fmt: skip
        same_env = env._replace(box=np.ones(dim))
        assert not spinning(bodies, same_env)
        orientation = bodies.orientation
        orientation[1] = turned
        bodies.orientation = orientation
        assert spinning(bodies, same_env), turned


@pytest.mark.parametrize(
    "make", [_walled_gas, _galton, _rough_gas], ids=["no gravity", "gravity", "rough, gravity"]
)
def test_a_checkpoint_with_or_without_gravity_resumes_bit_for_bit(make, tmp_path) -> None:  # type: ignore[no-untyped-def]
    # (without gravity the checkpoint holds no acc or support, and without spins no w, orient
    # or orient_t: the state has none)
    straight = make()
    straight.run(until=straight.time + 1.0)
    first = make()
    first.run(until=first.time + 0.5)
    first.save(tmp_path / "mid.npz")
    resumed = carom.World.load(tmp_path / "mid.npz")
    resumed.run(until=straight.time)
    np.testing.assert_array_equal(resumed.positions, straight.positions)
    np.testing.assert_array_equal(resumed.velocities, straight.velocities)
    np.testing.assert_array_equal(resumed.orientations, straight.orientations)
    np.testing.assert_array_equal(resumed.angular_velocities, straight.angular_velocities)


def test_the_bodies_lend_their_motion_to_the_engine_while_it_runs() -> None:
    # the table keeps no positions, velocities, orientations or spins while the engine runs
    # (its own copy would be a stale duplicate: 48 MB at 10^6 spheres in 3D); a read samples
    # the engine, at its clock, and a change to the world takes them back
    world = _rough_gas()
    world.run(until=world.time + 0.5)
    assert world.bodies.lent
    assert world.bodies._position is None
    assert world.bodies._velocity is None
    np.testing.assert_array_equal(world.bodies.position, world.positions)
    np.testing.assert_array_equal(world.bodies.velocity, world.velocities)
    np.testing.assert_array_equal(world.bodies.angular_velocity, world.angular_velocities)
    moved = world.positions
    world.add_spheres([[5.5, 5.5]], radius=0.05)  # the engine is dropped, the motion kept
    assert not world.bodies.lent
    np.testing.assert_array_equal(world.bodies.position[:36], moved)
    world.build()
    one = np.zeros((1, 2))
    with pytest.raises(RuntimeError, match="lent"):  # (the World takes the motion back first)
        world.bodies.append_spheres(one, one, np.zeros((1, 3)), np.ones(1), np.ones(1), 0.4, 0)


def _periodic_gas() -> carom.World:
    return gas(3, 4, 0.3, seed=2)


@pytest.mark.parametrize(
    "make",
    [_walled_gas, _periodic_gas, _galton, _rough_gas],
    ids=["walls", "periodic", "gravity", "rough, gravity"],
)
def test_positions_and_velocities_alone_are_those_of_a_full_sample(make, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # World.positions and .velocities, and the lent table's, sample those two alone
    # (EdmdEngine.sample_motion: loop.write_motion, write_frame's arithmetic): the same bits
    # as a full sample, periodic positions wrapped, under gravity or not, spinning or not
    world = make()
    world.run(until=world.time + 0.5)
    engine = world.engine
    assert isinstance(engine, EdmdEngine)
    x, v, orientation, spin = engine.sample()
    for got, want in (
        (engine.sample_motion(), (x, v)),
        ((world.positions, world.velocities), (x, v)),
    ):
        for a, b in zip(got, want, strict=True):
            assert a.shape == b.shape
            assert a.tobytes() == b.tobytes()  # every bit, signed zeros too
    assert world.bodies.position.tobytes() == x.tobytes()
    assert world.bodies.velocity.tobytes() == v.tobytes()
    # an engine whose bodies never turn or spin is not asked for orientations or spins: the
    # table makes identities and zeros, and stores none of them when saved
    assert engine.spinning == (make is _rough_gas)

    def refused() -> None:
        raise AssertionError("sampled orientations and spins")

    if not engine.spinning:
        monkeypatch.setattr(engine, "sample", refused)
        bodies = world.bodies
        np.testing.assert_array_equal(bodies.orientation, orientation)
        np.testing.assert_array_equal(bodies.angular_velocity, spin)
        assert bodies.unrotated
        assert bodies.still
        stored = bodies.stored_motion()
        assert stored[0].tobytes() == x.tobytes()
        assert stored[1].tobytes() == v.tobytes()
        assert stored[2] is None
        assert stored[3] is None


def test_reading_the_positions_makes_no_orientations_or_spins() -> None:
    # 3D smooth spheres: a full sample is 104 bytes a sphere (position, velocity, quaternion,
    # spin); the positions and velocities alone are 48, and that is all a read allocates
    import tracemalloc

    world = gas(3, 20, 0.3, seed=3)  # 8000 spheres
    world.run(until=world.time + 0.1)
    motion = 2 * world.n_bodies * 3 * 8  # bytes of the positions and velocities
    world.positions  # noqa: B018 (compiled and loaded before measuring)
    tracemalloc.start()
    try:
        positions = world.positions
        _, peak = tracemalloc.get_traced_memory()
    finally:
        tracemalloc.stop()
    assert positions.shape == (8000, 3)
    assert motion <= peak < motion + 64 * 1024  # a full sample would be 2.2x the motion


@pytest.mark.parametrize("failure", ["overlap", "interrupt"])
def test_a_failed_build_gives_the_motion_back_bit_for_bit(failure: str, monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # the build lends the bodies' motion to the engine before it checks overlaps and before
    # its kernels run: if it fails there, the table gets it back as it was (walls: positions
    # are not wrapped)
    world = gas(3, 3, 0.3, seed=2, boundary="walls")
    world.add_spheres(
        [[0.1, 0.1, 0.1]], [[0.5, -0.0, 1.0]], angular_velocities=[[0.0, 0.0, 3.0]], radius=0.01
    )
    if failure == "overlap":
        world.add_spheres([[0.105, 0.1, 0.1]], radius=0.01)
        error: type[BaseException] = carom.CaromError
    else:
        from carom.engines.edmd import loop

        def interrupted(*args: object) -> int:
            raise KeyboardInterrupt

        monkeypatch.setattr(loop, "initialise", interrupted)
        error = KeyboardInterrupt
    before = [np.copy(a) for a in (world.bodies.position, world.bodies.velocity)]
    spins = np.copy(world.bodies.angular_velocity)
    with pytest.raises(error):
        world.build()
    assert world.engine is None
    assert not world.bodies.lent
    for kept, now in zip(before, (world.bodies.position, world.bodies.velocity), strict=True):
        assert kept.tobytes() == now.tobytes()
    assert spins.tobytes() == world.bodies.angular_velocity.tobytes()
    n = world.n_bodies
    np.testing.assert_array_equal(world.bodies.orientation, np.tile([1.0, 0, 0, 0], (n, 1)))


def test_lists_that_overflow_at_the_build_grow_without_changing_a_bit() -> None:
    # 18 neighbours a sphere on the lattice: lists of 4 overflow while the build links them,
    # and grow (4 -> 8 -> 16 -> 32) in the state already filled; the run is the same as from
    # lists that fit at once
    world = gas(3, 4, 0.3, seed=3, e=0.9)
    env, settings = environment(world), world.settings
    tight = EdmdEngine(world.bodies, env, settings, 0.0, capacity=4)
    assert tight.capacity == 32
    roomy = EdmdEngine(world.bodies, env, settings, 0.0)  # (the motion: lent, sampled)
    for engine in (tight, roomy):
        engine.advance(5.0, 1 << 40, None)
    for got, want in zip(tight.sample(), roomy.sample(), strict=True):
        assert got.tobytes() == want.tobytes()
    assert tight.counters().collisions == roomy.counters().collisions > 0
