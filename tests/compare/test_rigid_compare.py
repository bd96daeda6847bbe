"""carom compare on rigid bodies: the scene as data, the closed form, the yardstick, the peers.

pymunk and Box2D come with the ``compare`` extra; each test of a peer is skipped, with the
reason, when that peer is not installed.
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
from carom.compare.rigid import RigidMonitor, RigidScene, _segments_cross
from carom.compare.yardstick import shape_coefficients
from carom.errors import CaromError
from carom.materials import Material
from carom.scene import Scene
from carom.shapes import Box
from carom.world import World


def _need(name):
    problem = ENGINES[name].missing()
    if problem is not None:
        pytest.skip(problem)


def test_the_rod_drop_closed_form_is_the_textbook_one():
    """A rod of length L and thickness h (I = m (L^2 + h^2) / 12) at angle theta, dropped from
    rest with its centre at height y0, lands on one corner, (L sin + h cos) / 2 below the
    centre; by free fall it arrives at v = sqrt(2 g drop); Hecker's impulse (PHYSICS.md section 2)
    there is j = (1 + e) m v / (1 + m r_x^2 / I), with r_x the corner's horizontal lever."""
    scene = peer_scene("rod-drop")
    assert isinstance(scene, RigidScene)
    check = compare(scene, ["carom"]).expected
    assert check is not None
    L, h, theta, y0, g, e, m = 1.0, 0.05, math.radians(30.0), 1.0, 9.81, 0.5, 0.05
    inertia = m * (L**2 + h**2) / 12.0
    low = (L * math.sin(theta) + h * math.cos(theta)) / 2.0  # the corner below the centre
    lever = -(L * math.cos(theta) - h * math.sin(theta)) / 2.0  # that corner's x offset
    drop = y0 - low
    v = math.sqrt(2.0 * g * drop)
    assert check.impact_time == pytest.approx(math.sqrt(2.0 * drop / g), rel=1e-14)
    j = (1.0 + e) * m * v / (1.0 + m * lever**2 / inertia)
    omega = lever * j / inertia  # r x (j y): r_x j
    dt = check.time - check.impact_time
    assert check.omega == pytest.approx(omega, rel=1e-13)
    assert check.velocity[1] == pytest.approx(-v + j / m - g * dt, rel=1e-13)
    assert check.velocity[0] == 0.0
    # mass from density 1 on a 1 m x 5 cm box
    assert scene.mass[1] == pytest.approx(m, rel=1e-15)


def test_carom_meets_the_rod_drop_closed_form():
    """The step is split at the impact found by conservative advancement; its tolerance
    (docs/rigid.md) bounds the error, far below any step's."""
    result = compare("rod-drop", ["carom"])
    assert isinstance(result, RigidComparison)
    m = result.engines["carom"]["metrics"]
    assert m["velocity_error"] < 1e-8
    assert m["omega_error"] < 1e-8
    assert m["energy_gain"] < 1e-12  # e = 0.5 loses energy; round-off only
    assert not m["tunnelled"]
    text = format_table(result)
    assert "Hecker" in text
    assert "carom" in text


def test_carom_stops_the_bullet():
    result = compare("bullet", ["carom"])
    m = result.engines["carom"]["metrics"]
    assert m["bodies_through_static"] == 0
    assert not m["tunnelled"]


def test_the_monitor_sees_a_centre_pass_through_a_wall():
    """Synthetic poses: a body jumps from one side of a static slab to the other in one step."""
    scene = peer_scene("bullet")
    monitor = RigidMonitor(scene, None, scene.dt)
    x = scene.position[: scene.n].copy()
    v, a, w = scene.velocity[: scene.n], scene.angle[: scene.n], scene.omega[: scene.n]
    monitor.observe(0.0, x, v, a, w)
    x[1, 0] = 3.5  # the wall is at x = 3 +- 0.005
    monitor.observe(scene.dt, x, v, a, w)
    assert monitor.result()["bodies_through_static"] == 1
    assert monitor.result()["tunnelled"]


