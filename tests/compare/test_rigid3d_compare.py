"""carom compare on 3D rigid bodies: the scene as data, the closed forms, the yardstick, the
peers (pybullet, MuJoCo, rapier3d).

The peers come with the ``compare`` extra; each test of a peer is skipped, with the reason,
when that peer is not installed.
"""

from __future__ import annotations

import json
import math

import numpy as np
import pytest

from carom.compare import compare
from carom.compare.driver import RigidComparison, peer_scene
from carom.compare.engines import ENGINES
from carom.compare.report import format_table, write_comparison
from carom.compare.rigid3d import (
    RigidScene3D,
    path_enters,
    primitives,
    principal_frame,
)
from carom.errors import CaromError
from carom.geometry.rotation import matrix_quaternion, quaternion_product, rotation_matrices
from carom.scene import Scene

PEERS = ["pybullet", "mujoco", "rapier3d"]
IMPACTS = ["box-edge-3d", "box-corner-3d", "rod-drop-3d", "spin-ball-3d"]


def _need(name):
    problem = ENGINES[name].missing()
    if problem is not None:
        pytest.skip(problem)


def test_the_rod_drop_closed_form_is_the_textbook_one():
    """A capsule rod (axis along its z, turned 60 degrees about y: 30 degrees from level)
    dropped from rest lands on the bottom of its lower cap, at r = -s (sin 60, 0, cos 60) -
    (0, 0, a) from its centre (s the half segment, a the radius). Free fall: v = sqrt(2 g
    drop). r x z = (0, -r_x, 0) lies along a principal axis (I_perp, the rod is symmetric
    about its own axis), so Hecker's impulse (PHYSICS.md section 2) is j = (1 + e) m v /
    (1 + m r_x^2 / I_perp), the spin w_y = -r_x j / I_perp, and it stays constant in flight
    (a principal axis)."""
    scene = peer_scene("rod-drop-3d")
    assert isinstance(scene, RigidScene3D)
    check = compare(scene, ["carom"]).expected
    assert check is not None
    assert check.points == 1
    s, a, e, g, z0 = 0.475, 0.025, 0.5, 9.81, 1.0
    m = float(scene.mass[1])
    tensor = scene.inertia[1]
    assert tensor[0, 0] == tensor[1, 1]
    assert np.count_nonzero(tensor - np.diag(np.diag(tensor))) == 0
    i_perp = float(tensor[0, 0])
    r = -s * np.array([math.sin(math.radians(60.0)), 0.0, math.cos(math.radians(60.0))])
    r[2] -= a
    drop = z0 + r[2]
    v = math.sqrt(2.0 * g * drop)
    assert check.impact_time == pytest.approx(math.sqrt(2.0 * drop / g), rel=1e-14)
    j = (1.0 + e) * m * v / (1.0 + m * r[0] ** 2 / i_perp)
    dt = check.time - check.impact_time
    assert check.velocity[2] == pytest.approx(-v + j / m - g * dt, rel=1e-12)
    assert check.velocity[0] == 0.0
    assert check.velocity[1] == 0.0
    assert check.omega[1] == pytest.approx(-r[0] * j / i_perp, rel=1e-12)
    assert abs(check.omega[0]) + abs(check.omega[2]) < 1e-12 * abs(check.omega[1])


