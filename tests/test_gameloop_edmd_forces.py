"""Forces through a step in the event-driven engine (issue 43, item 2).

A force F on a sphere of mass m acts through the next ``World.step`` and is then cleared: the
sphere flies the parabola of ``g + F / m`` for the step, exactly as under gravity, then that of
``g``. Every expected value is that closed form, ``x0 + v0 t + a t^2 / 2``; the engine flies a
sphere with ``x += (v + a t / 2) t`` from the clock at which the force was given, the same
arithmetic, so a few ulps of the coordinates (1e-12 m at coordinates of a few metres) bound the
error. The work a force does is ``F . (x1 - x0)`` over the step, and the ledger closes with it.
"""

from __future__ import annotations

import numpy as np
import pytest

import carom
from carom.errors import CaromError

G = np.array([0.0, 0.0, -9.81])
ULPS = 1e-12  # [m], [m/s]: a few ulps of coordinates and speeds of order 1-10
DT = 0.1  # [s]


def _world(gravity: np.ndarray | None = None, boundary: str = "walls") -> carom.World:
    return carom.World(
        3, [10.0, 10.0, 10.0], gravity=gravity, boundary=boundary, engine="event-driven"
    )


def test_a_force_from_rest_without_gravity_gives_the_parabola_then_a_line() -> None:
    world = _world()
    world.add_spheres([[5.0, 5.0, 5.0], [2.0, 2.0, 2.0]], radius=0.5, mass=2.0)
    world.step(DT)  # built without gravity: no accelerations kept until a force acts
    ball = world.body(0)
    world.apply_forces([0], [1.0, -0.5, 0.25])
    world.step(DT)
    a = np.array([1.0, -0.5, 0.25]) / 2.0  # F / m [m/s^2]
    x1 = np.array([5.0, 5.0, 5.0]) + 0.5 * a * DT * DT
    np.testing.assert_allclose(ball.position, x1, atol=ULPS)
    np.testing.assert_allclose(ball.velocity, a * DT, atol=ULPS)
    world.step(DT)  # the force is cleared: a straight line at the speed it gave
    np.testing.assert_allclose(ball.position, x1 + a * DT * DT, atol=ULPS)
    np.testing.assert_allclose(ball.velocity, a * DT, atol=ULPS)
    # the work F . dx = m a . (a dt^2 / 2) is the kinetic energy m (a dt)^2 / 2 it gave
    assert world.counters().work_done == pytest.approx(0.5 * 2.0 * np.sum((a * DT) ** 2))
    np.testing.assert_array_equal(world.body(1).position, [2.0, 2.0, 2.0])


def test_a_force_in_flight_under_gravity_adds_to_it_for_one_step() -> None:
    world = _world(G)
    world.add_spheres([[5.0, 5.0, 6.0]], [[1.0, 0.0, 2.0]], radius=0.1, mass=0.5)
    world.step(DT)
    ball = world.body(0)
    x0, v0 = ball.position, ball.velocity
    force = np.array([0.0, 1.5, 3.0])
    ball.apply_force(force)
    world.step(DT)
    a = G + force / 0.5
    x1, v1 = x0 + v0 * DT + 0.5 * a * DT * DT, v0 + a * DT
    np.testing.assert_allclose(ball.position, x1, atol=ULPS)
    np.testing.assert_allclose(ball.velocity, v1, atol=ULPS)
    world.step(DT)
    np.testing.assert_allclose(ball.position, x1 + v1 * DT + 0.5 * G * DT * DT, atol=ULPS)
    np.testing.assert_allclose(ball.velocity, v1 + G * DT, atol=ULPS)


def test_a_resting_ball_pushed_along_the_floor_slides_and_stays_on_it() -> None:
    world = _world(G)
    world.add_spheres([[5.0, 5.0, 0.1]], radius=0.1)  # on the floor, at rest (1 kg)
    world.step(0.2)
    assert world.engine is not None
    assert world.engine.resting()[0] == 4  # (face 4: the floor z = 0)
    ball = world.body(0)
    world.apply_forces([0], [[2.0, 0.0, -5.0]])  # along the floor, and pressing into it
    world.step(DT)
    # the floor bears the normal part (gravity's and the push's): a = (2, 0, 0) m/s^2
    np.testing.assert_allclose(ball.position, [5.0 + 0.5 * 2.0 * DT * DT, 5.0, 0.1], atol=ULPS)
    np.testing.assert_allclose(ball.velocity, [2.0 * DT, 0.0, 0.0], atol=ULPS)
    assert world.engine.resting()[0] == 4
    world.step(DT)  # then it slides on at that speed (smooth floor)
    np.testing.assert_allclose(ball.position, [5.0 + 0.01 + 0.2 * DT, 5.0, 0.1], atol=ULPS)
    assert world.engine.resting()[0] == 4


