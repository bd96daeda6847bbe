"""Joints in the 3D rigid engine (issue 43, item 5): spherical, revolute (a hinge), prismatic,
distance, fixed and target joints, against closed forms. Tolerances as in 2D
(tests/test_joints.py): the soft step's integrator and its joints' give under load."""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.errors import CaromError
from carom.joints import Distance, Fixed, Prismatic, Revolute, Spherical, Target, Wheel
from carom.shapes3d import Box, Sphere

G = 9.81


def world(gravity: float = -G) -> carom.World:
    return carom.World(3, [20.0, 20.0, 20.0], gravity=[0.0, 0.0, gravity], boundary="open")


def elliptic_k(k: float) -> float:
    """K(k) by the arithmetic-geometric mean (Abramowitz and Stegun 17.6)."""
    a, b = 1.0, math.sqrt(1.0 - k * k)
    for _ in range(30):
        a, b = 0.5 * (a + b), math.sqrt(a * b)
    return math.pi / (2.0 * a)


@pytest.mark.parametrize("joint", ["distance", "spherical"])
def test_a_3d_pendulum_swings_at_the_finite_amplitude_period(joint: str) -> None:
    w = world()
    pivot = np.array([10.0, 10.0, 15.0])
    amplitude = math.pi / 3
    start = pivot + np.array([math.sin(amplitude), 0.0, -math.cos(amplitude)])
    bob = w.add_body(Sphere(0.05), start)
    if joint == "distance":
        w.add_joint(Distance(None, bob, pivot, start))
        length = 1.0  # a point mass on a rod
    else:  # the ball held 1 m from its centre: a physical pendulum, I_p / (m d) long
        w.add_joint(Spherical(None, bob, pivot))
        length = 1.0 + 0.4 * 0.05**2  # (I_cm = 2 m R^2 / 5, d = 1 m)
    times, xs = [], []
    for _ in range(480):
        w.step()
        times.append(w.time)
        xs.append(w.positions[bob, 0] - pivot[0])
    t, x = np.array(times), np.array(xs)
    k = np.flatnonzero(np.sign(x[:-1]) != np.sign(x[1:]))
    crossings = t[k] - x[k] * (t[k + 1] - t[k]) / (x[k + 1] - x[k])
    measured = 2.0 * float(np.mean(np.diff(crossings)))
    exact = 4.0 * math.sqrt(length / G) * elliptic_k(math.sin(amplitude / 2))
    # measured 2.0e-4 and 1.6e-4 (the 2D joints' figures: the same soft step)
    assert measured == pytest.approx(exact, rel=5e-4)
    # it swings in its plane: nothing pushes it out of y = 10
    assert np.max(np.abs(w.positions[bob, 1] - 10.0)) < 1e-12


def test_a_hinge_motor_reaches_its_speed_and_is_limited_by_its_torque() -> None:
    w = world(gravity=0.0)
    fast = w.add_body(Box([1.0, 0.2, 0.2]), [5.5, 5.0, 5.0])
    weak = w.add_body(Box([1.0, 0.2, 0.2]), [15.5, 5.0, 5.0])
    w.add_joint(Revolute(None, fast, [5.0, 5.0, 5.0], axis=[0.0, 1.0, 0.0], motor=(2.0, 100.0)))
    w.add_joint(Revolute(None, weak, [15.0, 5.0, 5.0], axis=[0.0, 0.0, 1.0], motor=(100.0, 0.01)))
    model = w.build().model
    # about the hinge 0.5 m from its centre: I_zz + m d^2 (parallel axes)
    inertia = float(model.inertia[weak][2, 2]) + float(w.masses[weak]) * 0.25
    for frame in range(1, 61):
        w.step()
        # the weak motor turns it at its largest torque: omega = T t / I_pivot (measured 3e-6)
        assert w.angular_velocities[weak, 2] == pytest.approx(0.01 * frame / 60 / inertia, rel=1e-4)
    spin = w.angular_velocities[fast]
    # the strong one holds its speed (the pin's pull on the swinging bar shares the relax
    # pass with the motor: measured 1e-4 off), about its axis only
    assert spin[1] == pytest.approx(2.0, rel=5e-4)
    assert abs(spin[0]) < 1e-9
    assert abs(spin[2]) < 1e-9


def test_a_hinge_limit_holds_a_bar_against_gravity() -> None:
    w = world()
    bar = w.add_body(Box([1.0, 0.1, 0.1]), [10.5, 10.0, 10.0])
    w.add_joint(Revolute(None, bar, [10.0, 10.0, 10.0], axis=[0.0, 1.0, 0.0], limits=(-0.3, 0.3)))
    for _ in range(180):
        w.step()
    # it fell about the hinge (turning about +y tips +x down) until the limit at 0.3 rad
    w0, x, y, z = w.orientations[bar]
    angle = 2.0 * math.atan2(y, w0)
    assert angle == pytest.approx(0.3, abs=3e-3)  # the soft limit's give (measured 1.1e-3)
    assert abs(x) < 1e-9
    assert abs(z) < 1e-9