def test_the_box_edge_closed_form_is_the_textbook_one():
    """A 0.4 x 0.3 x 0.2 box turned 45 degrees about x lands on its lowest edge, the corner
    (y, z) = (-0.15, -0.1) turned: r_y = (-0.15 + 0.1) / sqrt 2, r_z = -(0.15 + 0.1) /
    sqrt 2. The edge's two ends lie symmetric about the centre along x, so they share the
    impulse: the total is j = (1 + e) m v / (1 + m r_y^2 / I_xx), I_xx = m (0.3^2 + 0.2^2)
    / 12 (Hecker's 3D formula, PHYSICS.md section 2, with r x n along x), and the box spins
    about x at w_x = r_y j / I_xx (a principal axis: constant by Euler's equations)."""
    scene = peer_scene("box-edge-3d")
    check = compare(scene, ["carom"]).expected
    assert check is not None
    assert check.points == 2
    e, g, z0 = 0.5, 9.81, 0.5
    m = float(scene.mass[1])
    assert m == pytest.approx(500.0 * 0.4 * 0.3 * 0.2, rel=1e-14)
    i_xx = m * (0.3**2 + 0.2**2) / 12.0
    r_y, r_z = (-0.15 + 0.1) / math.sqrt(2.0), -(0.15 + 0.1) / math.sqrt(2.0)
    drop = z0 + r_z
    v = math.sqrt(2.0 * g * drop)
    assert check.impact_time == pytest.approx(math.sqrt(2.0 * drop / g), rel=1e-13)
    j = (1.0 + e) * m * v / (1.0 + m * r_y**2 / i_xx)
    dt = check.time - check.impact_time
    assert check.velocity[2] == pytest.approx(-v + j / m - g * dt, rel=1e-12)
    assert check.omega[0] == pytest.approx(r_y * j / i_xx, rel=1e-12)
    assert abs(check.omega[1]) + abs(check.omega[2]) < 1e-12 * abs(check.omega[0])


def test_the_spinning_ball_closed_form_follows_coulomb():
    """A ball (I = 2/5 m R^2) landing with backspin slides through the impact (the rolling
    rule would need more than mu times the normal impulse): the normal impulse is (1 + e)
    m |v_z|, the tangential one mu times it against the slip, and the spin changes by
    R x P / I (Coulomb friction in Walton's model, PHYSICS.md section 3, on its sliding
    branch). The check waits in flight, where both stay constant."""
    scene = peer_scene("spin-ball-3d")
    check = compare(scene, ["carom"]).expected
    assert check is not None
    assert check.points == 1
    m, radius, e, mu, g = float(scene.mass[1]), 0.1, 0.6, 0.2, 9.81
    inertia = 0.4 * m * radius**2
    vz = -math.sqrt(2.0 * g * 0.5)
    slip = 2.0 - (-30.0) * radius  # contact point: v_x + (w x r)_x, w_y = -30, r = -R z
    assert slip > 0.0
    pn = -(1.0 + e) * m * vz
    pt = -mu * pn  # against the slip (+x)
    # sliding needs the sticking impulse beyond the cone: m slip / (1 + m R^2 / I) > mu pn
    assert m * slip / (1.0 + m * radius**2 / inertia) > mu * pn
    assert check.velocity[0] == pytest.approx(2.0 + pt / m, rel=1e-12)
    dt = check.time - check.impact_time
    assert check.velocity[2] == pytest.approx(vz + pn / m - g * dt, rel=1e-12)
    # the spin: w_y + (r x P)_y / I, r = (0, 0, -R), P = (pt, 0, pn): (r x P)_y = -R pt
    assert check.omega[1] == pytest.approx(-30.0 + (-radius * pt) / inertia, rel=1e-12)


@pytest.mark.parametrize("name", IMPACTS)
def test_carom_meets_the_3d_closed_forms(name):
    """The step is split at the impact found by conservative advancement (its tolerance,
    1e-9 of the reach, bounds the error) and the impulse is the closed form's law."""
    result = compare(name, ["carom"])
    assert isinstance(result, RigidComparison)
    m = result.engines["carom"]["metrics"]
    assert result.expected is not None
    assert m["velocity_error"] < 1e-7
    assert m["omega_error"] < 1e-7
    assert m["energy_gain"] < 1e-9  # e < 1 loses energy; the soft step's round-off only
    assert not m["tunnelled"]
    text = format_table(result)
    assert "3D rigid" in text
    assert "carom" in text


def test_carom_stops_all_twenty_bullets():
    """Twenty 5 cm boxes at 100 m/s, each turned its own way, against a 1 cm wall: none
    passes, and every one comes back (e = 0.5)."""
    result = compare("bullet-3d", ["carom"])
    m = result.engines["carom"]["metrics"]
    assert m["bodies_through_static"] == 0
    world = peer_scene("bullet-3d").world()
    world.run(until=0.2)
    assert np.all(world.frame().velocities[1:, 0] < 0.0)