def test_a_force_stronger_than_gravity_lifts_a_resting_ball() -> None:
    world = _world(G)
    world.add_spheres([[5.0, 5.0, 0.1]], radius=0.1)
    world.step(0.2)
    ball = world.body(0)
    ball.apply_force([0.0, 0.0, 20.0])  # 20 N up on 1 kg: a = 20 - 9.81 m/s^2 up
    world.step(DT)
    a_up = 20.0 - 9.81
    z1, w1 = 0.1 + 0.5 * a_up * DT * DT, a_up * DT
    np.testing.assert_allclose(ball.position, [5.0, 5.0, z1], atol=ULPS)
    np.testing.assert_allclose(ball.velocity, [0.0, 0.0, w1], atol=ULPS)
    assert world.engine is not None
    assert world.engine.resting()[0] == -1
    world.step(DT)  # flying under gravity alone
    np.testing.assert_allclose(ball.position[2], z1 + w1 * DT - 0.5 * 9.81 * DT * DT, atol=ULPS)


@pytest.mark.parametrize("boundary", ["walls", "periodic"])
def test_the_ledger_closes_with_forces_and_inelastic_impacts(boundary: str) -> None:
    # a sphere driven hard through a gas (wrapping round the periodic box several times),
    # others pushed at random: E0 + work = E + lost - given, the work F . dx of every force
    rng = np.random.default_rng(11)
    gravity = G if boundary == "walls" else None
    world = carom.World(3, [2.0, 2.0, 2.0], gravity=gravity, boundary=boundary,
                        engine="event-driven")  # fmt: skip
    world.add_spheres(rng.uniform(0.2, 1.8, (30, 3)), rng.normal(0, 2, (30, 3)), radius=0.03,
                      restitution=0.8)  # fmt: skip
    g = np.zeros(3) if gravity is None else gravity

    def energy() -> float:  # kinetic and potential [J], unit masses, no spins
        return float(0.5 * np.sum(world.velocities**2) - np.sum(world.positions @ g))

    e0 = energy()
    for k in range(60):
        world.apply_forces([0, 1 + k % 29], [[30.0, 5.0, 0.0], rng.normal(0, 5, 3)])
        world.step(1 / 60)
    c = world.counters()
    assert c.collisions > 0
    assert c.energy_lost > 0
    if boundary == "periodic":
        engine = world.engine
        assert engine is not None
        assert np.abs(engine.state.wraps).max() >= 2  # (it went round the box)
    # each event keeps ~100 J to a few ulps; ~1000 events: 1e-11 relative with room
    scale = e0 + abs(c.work_done)
    assert abs(e0 + c.work_done - (energy() + c.energy_lost - c.energy_given)) < 1e-11 * scale
    assert c.work_done > 0.0


def test_reruns_with_forces_are_bit_identical_and_renumbering_changes_nothing() -> None:
    def run(renumber_every: int) -> np.ndarray:
        rng = np.random.default_rng(7)
        world = carom.World(3, [4.0, 4.0, 4.0], gravity=G, engine="event-driven")
        lattice = np.stack(np.meshgrid(*[np.arange(12)] * 2, np.arange(2)), -1).reshape(-1, 3)
        at = 0.3 + 0.3 * lattice[:200] + [0.0, 0.0, 1.5]  # 0.3 m apart: none overlaps
        world.add_spheres(at, rng.normal(0, 1, (200, 3)), radius=0.05, restitution=0.9)
        world.step(1 / 60)
        assert world.engine is not None
        world.engine.renumber_every = renumber_every  # (a gas this small never renumbers)
        for k in range(30):
            world.apply_forces(np.arange(k % 20, 200, 7), [0.0, 3.0, 15.0])
            world.step(1 / 60)
        assert (world.engine._renumbered_at > 0) == (renumber_every > 0)  # (it renumbered)
        return np.concatenate((world.positions.ravel(), world.velocities.ravel()))

    plain = run(0)
    assert plain.tobytes() == run(0).tobytes()
    # renumbered every 50 events, mid-step: the rows the forces were given to move, and the
    # same bodies lose them at the step's end (only events at equal times may reorder)
    assert run(50).tobytes() == plain.tobytes()


