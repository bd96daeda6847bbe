"""Joints in ``carom compare``: the scene's joints as the peers build them, and the gauge that
measures every engine alike (the joint gap, a lone pendulum's period, the cradle's one ball).

Closed forms: ``K(k)`` (Abramowitz and Stegun 17.6, table 17.1), the finite-amplitude period
``4 sqrt(L/g) K(sin(theta0/2))``, and Newton's cradle on strings, whose strike speed is
``sqrt(2 g L (1 - cos theta0))``. The peers come with the ``compare`` extra (``make test``
installs it); a test of a peer is skipped, with the reason, when it is not installed.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.compare import compare
from carom.compare.driver import peer_scene
from carom.compare.engines import ENGINES
from carom.compare.jointed import JointGauge, elliptic_k, pendulum_period
from carom.compare.report import format_rigid_table
from carom.compare.rigid import RigidScene
from carom.errors import CaromError
from carom.joints import Distance, Prismatic, Revolute, Weld, Wheel
from carom.shapes import Box, Circle


def _need(name: str) -> None:
    problem = ENGINES[name].missing()
    if problem is not None:
        pytest.skip(problem)


def test_elliptic_k_is_the_tabulated_integral() -> None:
    # K(0) = pi/2; K(1/sqrt 2) = Gamma(1/4)^2 / (4 sqrt(pi)) = 1.854074677301372 (A&S 17.3.35)
    assert elliptic_k(0.0) == pytest.approx(math.pi / 2, rel=1e-15)
    assert elliptic_k(math.sqrt(0.5)) == pytest.approx(1.854074677301372, rel=1e-14)
    assert elliptic_k(0.5) == pytest.approx(1.685750354812596, rel=1e-14)  # A&S table 17.1
    # a small swing: 2 pi sqrt(L/g) (1 + theta0^2 / 16), the series' first terms
    assert pendulum_period(1.0, 9.81, 1e-3) == pytest.approx(
        2 * math.pi * math.sqrt(1 / 9.81) * (1 + 1e-6 / 16), rel=1e-12
    )
    with pytest.raises(ValueError, match="modulus"):
        elliptic_k(1.0)


def test_the_scenes_joints_reach_the_peers_as_world_terms() -> None:
    spec = peer_scene("pendulums", None)
    assert isinstance(spec, RigidScene)
    joints = spec.joints
    assert [j.kind for j in joints] == ["distance", "revolute", "revolute", "revolute"]
    assert (joints[0].a, joints[0].b) == (-1, 0)
    assert joints[0].rigid_rod
    np.testing.assert_allclose(joints[0].anchor_a, [1.0, 3.5], atol=1e-12)
    np.testing.assert_allclose(joints[0].anchor_b, [1.866025404, 3.0], atol=1e-12)
    assert joints[0].length == pytest.approx(1.0, abs=1e-9)  # the scene's 1 m rod
    np.testing.assert_allclose(joints[3].anchor_a, [5.433012702, 3.25], atol=1e-12)


def _gauge_world() -> carom.World:
    world = carom.World(2, [10.0, 10.0], gravity=[0.0, -9.81], boundary="open")
    bob = world.add_body(Circle(0.05), [3.0, 5.0])
    bar = world.add_body(Box(0.5, 0.1), [6.0, 5.0])
    slider = world.add_body(Box(0.2, 0.2), [8.0, 5.0])
    world.add_joint(Revolute(None, bob, [2.0, 5.0]))  # a pin 1 m from the bob's centre
    world.add_joint(Distance(None, bar, [6.25, 6.0], [6.25, 5.0]))  # a rod to its end
    world.add_joint(Prismatic(None, slider, [8.0, 5.0], [1.0, 0.0]))
    return world


def test_the_gauge_measures_each_joints_break() -> None:
    world = _gauge_world()
    spec = RigidScene.from_world(lambda: world, "gauge", 1.0)
    gauge = JointGauge(spec)
    x, turn = spec.position[: spec.n].copy(), spec.angle[: spec.n].copy()
    np.testing.assert_allclose(gauge.gaps(x, turn), 0.0, atol=1e-12)
    x[0] += [0.0, 0.003]  # the pinned bob 3 mm off its pin
    x[1] += [0.0, -0.004]  # the rod's end 4 mm farther from its anchor straight below
    x[2] += [0.5, 0.002]  # the slider along its axis (no break) and 2 mm off it
    np.testing.assert_allclose(gauge.gaps(x, turn), [0.003, 0.004, 0.002], rtol=1e-9)
    turn[2] = 0.3  # a slider's axis is fixed in A (the world): turning B does not move it
    assert gauge.gaps(x, turn)[2] == pytest.approx(0.002, rel=1e-9)


def test_carom_swings_the_pendulums_at_the_closed_form_period() -> None:
    result = compare("pendulums", ["carom"], until=3.0)
    metrics = result.engines["carom"]["metrics"]
    periods = {p["body"]: p for p in metrics["pendulums"]}
    # the bob on a 1 m rod and the bar pinned at its end (L = I_p / (m d)); the double
    # pendulum has two joints and is not a lone one
    assert set(periods) == {0, 1}
    # (the scene writes its points to nine digits: 1e-9 of the rod's length and angle)
    assert periods[0]["period_s"] == pytest.approx(
        4 * math.sqrt(1 / 9.81) * elliptic_k(math.sin(math.pi / 6)), rel=1e-8
    )
    for p in periods.values():
        # measured 2.0e-4 and 1.4e-4 over three swings (the soft rod's give under the swing's
        # load; the zero crossings' interpolation adds 1e-6): 1e-3 bounds it
        assert p["error"] < 1e-3
    assert metrics["joint_gap_m"] < 0.01  # measured 2.1 mm (the double pendulum's pins)
    table = format_rigid_table(result)
    assert "joint gap" in table
    assert "K(sin(theta0/2))" in table


def test_carom_sends_one_ball_out_of_the_cradle_on_strings() -> None:
    result = compare("cradle-on-strings", ["carom"], until=1.0)
    cradle = result.engines["carom"]["metrics"]["cradle"]
    # the striker's speed at the bottom: sqrt(2 g L (1 - cos 0.4)), L = 0.5 m
    assert cradle["strike_speed_m_s"] == pytest.approx(
        math.sqrt(2 * 9.81 * 0.5 * (1 - math.cos(0.4))), rel=1e-9
    )
    # measured 0.9997 and 5.1e-5: the impacts taken pair by pair at their times
    assert cradle["out"] == pytest.approx(1.0, abs=1e-3)
    assert cradle["others"] < 1e-3


@pytest.mark.parametrize("peer", ["pymunk", "box2d", "mujoco"])
def test_the_2d_peers_build_the_jointed_scenes(peer: str) -> None:
    _need(peer)
    result = compare("cradle-on-strings", ["carom", peer], until=1.0)
    metrics = result.engines[peer]["metrics"]
    # the strings hold in the peer too (measured 1.4 mm in pymunk, 1e-7 m in Box2D, 0.8 mm
    # in MuJoCo's tendons)...
    assert metrics["joint_gap_m"] < 0.01
    # ... and the blow is shared along the row: measured out 0.58, 0.19 and 0.43, the others
    # 0.66, 0.35 and 0.57 of the strike speed, where the closed form sends one ball out
    assert metrics["cradle"]["others"] > 0.1
    swing = compare("pendulums", [peer], until=3.0).engines[peer]["metrics"]
    # the rod and the pin hold the bob and the bar on their circles (measured within 2.6 cm
    # in pymunk, 2.4 mm in Box2D, 3.7 mm in MuJoCo), and each swings at its period within 2%
    # (measured 0.36% to 1.9% at the worst)
    assert swing["joint_gap_m"] < 0.05
    assert all(p["error"] < 0.02 for p in swing["pendulums"])


def _every_kind() -> carom.World:
    """A 2D world with every joint kind the 2D peers take, limits, motors and springs."""
    world = carom.World(2, [20.0, 20.0], gravity=[0.0, -9.81], boundary="open")
    add = world.add_body
    wheel_on = add(Box(1.0, 0.2), [2.0, 10.0])
    spun = add(Box(0.6, 0.1), [4.3, 10.0])
    rope = add(Circle(0.1), [6.0, 9.0])
    sprung = add(Circle(0.1), [8.0, 9.0])
    welded = add(Box(0.4, 0.4), [2.0, 9.5])
    slid = add(Box(0.4, 0.2), [10.0, 10.0])
    wheel = add(Circle(0.2), [2.4, 9.6])
    world.add_joint(Revolute(None, wheel_on, [2.0, 10.0], limits=(-0.5, 0.5)))
    world.add_joint(Revolute(None, spun, [4.0, 10.0], motor=(2.0, 50.0)))
    world.add_joint(Distance(None, rope, [6.0, 10.0], [6.0, 9.0], min_length=0.0, max_length=1.2))
    world.add_joint(Distance(None, sprung, [8.0, 10.0], [8.0, 9.0], spring=(2.0, 0.5)))
    world.add_joint(Weld(wheel_on, welded, [2.0, 9.75]))
    world.add_joint(Prismatic(None, slid, [10.0, 10.0], [1.0, 0.0], limits=(-0.5, 0.5)))
    world.add_joint(Wheel(wheel_on, wheel, [2.4, 9.6], [0.0, 1.0], spring=(4.0, 0.7)))
    return world


@pytest.mark.parametrize("peer", ["pymunk", "box2d"])
def test_every_2d_joint_kind_holds_in_the_peers(peer: str) -> None:
    _need(peer)
    spec = RigidScene.from_world(_every_kind, "every-kind", 1.0)
    assert sorted({j.kind for j in spec.joints}) == [
        "distance", "prismatic", "revolute", "weld", "wheel",
    ]  # fmt: skip
    engine = ENGINES[peer]
    sim = engine.start(spec)
    gauge = JointGauge(spec)
    worst = 0.0
    for _ in range(60):
        sim.step()
        x, _, turn, w = sim.state()
        worst = max(worst, float(gauge.gaps(x, turn).max()))
    # every joint made: the pins, the rope, the slider hold within 2 cm over a second
    assert worst < 0.02
    # the motor turns the bar at its 2 rad/s (a 50 N m motor on a 0.6 m bar: reached at once)
    assert w[1] == pytest.approx(2.0, rel=0.05)
    # the limits hold: the slider's travel within (-0.5, 0.5) m, the rope within 1.2 m
    assert abs(x[5, 0] - 10.0) <= 0.5 + 0.02
    assert np.hypot(*(x[2] - [6.0, 10.0])) <= 1.2 + 0.02


def test_a_peer_that_cannot_build_a_scenes_joints_is_skipped_with_the_reason() -> None:
    if ENGINES["mujoco"].missing() is not None:
        pytest.skip("mujoco is not installed")
    spec = RigidScene.from_world(_every_kind, "every-kind", 0.1)
    result = compare(spec)  # the default engines: MuJoCo has no 2D slider, wheel or limit
    assert "carom" in result.engines
    assert "limits" in result.skipped["mujoco"] or "motor" in result.skipped["mujoco"]
    with pytest.raises(CaromError, match="MuJoCo: scene 'every-kind' has"):
        compare(spec, ["mujoco"])  # asked for by name: refused, not skipped


def _ball_on_a_socket() -> carom.World:
    """A 5 cm ball hung 1 m from a socket, let go from 40 degrees (3D, no floor near)."""
    from carom.joints import Spherical
    from carom.shapes3d import Sphere

    world = carom.World(3, [6.0, 6.0, 6.0], gravity=[0.0, 0.0, -9.81], boundary="open")
    theta = math.radians(40.0)
    ball = world.add_body(Sphere(0.05), [3.0 + math.sin(theta), 3.0, 5.0 - math.cos(theta)])
    world.add_joint(Spherical(None, ball, [3.0, 3.0, 5.0]))
    return world


def test_a_ball_on_a_socket_swings_at_its_period_in_carom_and_the_3d_peers() -> None:
    from carom.compare.rigid3d import RigidScene3D

    spec = RigidScene3D.from_world(_ball_on_a_socket, "socket", 3.0)
    (pendulum,) = JointGauge(spec).pendulums
    # a physical pendulum: L = (I + m d^2) / (m d), I = 2/5 m r^2 (a ball), d = 1 m
    length = 1.0 + 0.4 * 0.05**2
    assert pendulum.period == pytest.approx(
        pendulum_period(length, 9.81, math.radians(40.0)), rel=1e-12
    )
    engines = ["carom"] + [e for e in ("mujoco", "rapier3d") if ENGINES[e].missing() is None]
    result = compare(spec, engines)
    for name in engines:
        metrics = result.engines[name]["metrics"]
        (swing,) = metrics["pendulums"]
        # measured: carom 8.7e-5 (its soft socket's give), MuJoCo 1.3e-6 (a ball joint of its
        # tree, in generalized coordinates)
        assert swing["error"] < 1e-3, name
        assert metrics["joint_gap_m"] < 0.01, name


@pytest.mark.parametrize("peer", ["carom", "mujoco", "rapier3d"])
def test_the_3d_rope_scene_drives_its_motors_in_the_3d_peers(peer: str) -> None:
    _need(peer)
    from carom.compare.rigid3d import RigidScene3D
    from carom.geometry.rotation import rotation_matrices

    spec = peer_scene("rope-3d", None)
    assert isinstance(spec, RigidScene3D)
    sim = ENGINES[peer].start(spec)
    gauge = JointGauge(spec)
    worst = 0.0
    for _ in range(round(1.0 / sim.dt)):
        sim.step()
        x, v, q, w = sim.state()
        worst = max(worst, float(gauge.gaps(x, q).max()))
    # the door's motor (1.5 rad/s, 20 N m) and the bar's (0.8 m/s, 10 N) run at their
    # speeds after a second, the door short of its limit at 2 rad (measured 85-86 degrees)
    assert w[30, 2] == pytest.approx(1.5, rel=1e-2)
    assert v[31, 0] == pytest.approx(0.8, rel=1e-2)
    turn = rotation_matrices(q[30:31])[0]
    assert math.degrees(math.atan2(turn[1, 0], turn[0, 0])) == pytest.approx(86.0, abs=1.5)
    # the rope, the hinge, the slider and the weld hold (measured 6 mm in carom, 2 cm in
    # Rapier, 3 cm in MuJoCo over this second)
    assert worst < 0.05