def test_a_3d_prismatic_limit_holds_under_load() -> None:
    w = world()
    box = w.add_body(Box([0.2, 0.2, 0.2]), [10.0, 10.0, 10.0])
    slider = w.add_joint(
        Prismatic(None, box, [10.0, 10.0, 10.0], [0.0, 0.0, 1.0], limits=(-0.5, 0.5))
    )
    for _ in range(120):
        w.step()
    assert w.positions[box, :2] == pytest.approx([10.0, 10.0], abs=1e-12)
    assert w.positions[box, 2] == pytest.approx(9.5, abs=2e-4)  # measured 6.9e-5 below
    assert w.orientations[box] == pytest.approx([1.0, 0.0, 0.0, 0.0], abs=1e-12)
    force, _ = w.joint_reactions()
    assert force[slider] == pytest.approx([0.0, 0.0, float(w.masses[box]) * G], rel=1e-9, abs=1e-12)


def test_a_fixed_joint_makes_one_body_of_two() -> None:
    w = world()
    a = w.add_body(Box([0.2, 0.2, 0.2]), [10.0, 10.0, 10.0])
    b = w.add_body(Box([0.2, 0.2, 0.2]), [10.2, 10.0, 10.0])
    w.add_joint(Spherical(None, a, [10.0, 10.0, 10.1]))
    w.add_joint(Fixed(a, b, [10.1, 10.0, 10.0]))
    for _ in range(120):
        w.step()
        # the pair swings as one: the same orientation, their centres 0.2 m apart
        assert np.linalg.norm(w.positions[b] - w.positions[a]) == pytest.approx(0.2, abs=5e-4)
        assert abs(float(np.dot(w.orientations[a], w.orientations[b]))) == pytest.approx(
            1.0, abs=2e-6
        )


def test_a_3d_target_joint_pulls_its_body_to_the_point() -> None:
    w = world()
    box = w.add_body(Box([0.2, 0.2, 0.2]), [10.0, 10.0, 10.0])
    w.add_joint(Target(box, [11.0, 11.0, 11.0]))
    for _ in range(240):
        w.step()
    sag = G / (2.0 * math.pi * 5.0) ** 2  # a 5 Hz spring holds the weight g / omega^2 below
    assert w.positions[box] == pytest.approx([11.0, 11.0, 11.0 - sag], abs=1e-4)


def rope(links: int = 12) -> tuple[carom.World, list[int]]:
    """A rope of ``links`` balls on spherical joints hung from the world, let go sideways."""
    w = world()
    balls = []
    for k in range(links):
        balls.append(w.add_body(Sphere(0.05), [10.0 + 0.1 * (k + 1), 10.0, 15.0]))
    w.add_joint(Spherical(None, balls[0], [10.05, 10.0, 15.0]))
    for k in range(links - 1):
        w.add_joint(Spherical(balls[k], balls[k + 1], [10.1 + 0.1 * k + 0.05, 10.0, 15.0]))
    return w, balls


def test_a_rope_of_spherical_joints_holds_together_and_keeps_its_ledger() -> None:
    w, balls = rope()
    e0 = w.build().energy()
    for _ in range(240):
        w.step()
        anchors = w.joint_anchors()
        # each link holds (the soft joints' give under the whip: measured 2 mm)
        assert np.max(np.linalg.norm(anchors[:, 0] - anchors[:, 1], axis=1)) < 1e-2
    c = w.counters()
    e = w.build().energy()
    assert e0 + c.work_done == pytest.approx(e + c.energy_lost - c.energy_given, abs=1e-9 * abs(e0))
    # it fell and swings below its pin, 1.2 m of rope
    assert np.all(w.positions[balls, 2] < 15.0 + 1e-3)
    assert np.all(np.linalg.norm(w.positions[balls] - [10.05, 10.0, 15.0], axis=1) < 1.25)


def test_3d_joints_rerun_and_checkpoint_bit_for_bit(tmp_path) -> None:  # type: ignore[no-untyped-def]
    a, _ = rope(6)
    b, _ = rope(6)
    for _ in range(30):
        a.step()
        b.step()
    assert np.array_equal(a.positions, b.positions)
    path = tmp_path / "rope.npz"
    a.save(path)
    c = carom.World.load(path)
    for _ in range(30):
        a.step()
        c.step()
    assert np.array_equal(a.positions, c.positions)
    assert np.array_equal(a.orientations, c.orientations)


@pytest.mark.parametrize(
    ("joint", "message"),
    [
        (Wheel(None, 0, [10.0, 10.0, 10.0], [0.0, 0.0, 1.0]), "a wheel joint is 2D"),
        (Revolute(None, 0, [10.0, 10.0, 10.0]), "needs its axis"),
        (
            Revolute(None, 0, [10.0, 10.0, 10.0], axis=[0, 0, 1], limits=(-4.0, 1.0)),
            "within a turn",
        ),
        (Spherical(0, 0, [10.0, 10.0, 10.0]), "two different bodies"),
        (Spherical(None, 0, [10.0, 10.0]), "must be 3 numbers"),
    ],
)
def test_bad_3d_joints_are_refused_and_change_nothing(joint: object, message: str) -> None:
    w = world()
    w.add_body(Box([0.2, 0.2, 0.2]), [10.0, 10.0, 10.0])
    with pytest.raises(CaromError, match=message):
        w.add_joint(joint)  # type: ignore[arg-type]
    assert w.n_joints == 0


def test_a_spherical_joint_is_refused_in_2d() -> None:
    from carom.shapes import Circle

    w = carom.World(2, [10.0, 10.0], boundary="open")
    w.add_body(Circle(0.1), [5.0, 5.0])
    with pytest.raises(CaromError, match="a spherical joint is 3D"):
        w.add_joint(Spherical(None, 0, [5.0, 5.0]))
