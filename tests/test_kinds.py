"""Switching a body's kind between steps (issue 43, item 2): ``World.set_kind`` and
``Body.kind``.

Expected values are closed forms: free fall from rest ``y0 - g t^2 / 2`` and uniform motion
``x0 + v t``, which the rigid engine's free flight evaluates exactly (to a few ulps of the
coordinates: 1e-12 m here); a box's mass ``rho w h`` and moment ``m (w^2 + h^2) / 12`` (a
cuboid's ``m (b^2 + c^2) / 12`` about each axis); the energy ledger
``E0 + work = E + lost - given`` to round-off.
"""

from __future__ import annotations

import numpy as np
import pytest

import carom
from carom import joints
from carom.errors import CaromError
from carom.shapes import Box, Circle, Segment
from carom.shapes3d import Box as Box3D

G = 9.81
DT = 1.0 / 60.0


def _world(dim: int = 2) -> carom.World:
    gravity = [0.0, -G] if dim == 2 else [0.0, 0.0, -G]
    return carom.World(dim, [20.0] * dim, gravity=gravity, boundary="open", engine="rigid")


def test_a_body_made_static_stops_and_holds_what_lands_on_it() -> None:
    world = _world()
    crate = world.add_body(Box(2.0, 1.0), [5.0, 5.0])
    for _ in range(10):
        world.step()
    world.body(crate).kind = "static"
    assert world.body(crate).kind == "static"
    held = world.positions[crate].copy()
    ball = world.add_body(Circle(0.25), [5.0, 7.0], restitution=0.0)
    for _ in range(120):
        world.step()
    assert world.positions[crate].tobytes() == held.tobytes()
    np.testing.assert_array_equal(world.velocities[crate], [0.0, 0.0])
    # the ball rests on the crate's top (y = held + 0.5) at its radius, within the solver's
    # slop (the soft contacts rest a little inside: linear_slop, 5 mm)
    assert abs(world.positions[ball][1] - (held[1] + 0.5 + 0.25)) < 5e-3
    assert abs(world.velocities[ball][1]) < 1e-3


def test_a_static_body_made_dynamic_falls_freely() -> None:
    world = _world()
    shelf = world.add_body(Box(2.0, 0.5), [5.0, 10.0], kind="static")
    for _ in range(5):
        world.step()
    world.set_kind(shelf, "dynamic", density=2.0)
    # mass rho w h, moment m (w^2 + h^2) / 12
    assert world.bodies.mass[shelf] == pytest.approx(2.0 * 2.0 * 0.5, rel=1e-15)
    assert world.bodies.inertia[shelf] == pytest.approx(2.0 * (4.0 + 0.25) / 12, rel=1e-14)
    for n in range(1, 31):
        world.step()
        t = n * DT
        np.testing.assert_allclose(world.positions[shelf], [5.0, 10.0 - 0.5 * G * t * t],
                                   atol=1e-12, rtol=0)  # fmt: skip


def test_a_body_made_kinematic_keeps_its_velocity_whatever_pulls_it() -> None:
    world = _world()
    paddle = world.add_body(Box(1.0, 0.2), [5.0, 10.0], velocity=[2.0, 1.0])
    world.step()
    x0, v0 = world.positions[paddle].copy(), world.velocities[paddle].copy()
    world.body(paddle).kind = "kinematic"
    for n in range(1, 31):
        world.step()
        np.testing.assert_allclose(world.positions[paddle], x0 + v0 * n * DT, atol=1e-12)
    np.testing.assert_array_equal(world.velocities[paddle], v0)


def test_a_body_made_dynamic_again_takes_the_mass_it_had() -> None:
    world = _world()
    body = world.add_body(Box(1.0, 1.0), [5.0, 5.0], mass=3.0)
    inertia = float(world.bodies.inertia[body])
    world.step()
    world.set_kind(body, "static")
    assert np.isinf(world.bodies.mass[body])
    world.step()
    world.set_kind(body, "dynamic")
    assert world.bodies.mass[body] == 3.0
    assert world.bodies.inertia[body] == inertia
    # given a mass, it takes that one
    world.set_kind(body, "kinematic")
    world.set_kind(body, "dynamic", mass=5.0)
    assert world.bodies.mass[body] == pytest.approx(5.0, rel=1e-15)


def test_a_3d_box_made_dynamic_takes_the_cuboids_tensor() -> None:
    world = _world(3)
    block = world.add_body(Box3D([1.0, 2.0, 3.0]), [5.0, 5.0, 5.0], kind="static")
    world.step()
    world.set_kind(block, "dynamic", mass=6.0)
    tensor = world.bodies.inertia_tensor[block]
    # m (b^2 + c^2) / 12 about x, m (a^2 + c^2) / 12 about y, m (a^2 + b^2) / 12 about z
    np.testing.assert_allclose(np.diag(tensor), [6.5, 5.0, 2.5], rtol=1e-14)
    for n in range(1, 11):
        world.step()
        z = 5.0 - 0.5 * G * (n * DT) ** 2
        np.testing.assert_allclose(world.positions[block], [5.0, 5.0, z], atol=1e-12, rtol=0)