def test_forces_given_before_the_engine_is_built_again_act_on_the_next_step() -> None:
    world = _world()
    world.add_spheres([[5.0, 5.0, 5.0]], radius=0.5)
    world.step(DT)
    world.apply_forces([0], [4.0, 0.0, 0.0])
    world.add_spheres([[2.0, 2.0, 2.0]], radius=0.5)  # (the engine is built again)
    world.step(DT)
    np.testing.assert_allclose(world.body(0).velocity, [4.0 * DT, 0.0, 0.0], atol=ULPS)


def test_a_checkpoint_between_forced_steps_continues_bit_for_bit(tmp_path) -> None:  # type: ignore[no-untyped-def]
    def start() -> carom.World:
        rng = np.random.default_rng(5)
        world = carom.World(3, [2.0, 2.0, 2.0], boundary="periodic", engine="event-driven")
        world.add_spheres(rng.uniform(0.2, 1.8, (30, 3)), rng.normal(0, 2, (30, 3)),
                          radius=0.03, restitution=0.8)  # fmt: skip
        for _ in range(10):
            world.apply_forces([3], [20.0, 0.0, 0.0])
            world.step(1 / 60)
        return world

    def finish(world: carom.World) -> carom.World:
        for _ in range(10):
            world.apply_forces([3], [0.0, 20.0, 0.0])
            world.step(1 / 60)
        return world

    world = start()
    world.save(tmp_path / "forced.npz")
    loaded = carom.World.load(tmp_path / "forced.npz")
    straight = finish(world)
    again = finish(loaded)
    assert again.positions.tobytes() == straight.positions.tobytes()
    assert again.counters().work_done == straight.counters().work_done


def test_torques_and_forces_off_centre_are_refused_and_change_nothing() -> None:
    world = _world()
    world.add_spheres([[1.0, 1.0, 1.0], [2.0, 1.0, 1.0]], [[0.5, 0, 0], [0, 0, 0]], radius=0.2)
    world.add_static_spheres([[3.0, 3.0, 3.0]], radius=0.2)
    world.step(0.1)
    before = world.positions.copy(), world.velocities.copy()
    with pytest.raises(CaromError, match="keep their spin between impacts"):
        world.apply_torques([0], [0.0, 0.0, 1.0])
    with pytest.raises(CaromError, match="off a sphere's centre"):
        world.apply_forces([0], [0.0, 1.0, 0.0], points=[[1.25, 1.0, 1.0]])
    with pytest.raises(CaromError, match="static"):
        world.apply_forces([2], [1.0, 0.0, 0.0])
    with pytest.raises(CaromError, match="finite"):
        world.apply_forces([0], [np.nan, 0.0, 0.0])
    world.step(0.1)  # (no force was kept: both fly on at their speeds)
    np.testing.assert_allclose(world.positions[:2], before[0][:2] + before[1][:2] * 0.1,
                               atol=ULPS)  # fmt: skip
    # a force at a point on its line through the centre turns nothing: taken
    world.apply_forces([1], [1.0, 0.0, 0.0], points=[[2.5, 1.0, 1.0]])
    world.step(0.1)
    assert world.velocities[1, 0] > 0.0


def test_forces_wait_through_a_run_for_the_next_step() -> None:
    # the engine has no step of its own: a force acts through the next World.step(dt)
    world = _world()
    world.add_spheres([[5.0, 5.0, 5.0]], radius=0.5)  # 1 kg: dv = F dt
    world.apply_forces([0], [1.0, 0.0, 0.0])
    world.run(until=0.5)
    np.testing.assert_array_equal(world.velocities[0], [0.0, 0.0, 0.0])
    world.step(DT)
    np.testing.assert_allclose(world.velocities[0], [DT, 0.0, 0.0], atol=ULPS)