def test_paths_crossing_a_convex_core():
    square = np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0], [0.0, 1.0]])
    before = np.array([[-1.0, 0.5], [-1.0, 2.0], [0.5, 0.5], [-1.0, 0.5]])
    after = np.array([[2.0, 0.5], [2.0, 2.0], [0.6, 0.6], [-0.1, 0.5]])
    assert _segments_cross(before, after, square).tolist() == [True, False, True, False]
    segment = np.array([[0.0, 0.0], [0.0, 1.0]])
    assert _segments_cross(before, after, segment).tolist() == [True, False, False, False]


def test_per_material_coefficients_reproduce_the_pairs():
    scene = peer_scene("rod-drop")
    table = np.array([[0.36]])
    product, _ = shape_coefficients(scene, table, "product", "x", "restitution")
    assert product[0] ** 2 == pytest.approx(0.36, rel=1e-15)
    geometric, _ = shape_coefficients(scene, table, "geometric", "x", "friction")
    assert geometric[0] == pytest.approx(0.36, rel=1e-15)
    top, _ = shape_coefficients(scene, table, "max", "x", "restitution")
    assert top[0] == 0.36


def test_a_pair_no_mixing_rule_gives_is_refused():
    """Two materials, 0.9 and 0.8 alone, 0.1 together: under max(c_a, c_b) the pair needs
    c_a <= 0.1, and then a against a cannot be 0.9."""

    def build():
        world = World(2, box=[6.0, 2.0], boundary="open")
        a = world.add_material(Material(restitution=0.9))
        b = world.add_material(Material(restitution=0.8))
        world.set_pair(a, b, 0.1)
        for x, mat in ((1.0, a), (2.5, a), (4.0, b)):
            world.add_body(Box(1.0, 1.0), [x, 1.0], material=mat)
        return world

    scene = RigidScene.from_world(build, "mixed", 0.1)
    with pytest.raises(CaromError, match=r"its restitution 0\.9 between materials 0 and 0"):
        shape_coefficients(scene, scene.restitution, "max", "Box2D", "restitution")
    coefficient, _ = shape_coefficients(scene, scene.restitution, "product", "pymunk", "e")
    assert coefficient[0] == pytest.approx(math.sqrt(0.9), rel=1e-15)  # a meets a


@pytest.mark.parametrize("peer", ["pymunk", "box2d"])
def test_peers_run_the_rigid_scenes(peer, tmp_path):
    """Each peer takes the same bodies; its errors are measured, not asserted small: the
    peers step through the impact (about 1e-2 here), which is what carom compare shows."""
    _need(peer)
    result = compare("rod-drop", ["carom", peer])
    m = result.engines[peer]["metrics"]
    assert m["velocity_error"] is not None
    assert math.isfinite(m["velocity_error"])
    assert result.engines[peer]["ms_per_step"] > 0.0
    # the same mass and inertia in every engine: before the impact all fall alike, so each
    # engine's rod turns by the same angle in the same flight; the check is after it
    written = write_comparison(result, tmp_path, plot=False)
    data = json.loads((tmp_path / "compare.json").read_text())
    assert written == ["compare.json", "compare.txt"]
    assert data["closed_form"].startswith("free fall")
    assert set(data["engines"]) == {"carom", peer}


def test_box2d_refuses_a_rounded_polygon():
    _need("box2d")
    scene = Scene.from_dict(
        {
            "world": {"dimension": 2, "box": [4.0, 2.0], "boundary": "open"},
            "bodies": [{"shape": "box", "size": [1.0, 1.0], "radius": 0.1, "positions": [[2, 1]]}],
            "run": {"until": 0.1},
        },
        source="rounded",
    )
    with pytest.raises(CaromError, match="rounded polygon"):
        compare(scene, ["box2d"])