def test_the_path_check_sees_a_centre_enter_a_slab():
    # the slab 2.995 <= x <= 3.005 (two faces): a path through it, one short of it, one along
    normals = np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]])
    offsets = np.array([3.005, -2.995])
    before = np.array([[0.3, 0.0, 0.0], [0.3, 0.0, 0.0], [0.3, 1.0, 0.0], [3.0, 0.0, 0.0]])
    after = np.array([[5.0, 0.0, 0.0], [2.9, 0.0, 0.0], [0.3, 1.0, 9.0], [5.0, 0.0, 0.0]])
    assert path_enters(before, after, normals, offsets).tolist() == [True, False, False, False]


def test_primitives_name_each_piece_as_the_peers_shapes():
    scene = Scene.from_dict(
        {
            "world": {"dimension": 3, "box": [2.0, 2.0, 2.0], "gravity": [0.0, 0.0, -9.81]},
            "bodies": [
                {"shape": "box", "size": [0.4, 0.3, 0.2], "positions": [[1.0, 1.0, 1.0]]},
                {"shape": "capsule", "size": 0.5, "radius": 0.1, "positions": [[0.5, 0.5, 1]]},
                {"shape": "ball", "radius": 0.2, "positions": [[1.5, 1.5, 1.0]]},
            ],
            "run": {"until": 0.1},
        },
        source="shapes",
    )
    spec = peer_scene(scene)
    assert isinstance(spec, RigidScene3D)
    (box,) = primitives(spec, 0)
    assert box.shape == "box"
    assert box.half.tolist() == pytest.approx([0.2, 0.15, 0.1], rel=1e-15)
    (capsule,) = primitives(spec, 1)
    assert capsule.shape == "capsule"
    assert capsule.radius == 0.1
    assert np.linalg.norm(capsule.ends[1] - capsule.ends[0]) == pytest.approx(0.5, rel=1e-15)
    (ball,) = primitives(spec, 2)
    assert ball.shape == "sphere"
    assert ball.radius == 0.2
    # the box's six walls are static boxes
    assert {p.shape for b in range(3, spec.bodies) for p in primitives(spec, b)} == {"box"}


def test_the_principal_frame_rebuilds_the_tensor():
    rng = np.random.default_rng(3)
    turn = np.linalg.qr(rng.normal(size=(3, 3)))[0]
    turn *= np.sign(np.linalg.det(turn))
    tensor = turn @ np.diag([1.0, 2.0, 3.5]) @ turn.T
    moments, q = principal_frame(tensor)
    r = rotation_matrices(q[None, :])[0]
    assert r @ np.diag(moments) @ r.T == pytest.approx(tensor, abs=1e-14)
    assert matrix_quaternion(r) == pytest.approx(q, abs=1e-15) or matrix_quaternion(
        r
    ) == pytest.approx(-q, abs=1e-15)
    identity = quaternion_product(q, q * np.array([1.0, -1.0, -1.0, -1.0]))
    assert identity == pytest.approx([1.0, 0.0, 0.0, 0.0], abs=1e-15)


def _tilted_hull_scene():
    """A spinning, moving tetrahedron (a tensor with products of inertia) above a plane."""
    return Scene.from_dict(
        {
            "world": {
                "dimension": 3,
                "box": [4.0, 4.0, 4.0],
                "gravity": [0.0, 0.0, -9.81],
                "boundary": "open",
            },
            "materials": [{"name": "m", "restitution": 0.4, "friction": 0.3}],
            "bodies": [
                {
                    "shape": "box",
                    "size": [4.0, 4.0, 1.0],
                    "positions": [[2.0, 2.0, -0.5]],
                    "kind": "static",
                    "material": "m",
                },
                {
                    "shape": "hull",
                    "vertices": [[0, 0, 0], [0.3, 0, 0], [0, 0.2, 0.05], [0.05, 0.1, 0.4]],
                    "positions": [[2.0, 2.0, 1.0]],
                    "orientations": [[0.9, 0.3, -0.2, 0.1]],
                    "velocities": [[0.5, -0.2, 0.1]],
                    "angular_velocities": [[1.0, -2.0, 3.0]],
                    "material": "m",
                },
            ],
            "run": {"until": 0.05},
        },
        source="hull",
    )


