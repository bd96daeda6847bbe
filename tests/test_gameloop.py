"""Stepping a world by hand (issue 43, item 1): ``World.step(dt=None)``, ``World.steps``.

Stepping by hand and ``run`` take the same engine steps, so they give the same bits at the
same times; another ``dt`` is one step of that length in the rigid engines (free flight in it
exact: the parabola to round-off) and exactly ``dt`` of events in the event-driven engine.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.errors import CaromError
from tests.worlds import rotation

G = 9.81


def _boxes(dim: int) -> carom.World:
    """Three boxes dropped on a floor, turned, so that they hit, slide and come to rest."""
    if dim == 2:
        from carom.shapes import Box

        world = carom.World(2, [10.0, 10.0], gravity=[0.0, -G], boundary="open")
        world.add_body(Box(10.0, 1.0), [5.0, -0.5], kind="static")
        for k in range(3):
            world.add_body(Box(1.0, 0.5), [4.0 + k, 1.0 + 0.8 * k], angle=0.3 * k)
        return world
    from carom.shapes3d import Box as Box3D

    world = carom.World(3, [10.0] * 3, gravity=[0.0, 0.0, -G], boundary="open")
    world.add_body(Box3D([10.0, 10.0, 1.0]), [5.0, 5.0, -0.5], kind="static")
    for k in range(3):
        half = 0.15 * k
        turn = [math.cos(half), math.sin(half), 0.0, 0.0]
        world.add_body(Box3D([1.0, 0.5, 0.3]), [4.0 + k, 5.0, 1.0 + 0.8 * k], orientation=turn)
    return world


@pytest.mark.parametrize("dim", [2, 3])
def test_stepping_by_hand_gives_the_bits_of_a_run(dim: int) -> None:
    by_hand, run = _boxes(dim), _boxes(dim)
    for _ in range(90):
        by_hand.step()
    run.run(until=90 / 60)
    assert by_hand.steps == run.steps == 90
    assert by_hand.time == run.time
    for read in ("positions", "velocities", "orientations", "angular_velocities"):
        np.testing.assert_array_equal(getattr(by_hand, read), getattr(run, read), err_msg=read)
    # and on from there, mixed: a run after steps by hand is the same run
    by_hand.run(until=2.0)
    run.run(until=2.0)
    np.testing.assert_array_equal(by_hand.positions, run.positions)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_step_of_another_length_is_one_step_of_it(dim: int) -> None:
    world = _boxes(dim)
    start = world.positions.copy()
    world.step(0.01)
    assert world.steps == 1
    assert world.time == 0.01
    # free fall over the step, exact: z = z0 - g t^2 / 2, to round-off of z0 (a few ulps)
    fall = start[1:, -1] - 0.5 * G * 0.01**2
    np.testing.assert_allclose(world.positions[1:, -1], fall, rtol=0, atol=4e-16 * 3)
    np.testing.assert_allclose(world.velocities[1:, -1], -G * 0.01, rtol=1e-15)
    # later steps are whole steps from there
    world.step()
    world.step()
    assert world.steps == 3
    assert world.time == pytest.approx(0.01 + 2 / 60, rel=1e-15)


def test_the_event_driven_engine_steps_exactly_dt_and_needs_one() -> None:
    world = carom.World(2, box=[1.0, 1.0])
    world.add_spheres([[0.3, 0.5], [0.7, 0.5]], [[1.0, 0.0], [-1.0, 0.0]], radius=0.05)
    with pytest.raises(CaromError, match="no step of its own"):
        world.step()
    assert world.time == 0.0
    assert world.steps == 0
    # the gap of 0.3 m closes at 2 m/s: the impact at 0.15 s, inside the second step
    world.step(0.1)
    np.testing.assert_array_equal(world.velocities, [[1.0, 0.0], [-1.0, 0.0]])
    world.step(0.1)
    assert world.steps == 2
    assert world.time == pytest.approx(0.2, rel=1e-15)
    # equal masses, elastic: the velocities exchanged, and each ball 0.05 s back from contact
    np.testing.assert_array_equal(world.velocities, [[-1.0, 0.0], [1.0, 0.0]])
    np.testing.assert_allclose(world.positions[:, 0], [0.40, 0.60], rtol=0, atol=1e-15)


@pytest.mark.parametrize(
    "dt", [0.0, -0.01, math.nan, math.inf, "0.01", True, None, 1e-12, 1e300], ids=repr
)
def test_a_step_that_cannot_be_taken_is_refused_and_nothing_moves(dt: object) -> None:
    world = _boxes(2)
    world.step()
    before = world.positions.copy(), world.time, world.steps
    if dt is None:  # a step of its own is fine in the rigid engine: refused in the other
        world = carom.World(2, box=[1.0, 1.0])
        world.add_spheres([[0.5, 0.5]], [[1.0, 0.0]], radius=0.05)
        before = world.positions.copy(), world.time, world.steps
    with pytest.raises(CaromError, match=r"dt|step"):
        world.step(dt)  # type: ignore[arg-type]
    np.testing.assert_array_equal(world.positions, before[0])
    assert (world.time, world.steps) == before[1:]


# -- reaching a body between steps (issue 43, item 2) -------------------------------------


def _free_box(dim: int, gravity: bool = False) -> carom.World:
    """One box alone, open boundary: its free flight between impulses is exact."""
    g = -G if gravity else 0.0
    if dim == 2:
        from carom.shapes import Box

        world = carom.World(2, [10.0, 10.0], gravity=[0.0, g], boundary="open")
        world.add_body(Box(2.0, 1.0), [5.0, 5.0], angle=0.4)
        return world
    from carom.shapes3d import Box as Box3D

    world = carom.World(3, [10.0] * 3, gravity=[0.0, 0.0, g], boundary="open")
    turn = [math.cos(0.2), 0.6 * math.sin(0.2), 0.8 * math.sin(0.2), 0.0]
    world.add_body(Box3D([2.0, 1.0, 0.5]), [5.0, 5.0, 5.0], orientation=turn)
    return world


def test_an_impulse_at_a_point_changes_momentum_and_angular_momentum_by_it_2d() -> None:
    world = _free_box(2)
    body = world.body(0)
    mass, inertia = world.masses[0], (2.0**2 + 1.0**2) / 12 * world.masses[0]
    j, point = np.array([0.3, -1.2]), np.array([5.7, 4.6])
    body.apply_impulse(j, point)
    # Newton for an impulse: m dv = J, I dw = (p - x) x J (from rest), to round-off
    np.testing.assert_allclose(mass * body.velocity, j, rtol=1e-15)
    r = point - 5.0
    assert inertia * body.angular_velocity == pytest.approx(r[0] * j[1] - r[1] * j[0], rel=1e-15)
    # then free flight, exact: the angle turns at that spin
    spin = body.angular_velocity
    world.run(until=0.5)
    assert body.angle == pytest.approx(0.4 + spin * 0.5, rel=1e-14)
    np.testing.assert_allclose(body.position, 5.0 + j / mass * 0.5, rtol=1e-14)


def test_an_impulse_at_a_point_changes_angular_momentum_by_r_cross_j_in_3d() -> None:
    world = _free_box(3)
    body = world.body(0)
    j, point = np.array([0.3, -1.2, 0.7]), np.array([5.8, 4.7, 5.2])
    body.apply_impulse(j, point)
    np.testing.assert_allclose(world.masses[0] * body.velocity, j, rtol=1e-15)
    # the angular momentum about the centre, I_world w, is r x J: I_world = R I_body R^T
    # with the box's principal moments m (b^2 + c^2) / 12 ...
    rot = rotation(body.orientation)
    sides = np.array([2.0, 1.0, 0.5])
    moments = world.masses[0] * (np.sum(sides**2) - sides**2) / 12
    momentum = rot @ (moments * (rot.T @ body.angular_velocity))
    np.testing.assert_allclose(momentum, np.cross(point - 5.0, j), rtol=1e-14, atol=1e-16)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_body_kicked_in_flight_follows_the_new_parabola(dim: int) -> None:
    world = _free_box(dim, gravity=True)
    for _ in range(12):
        world.step()
    body = world.body(0)
    x0, t0 = body.position, world.time
    body.velocity = np.r_[np.zeros(dim - 1), 0.0] + np.r_[[2.0] * (dim - 1), 3.0]
    v0 = body.velocity
    for _ in range(30):
        world.step()
    t = world.time - t0
    down = np.zeros(dim)
    down[-1] = -G
    # x0 + v0 t + g t^2 / 2, to round-off of the position's size (free flight is exact)
    np.testing.assert_allclose(body.position, x0 + v0 * t + 0.5 * down * t**2, rtol=0, atol=1e-14)


@pytest.mark.parametrize("dim", [2, 3])
def test_the_ledger_closes_across_kicks_and_impacts(dim: int) -> None:
    world = _boxes(dim)
    e0 = world.build().energy()  # type: ignore[attr-defined]
    for k in range(120):
        if k % 20 == 5:
            world.apply_impulses([1, 2, 3], [[1.0] + [0.0] * (dim - 1)] * 3)
        if k == 50:
            world.set_velocities([2], [0.0] * (dim - 1) + [4.0])
        world.step()
    c = world.counters()
    e = world.engine.energy()  # type: ignore[union-attr]
    # E0 + work done = E + lost - given (the kicks are work done on the bodies), to round-off:
    # 120 steps of three bodies, each keeping its energy to a few ulps a step (3D: the
    # torque-free turn), 1e-11 of the energies bounds 120 x 3 x 1e-14 with room
    scale = e0 + abs(c.work_done)
    assert abs(e0 + c.work_done - (e + c.energy_lost - c.energy_given)) < 1e-11 * scale
    assert c.work_done != 0.0


def test_many_at_once_are_the_bits_of_one_at_a_time() -> None:
    one, many = _boxes(3), _boxes(3)
    for world in (one, many):
        world.step()
    kicks = np.array([[0.5, 0.0, 1.0], [0.0, -0.2, 0.3], [0.1, 0.1, 0.1]])
    at = one.positions[1:] + 0.1
    for k, i in enumerate([1, 2, 3]):
        one.body(i).apply_impulse(kicks[k], at[k])
    many.apply_impulses([1, 2, 3], kicks, at)
    np.testing.assert_array_equal(one.velocities, many.velocities)
    np.testing.assert_array_equal(one.angular_velocities, many.angular_velocities)


@pytest.mark.parametrize(
    "push",
    [
        lambda box: box.apply_impulse([2.0, 0.0]),
        lambda box: box.apply_force([500.0, 0.0]),  # (a force through the next step)
    ],
    ids=["impulse", "force"],
)
def test_a_push_wakes_a_sleeping_box(push: object) -> None:
    from carom.shapes import Box

    world = carom.World(2, [10.0, 10.0], gravity=[0.0, -G], boundary="open")
    world.add_body(Box(10.0, 1.0), [5.0, -0.5], kind="static")
    world.add_body(Box(1.0, 1.0), [5.0, 0.5])
    world.run(until=2.0)
    box = world.body(1)
    assert not box.awake
    push(box)  # type: ignore[operator]
    assert box.awake
    world.step()
    assert box.position[0] > 5.0


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda w: w.body(7), "body 7 is not in the world"),
        (lambda w: w.body(True), "whole number"),
        (lambda w: w.body(0).apply_impulse([1.0, 0.0]), "body 0 is static"),
        (lambda w: w.body(1).apply_impulse([math.nan, 0.0]), "finite"),
        (lambda w: w.body(1).apply_impulse([1.0, 0.0, 0.0]), "shape"),
        (lambda w: w.apply_impulses([1, 9], [1.0, 0.0]), "body 9"),
        (lambda w: w.apply_impulses([1.5], [1.0, 0.0]), "ids"),
        (lambda w: w.set_velocities([1, 2], [[1.0, 0.0]] * 3), "shape"),
        (lambda w: setattr(w.body(1), "orientation", [1.0, 0, 0, 0]), "3D body"),
        (lambda w: setattr(w.body(1), "angle", 1e300), "limits"),
    ],
)
def test_a_wrong_reach_is_refused_and_changes_nothing(call: object, match: str) -> None:
    world = _boxes(2)
    world.step()
    before = world.positions.copy(), world.velocities.copy(), world.counters().work_done
    with pytest.raises(CaromError, match=match):
        call(world)  # type: ignore[operator]
    np.testing.assert_array_equal(world.positions, before[0])
    np.testing.assert_array_equal(world.velocities, before[1])
    assert world.counters().work_done == before[2]


def test_a_3d_orientation_must_be_a_unit_quaternion() -> None:
    world = _free_box(3)
    with pytest.raises(CaromError, match="unit quaternion"):
        world.body(0).orientation = [1.0, 1.0, 0.0, 0.0]
    world.body(0).orientation = [0.0, 0.0, 0.0, 1.0]
    np.testing.assert_array_equal(world.orientations[0], [0.0, 0.0, 0.0, 1.0])


def test_the_event_driven_engine_says_what_it_does_not_take_yet() -> None:
    # (what it takes: tests/test_gameloop_edmd.py, tests/test_gameloop_edmd_forces.py)
    world = carom.World(2, box=[1.0, 1.0])
    world.add_spheres([[0.5, 0.5]], [[1.0, 0.0]], radius=0.05)
    with pytest.raises(CaromError, match="a torque through a step is the rigid engines'"):
        world.body(0).apply_torque(1.0)
    with pytest.raises(CaromError, match="a force off a sphere's centre through a step"):
        world.body(0).apply_force([1.0, 0.0], point=[0.5, 0.55])


@pytest.mark.parametrize("dim", [2, 3])
def test_positions_and_spins_set_for_many_are_those_set_one_at_a_time(dim: int) -> None:
    one, many = _boxes(dim), _boxes(dim)
    for world in (one, many):
        world.step()
    places = one.positions[1:] + np.r_[[0.5] * (dim - 1), 1.0]
    spins = np.array([0.5, -1.0, 2.0]) if dim == 2 else np.array([[0.5, 0.0, 1.0]] * 3)
    for k, i in enumerate([1, 2, 3]):
        one.body(i).position = places[k]
        one.body(i).angular_velocity = spins[k]
    many.set_positions([1, 2, 3], places)
    many.set_angular_velocities([1, 2, 3], spins)
    np.testing.assert_array_equal(one.positions, many.positions)
    np.testing.assert_array_equal(one.angular_velocities, many.angular_velocities)
    # raised 1 m and spun, they then move alike: the same bits 30 steps on, and what the hand
    # gave (potential and kinetic energy) booked as work done in both
    for world in (one, many):
        for _ in range(30):
            world.step()
    np.testing.assert_array_equal(one.positions, many.positions)
    # (booked per body against all at once: the same sum in another order, to round-off)
    assert one.counters().work_done > 0.0
    assert one.counters().work_done == pytest.approx(many.counters().work_done, rel=1e-14)