@pytest.mark.parametrize("dim", [2, 3])
def test_the_ledger_closes_across_switches(dim: int) -> None:
    world = _world(dim)
    shape = Box(1.0, 1.0) if dim == 2 else Box3D([1.0, 1.0, 1.0])
    floor = Box(20.0, 1.0) if dim == 2 else Box3D([20.0, 20.0, 1.0])
    world.add_body(floor, [10.0, 0.5] if dim == 2 else [10.0, 10.0, 0.5], kind="static")
    at = [[5.0, 4.0], [5.2, 6.0], [8.0, 3.0]]
    ids = [world.add_body(shape, p if dim == 2 else [*p[:1], 10.0, p[1]]) for p in at]
    e0 = world.build().energy()  # type: ignore[attr-defined]
    for k in range(150):  # (landed and at rest by step 60)
        if k == 30:
            world.set_kind(ids[1], "kinematic")  # falling: it falls on through all
        if k == 70:
            world.set_kind(ids[0], "kinematic")
        if k == 90:
            world.set_kind(ids[2], "static")
        if k == 110:
            world.set_kind([ids[0], ids[2]], "dynamic")
        world.step()
    c = world.counters()
    e = world.engine.energy()  # type: ignore[union-attr]
    assert c.work_done != 0.0
    # 150 steps of three bodies, each step keeping the energies (~100 J) to a few ulps
    scale = abs(e0) + abs(c.work_done) + c.energy_lost
    assert abs(e0 + c.work_done - (e + c.energy_lost - c.energy_given)) < 1e-11 * scale


def test_joints_filters_and_removals_survive_a_switch() -> None:
    world = _world()
    a = world.add_body(Box(1.0, 1.0), [5.0, 10.0])
    b = world.add_body(Box(1.0, 1.0), [7.0, 10.0])
    c = world.add_body(Box(1.0, 1.0), [12.0, 10.0])
    world.add_joint(joints.Revolute(None, a, [5.0, 11.0]))
    world.set_filter(b, group=-3)
    world.remove_body(c)
    world.step()
    world.set_kind(b, "kinematic")
    for _ in range(30):
        world.step()
    assert world.n_joints == 1
    # the pendulum hangs from its pin: its centre stays 1 m from it (the soft joint's drift)
    assert abs(np.linalg.norm(world.positions[a] - [5.0, 11.0]) - 1.0) < 1e-3
    assert world.collision_filters[b, 2] == -3
    assert not world.alive[c]
    np.testing.assert_array_equal(world.positions[c], [12.0, 10.0])  # (removed before a step)


def test_forces_given_before_a_rebuild_act_in_the_next_step() -> None:
    # switching a kind (or adding a body) builds the engine again: the force given for the
    # next step still acts in it, dv = (F / m - g) dt
    world = _world()
    a = world.add_body(Box(1.0, 1.0), [5.0, 5.0])  # 1 kg
    b = world.add_body(Box(1.0, 1.0), [8.0, 5.0])
    world.step()
    v0 = world.velocities[a].copy()
    world.apply_forces([a], [0.0, 30.0])
    world.set_kind(b, "kinematic")
    world.step()
    np.testing.assert_allclose(world.velocities[a] - v0, [0.0, (30.0 - G) * DT], atol=1e-14)
    world.step()  # then cleared
    np.testing.assert_allclose(world.velocities[a] - v0, [0.0, (30.0 - 2 * G) * DT], atol=1e-14)


def test_a_refused_switch_keeps_the_forces_given_once() -> None:
    world = _world()
    a = world.add_body(Box(1.0, 1.0), [5.0, 5.0])  # 1 kg
    world.add_body(Box(1.0, 1.0), [9.0, 5.0], kind="static")
    inside = world.add_body(Box(1.0, 1.0), [9.2, 5.0], kind="static")
    world.step()
    v0 = world.velocities[a].copy()
    world.apply_forces([a], [0.0, 30.0])
    with pytest.raises(CaromError, match="overlap"):
        world.set_kind(inside, "dynamic")
    world.step()  # the force acts once: dv = (F / m - g) dt
    np.testing.assert_allclose(world.velocities[a] - v0, [0.0, (30.0 - G) * DT], atol=1e-14)
    world.add_body(Circle(0.1), [2.0, 2.0])  # a rebuild later adds nothing
    world.step()
    np.testing.assert_allclose(world.velocities[a] - v0, [0.0, (30.0 - 2 * G) * DT], atol=1e-14)


