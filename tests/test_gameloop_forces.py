"""Forces and torques for the next step (issue 43, item 2): ``Body.apply_force``,
``Body.apply_torque``, ``World.apply_forces``, ``World.apply_torques``.

A load acts through the next step and is then cleared, as in Box2D. It is constant through
the step, so free flight under it stays exact (the closed forms below hold to round-off), the
solver takes it each substep as it takes gravity, and the energy ledger books its work.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.errors import CaromError
from tests.worlds import rotation

G = 9.81


def _free_box(dim: int, gravity: bool = True) -> carom.World:
    """One box alone (2 x 1 (x 0.5) m, turned), open boundary: nothing but its loads and
    gravity acts on it."""
    g = -G if gravity else 0.0
    if dim == 2:
        from carom.shapes import Box

        world = carom.World(2, [10.0, 10.0], gravity=[0.0, g], boundary="open")
        world.add_body(Box(2.0, 1.0), [5.0, 5.0], angle=0.4, velocity=[0.5, 1.0])
        return world
    from carom.shapes3d import Box as Box3D

    world = carom.World(3, [10.0] * 3, gravity=[0.0, 0.0, g], boundary="open")
    turn = [math.cos(0.2), 0.6 * math.sin(0.2), 0.8 * math.sin(0.2), 0.0]
    world.add_body(
        Box3D([2.0, 1.0, 0.5]), [5.0, 5.0, 5.0], orientation=turn, velocity=[0.5, 0.0, 1.0]
    )
    return world


@pytest.mark.parametrize("dim", [2, 3])
def test_a_force_held_each_frame_gives_the_parabola_of_g_plus_f_over_m(dim: int) -> None:
    world = _free_box(dim)
    body = world.body(0)
    mass = world.masses[0]
    force = np.array([3.0, -2.0, 5.0][:dim])
    x0, v0 = body.position, body.velocity
    for _ in range(45):
        body.apply_force(force)
        world.step()
    t = world.time
    a = force / mass
    a[-1] -= G
    # Newton with a constant force: x0 + v0 t + (g + F/m) t^2 / 2, v0 + (g + F/m) t; free
    # flight is exact, so to round-off of the position's size (45 steps, a few ulps each)
    np.testing.assert_allclose(body.position, x0 + v0 * t + 0.5 * a * t**2, rtol=0, atol=1e-13)
    np.testing.assert_allclose(body.velocity, v0 + a * t, rtol=0, atol=1e-13)
    # the force was for those steps only: the next step is gravity's alone
    v1 = body.velocity
    world.step()
    g = np.zeros(dim)
    g[-1] = -G
    np.testing.assert_allclose(body.velocity, v1 + g / 60, rtol=0, atol=1e-14)


def test_a_torque_held_each_frame_turns_a_2d_body_by_its_closed_form() -> None:
    world = _free_box(2, gravity=False)
    body = world.body(0)
    inertia = world.masses[0] * (2.0**2 + 1.0**2) / 12  # a 2 x 1 box about its centre
    theta0, torque = body.angle, -0.7
    for _ in range(30):
        body.apply_torque(torque)
        world.step()
    t = world.time
    # constant angular acceleration T / I: theta0 + T t^2 / (2 I), omega = T t / I
    assert body.angle == pytest.approx(theta0 + 0.5 * torque / inertia * t**2, abs=1e-14)
    assert body.angular_velocity == pytest.approx(torque / inertia * t, abs=1e-14)


def test_a_torque_on_a_tumbling_3d_body_changes_its_angular_momentum_by_t_dt() -> None:
    world = _free_box(3, gravity=False)
    body = world.body(0)
    body.angular_velocity = [1.0, -2.0, 0.5]  # about no principal axis: it tumbles
    mass, sides = world.masses[0], np.array([2.0, 1.0, 0.5])
    moments = mass * (np.sum(sides**2) - sides**2) / 12  # a box's principal moments

    def momentum() -> np.ndarray:
        rot = rotation(body.orientation)
        return rot @ (moments * (rot.T @ body.angular_velocity))

    l0 = momentum()
    torque = np.array([0.4, 0.3, -1.1])
    for _ in range(60):
        body.apply_torque(torque)
        world.step()
    # dL/dt = T: L = L0 + T t, whatever the body does meanwhile; the turn keeps L exactly
    # and the orientation to 3e-11 of the energy (motion.free_turn), so L to 1e-10
    np.testing.assert_allclose(momentum(), l0 + torque * world.time, rtol=0, atol=1e-10)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_force_at_a_point_is_the_force_and_its_moment(dim: int) -> None:
    at_point, split = _free_box(dim), _free_box(dim)
    force = np.array([1.0, 2.0, -0.5][:dim])
    point = at_point.positions[0] + np.array([0.3, -0.4, 0.2][:dim])
    arm = point - at_point.positions[0]
    moment = arm[0] * force[1] - arm[1] * force[0] if dim == 2 else np.cross(arm, force)
    at_point.body(0).apply_force(force, point)
    split.body(0).apply_force(force)
    split.body(0).apply_torque(moment)
    for world in (at_point, split):
        world.step()
    np.testing.assert_array_equal(at_point.positions, split.positions)
    np.testing.assert_array_equal(at_point.angular_velocities, split.angular_velocities)


def _box_on_floor(mu: float) -> carom.World:
    from carom.materials import Material
    from carom.shapes import Box

    floor = Material(restitution=0.0, friction=mu)
    world = carom.World(2, [20.0, 10.0], gravity=[0.0, -G], boundary="open")
    world.add_body(Box(20.0, 1.0), [10.0, -0.5], kind="static", material=floor)
    world.add_body(Box(1.0, 1.0), [2.0, 0.5], material=floor)
    world.run(until=0.5)  # settled on the floor
    return world


def test_a_push_beyond_static_friction_slides_a_box_at_f_over_m_less_mu_g() -> None:
    mu = 0.4
    world = _box_on_floor(mu)
    box = world.body(1)
    mass = world.masses[1]
    force = 1.5 * mu * mass * G  # half again what friction holds
    for _ in range(20):  # the push tips the box onto its front edge (1e-4 rad) and it slides
        box.apply_force([force, 0.0])
        world.step()
    x0, v0, t0 = box.position, box.velocity, world.time
    for _ in range(40):
        box.apply_force([force, 0.0])
        world.step()
    t = world.time - t0
    # Coulomb sliding: m a = F - mu m g, so v = v0 + a t. The solver moves a body in contact
    # by symplectic Euler over substeps of h = dt / 4 (x gains h v after v gains h a), whose
    # sum is x0 + v0 t + a t (t + h) / 2, not a t^2 / 2. The soft contacts carry the weight to
    # 1e-8 of it once the tipping has settled (measured: each step's dv within 1e-8 of a dt
    # after 20 steps), so 1e-6 relative bounds both with room
    a, h = force / mass - mu * G, 1 / 240
    assert box.velocity[0] - v0[0] == pytest.approx(a * t, rel=1e-6)
    assert box.position[0] - x0[0] == pytest.approx(v0[0] * t + 0.5 * a * t * (t + h), rel=1e-6)
    # a push under what friction holds: the soft contacts give once as the push tips the
    # box (measured 1.7e-5 m, far under the 5 mm slop), then the box holds: the give dies
    # away (halving about every 4 steps, measured) and from 2 s on it has stopped
    still = _box_on_floor(mu)
    x1 = still.body(1).position
    for k in range(150):
        if k == 120:
            x2 = still.body(1).position
        still.body(1).apply_force([0.5 * mu * mass * G, 0.0])
        still.step()
    assert abs(x2[0] - x1[0]) < 1e-4
    assert abs(still.body(1).position[0] - x2[0]) < 1e-12


@pytest.mark.parametrize("dim", [2, 3])
def test_the_ledger_closes_with_forces_and_torques(dim: int) -> None:
    from tests.test_gameloop import _boxes

    world = _boxes(dim)
    e0 = world.build().energy()  # type: ignore[attr-defined]
    push = np.zeros(dim)
    push[0] = 4.0
    spin = 0.6 if dim == 2 else [0.0, 0.3, 0.6]
    for k in range(150):
        if k % 3 == 0:
            world.apply_forces([1, 2, 3], push)
            world.body(2).apply_torque(spin)
        if 40 <= k < 60:
            world.body(3).apply_force(-push, world.body(3).position + 0.1)
        world.step()
    c = world.counters()
    e = world.engine.energy()  # type: ignore[union-attr]
    # E0 + work done = E + lost - given: the loads' work is booked (F . dx, T dtheta; in 3D
    # T . w over the solver's substeps), so the ledger closes to round-off, as without loads
    scale = e0 + abs(c.work_done)
    assert abs(e0 + c.work_done - (e + c.energy_lost - c.energy_given)) < 1e-11 * scale
    assert c.work_done > 0.0


def test_a_force_in_free_flight_books_exactly_f_dot_dx() -> None:
    world = _free_box(2, gravity=False)
    force = np.array([2.0, -1.0])
    x0 = world.positions[0].copy()
    for _ in range(10):
        world.body(0).apply_force(force)
        world.step()
    # the work of a constant force is F . dx, whatever the path
    work = float(force @ (world.positions[0] - x0))
    assert world.counters().work_done == pytest.approx(work, rel=1e-13)


def test_many_loads_at_once_are_the_bits_of_one_at_a_time() -> None:
    from tests.test_gameloop import _boxes

    one, many = _boxes(3), _boxes(3)
    forces = np.array([[0.5, 0.0, 1.0], [0.0, -0.2, 0.3], [0.1, 0.1, 0.1]])
    torques = np.array([[0.0, 0.1, 0.0], [0.2, 0.0, 0.0], [0.0, 0.0, -0.3]])
    for _ in range(20):
        for k, i in enumerate([1, 2, 3]):
            one.body(i).apply_force(forces[k])
            one.body(i).apply_torque(torques[k])
        many.apply_forces([1, 2, 3], forces)
        many.apply_torques([1, 2, 3], torques)
        one.step()
        many.step()
    np.testing.assert_array_equal(one.positions, many.positions)
    np.testing.assert_array_equal(one.orientations, many.orientations)


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda w: w.body(0).apply_force([1.0, 0.0]), "body 0 is static: forces"),
        (lambda w: w.body(1).apply_force([math.inf, 0.0]), "finite"),
        (lambda w: w.body(1).apply_torque([1.0, 2.0]), "shape"),
        (lambda w: w.apply_torques([0, 1], 1.0), "body 0 is static: torques"),
        (lambda w: w.apply_forces([1, 2], [[1.0, 0.0]] * 3), "shape"),
        (lambda w: w.body(1).apply_force([1.0, 0.0], [math.nan, 0.0]), "finite"),
    ],
)
def test_a_wrong_load_is_refused_and_changes_nothing(call: object, match: str) -> None:
    from tests.test_gameloop import _boxes

    world, twin = _boxes(2), _boxes(2)
    with pytest.raises(CaromError, match=match):
        call(world)  # type: ignore[operator]
    # nothing was kept for the next step: it is the step of a world never asked
    world.step()
    twin.step()
    np.testing.assert_array_equal(world.positions, twin.positions)