@pytest.mark.parametrize("peer", PEERS)
def test_each_peer_starts_from_the_same_state(peer):
    """The peers' conventions (quaternion order, inertial frames, a free joint's body-frame
    angular velocity) are converted both ways: each reports the scene's own pose and
    velocities before its first step. Rapier computes in f32 (7 digits)."""
    _need(peer)
    spec = peer_scene(_tilted_hull_scene())
    assert np.count_nonzero(spec.inertia[1] - np.diag(np.diag(spec.inertia[1]))) > 0
    sim = ENGINES[peer].start(spec)
    try:
        x, v, q, w = sim.state()
    finally:
        sim.close()
    tol = 2e-7 if peer == "rapier3d" else 1e-12
    assert x[1] == pytest.approx(spec.position[1], rel=tol, abs=tol)
    assert v[1] == pytest.approx(spec.velocity[1], rel=tol, abs=tol)
    sign = 1.0 if float(q[1] @ spec.orientation[1]) > 0 else -1.0
    assert sign * q[1] == pytest.approx(spec.orientation[1], abs=tol)
    assert w[1] == pytest.approx(spec.omega[1], rel=tol, abs=tol)


@pytest.mark.parametrize("peer", PEERS)
def test_peers_run_the_3d_impacts(peer, tmp_path):
    """Each peer takes the same bodies; its errors are measured, not asserted small: the
    peers step through the impact, which is what carom compare shows."""
    _need(peer)
    result = compare("rod-drop-3d", ["carom", peer])
    m = result.engines[peer]["metrics"]
    assert m["velocity_error"] is not None
    assert math.isfinite(m["velocity_error"])
    assert result.engines[peer]["ms_per_step"] > 0.0
    written = write_comparison(result, tmp_path, plot=False)
    data = json.loads((tmp_path / "compare.json").read_text())
    assert written == ["compare.json", "compare.txt"]
    assert data["dimension"] == 3
    assert data["closed_form"].startswith("free fall")
    assert len(data["checks"][0]["omega_rad_s"]) == 3
    assert set(data["engines"]) == {"carom", peer}


def test_mujoco_refuses_a_concave_static_mesh():
    _need("mujoco")
    with pytest.raises(CaromError, match="convex hull"):
        compare("bowl", ["mujoco"], until=0.01)


@pytest.mark.parametrize("peer", PEERS)
def test_peers_turn_the_kinematic_drum_as_carom_does(peer):
    """The tumbler's drum turns at 25 deg/s about y: after each step every peer reports it
    where carom's kinematic motion puts it (Rapier: f32)."""
    _need(peer)
    spec = peer_scene("tumbler-3d")
    drum = int(spec.kinematic[0])
    sim = ENGINES[peer].start(spec)
    try:
        for _ in range(5):
            sim.step()
        x, _, q, w = sim.state()
        time = 5 * sim.dt
    finally:
        sim.close()
    where, turn = spec.kinematic_pose(drum, time)
    tol = 2e-6 if peer == "rapier3d" else 1e-12
    assert x[drum] == pytest.approx(where, abs=tol)
    sign = 1.0 if float(q[drum] @ turn) > 0 else -1.0
    assert sign * q[drum] == pytest.approx(turn, abs=tol)
    assert w[drum] == pytest.approx(spec.omega[drum], abs=tol)
    # the closed form: a turn of 5 dt x 25 deg/s about y
    angle = 2.0 * math.acos(min(1.0, abs(float(turn[0]))))
    assert angle == pytest.approx(5 * sim.dt * math.radians(25.0), rel=1e-9)


def test_2d_rigid_scenes_are_not_for_the_3d_peers():
    _need("pybullet")
    with pytest.raises(CaromError, match="rigid bodies in 3D only"):
        compare("rod-drop", ["pybullet"])


def test_each_dimension_of_rigid_bodies_has_its_own_peers():
    from carom.compare.driver import default_engines

    assert default_engines(2, "rigid") == ["carom", "pymunk", "box2d"]
    # (pooltool takes the 3D rigid scenes of balls on a cloth, and refuses the others by name)
    assert default_engines(3, "rigid") == ["carom", "pybullet", "mujoco", "rapier3d", "pooltool"]
    assert default_engines(3, "spheres") == ["carom", "pybullet", "mujoco"]