def test_bad_switches_are_refused_and_change_nothing() -> None:
    world = _world()
    box = world.add_body(Box(1.0, 1.0), [5.0, 5.0])
    line = world.add_body(Segment([0.0, 0.0], [2.0, 0.0]), [2.0, 2.0], kind="static")
    world.step()
    engine, before = world.engine, world.positions.copy()
    with pytest.raises(CaromError, match="kind must be one of"):
        world.set_kind(box, "frozen")
    with pytest.raises(CaromError, match="static only"):
        world.set_kind(line, "dynamic")
    with pytest.raises(CaromError, match="no mass"):
        world.set_kind(box, "static", mass=2.0)
    with pytest.raises(CaromError, match="density"):
        world.set_kind(box, "dynamic", density=-1.0)
    with pytest.raises(CaromError, match="not in the world"):
        world.set_kind(9, "static")
    assert world.engine is engine
    # made dynamic deep inside another body: the rebuilt engine refuses, the old one stays
    world.add_body(Box(1.0, 1.0), [9.0, 5.0], kind="static")
    inside = world.add_body(Box(1.0, 1.0), [9.2, 5.0], kind="static")
    world.step()
    engine, before, kinds = world.engine, world.positions.copy(), world.bodies.kind.copy()
    with pytest.raises(CaromError, match="overlap"):
        world.set_kind(inside, "dynamic")
    assert world.engine is engine
    assert world.positions.tobytes() == before.tobytes()
    assert world.bodies.kind.tobytes() == kinds.tobytes()
    world.set_kind(box, "dynamic")  # already: nothing to do, the engine stays
    assert world.engine is engine
    assert world.body(box).kind == "dynamic"
    world.step()  # and steps on
    spheres = carom.World(2, [1.0, 1.0], engine="event-driven")
    spheres.add_spheres([[0.5, 0.5]], [[0.3, 0.0]], radius=0.1)
    spheres.step(0.1)
    engine, before = spheres.engine, spheres.positions.copy()
    with pytest.raises(CaromError, match="dynamic or static"):
        spheres.set_kind(0, "kinematic")
    assert spheres.engine is engine
    assert spheres.positions.tobytes() == before.tobytes()
    assert spheres.body(0).kind == "dynamic"


G3 = np.array([0.0, 0.0, -9.81])


def test_event_driven_spheres_made_static_stop_and_made_dynamic_fall_from_rest() -> None:
    # closed forms: free flight x0 + v t + g t^2 / 2 (the engine's own arithmetic: a few ulps)
    world = carom.World(3, [4.0, 4.0, 4.0], gravity=G3, engine="event-driven")
    world.add_spheres([[1.0, 2.0, 2.0], [2.2, 2.0, 2.0]], [[0.5, 0.0, 1.0], [-5.0, 0.0, 0.0]],
                      radius=0.2, mass=2.0)  # fmt: skip
    e0 = _ledger_energy(world)
    world.step(0.1)
    world.body(0).kind = "static"
    x_stop = world.positions[0].copy()
    np.testing.assert_allclose(x_stop, [1.05, 2.0, 2.0 + 0.1 - 0.5 * 9.81 * 0.01], atol=1e-12)
    # the other sphere, flying at it along x (0.65 m apart), meets it within 0.06 s and
    # bounces back off it (nearly head on: its speed along x reversed)
    world.step(0.2)
    assert world.body(0).kind == "static"
    np.testing.assert_array_equal(world.positions[0], x_stop)
    assert world.velocities[1, 0] > 0.0
    world.set_kind(0, "dynamic")  # its mass as before (2 kg): it falls from rest
    world.step(0.2)
    np.testing.assert_allclose(world.positions[0], x_stop + 0.5 * G3 * 0.04, atol=1e-12)
    np.testing.assert_allclose(world.velocities[0], G3 * 0.2, atol=1e-12)
    assert world.bodies.mass[0] == 2.0
    # what the switches took out and gave back is booked as work: the ledger closes
    c = world.counters()
    assert c.work_done != 0.0
    scale = abs(e0) + abs(c.work_done)
    closed = e0 + c.work_done - (_ledger_energy(world) + c.energy_lost - c.energy_given)
    assert abs(closed) < 1e-12 * scale  # (a handful of events: a few ulps each)


def _ledger_energy(world: carom.World) -> float:
    """Kinetic and potential energy [J] of the dynamic spheres (no spins)."""
    moving = world.bodies.kind == 0
    m = world.bodies.mass[moving]
    v, x = world.velocities[moving], world.positions[moving]
    return float(0.5 * np.sum(m * np.sum(v * v, axis=1)) - np.sum(m * (x @ world.gravity)))
