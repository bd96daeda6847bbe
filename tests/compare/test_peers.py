"""Each engine set up as its documentation says, run through the same yardstick.

The peers come with the ``compare`` extra (``make test`` installs it); each test of a peer is
skipped, with the reason, when that peer is not installed.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from carom.compare import compare
from carom.compare.driver import peer_scene
from carom.compare.engines import ENGINES
from carom.scene import Scene
from carom.studies.two_spheres import ROUND_OFF

PEERS = ["pymunk", "pybullet", "mujoco"]


def _need(name):
    problem = ENGINES[name].missing()
    if problem is not None:
        pytest.skip(problem)


def _head_on(restitution):
    """Two equal spheres meeting head-on at 2 m/s, between steps of every peer (the contact
    at t = 0.3031 s is on no grid of 1/60, 1/240 or 0.002 s)."""
    return Scene.from_dict(
        {
            "world": {"dimension": 2, "box": [3.0, 1.0]},
            "materials": [{"name": "m", "restitution": restitution}],
            "bodies": [
                {
                    # the gap 0.3031 s x 3 m/s closes at t = 0.3031 s
                    "positions": [[0.5, 0.5], [0.5 + 0.2 + 3 * 0.3031, 0.5]],
                    "velocities": [[2.0, 0.0], [-1.0, 0.0]],
                    "radius": 0.1,
                    "material": "m",
                }
            ],
            "run": {"until": 0.6, "frame_interval": 0.01},
        }
    )


@pytest.mark.parametrize("case", range(1, 8))
def test_carom_is_exact_on_every_two_sphere_case(case):
    # the target: carom's post-collision velocities and energy equal the closed
    # form (rational arithmetic) to round-off, ROUND_OFF = 64 ulps of the approach speed
    result = compare(f"case-{case}", ["carom"])
    metrics = result.engines["carom"]["metrics"]
    assert metrics["velocity_error"] <= ROUND_OFF
    assert abs(metrics["energy_error"]) <= ROUND_OFF
    assert metrics["max_penetration"] == 0.0
    assert not metrics["tunnelled"]


def test_carom_is_exact_on_newtons_cradle():
    metrics = compare("newtons-cradle", ["carom"]).engines["carom"]["metrics"]
    assert metrics["velocity_error"] <= ROUND_OFF
    assert abs(metrics["energy_error"]) <= ROUND_OFF
    # the row touches from the start: its gaps are zero to round-off of the positions
    assert metrics["max_penetration_per_radius"] <= 8 * 2.0**-52


@pytest.mark.parametrize("peer", PEERS)
@pytest.mark.parametrize("restitution", [1.0, 0.5])
def test_each_peer_bounces_with_the_restitution_asked_for(peer, restitution):
    _need(peer)
    spec = peer_scene(_head_on(restitution), name="head-on")
    result = compare(spec, ["carom", peer])
    run = result.engines[peer]
    assert run["version"] == ENGINES[peer].version()
    # a peer takes whole steps of dt_s, so it stops within one step of the scene's end
    assert run["simulated_s"] == pytest.approx(0.6, rel=0, abs=run["dt_s"])
    assert run["wall_s"] > 0.0
    assert run["steps"] == spec.steps(run["dt_s"])
    metrics = run["metrics"]
    # equal masses: the relative velocity turns from 3 m/s to -3 e m/s. No peer is exact
    # (soft contacts, position correction, a fixed step): measured errors are 0 to 1.5% of
    # the approach speed. 0.1 separates that from a coefficient set wrongly, e.g. e instead
    # of sqrt(e) per surface under a product rule, which is off by (e - e^2) 3 / 2 / 3 = 12.5%
    # at e = 0.5 (and at e = 1 both agree, so the elastic case checks the set-up itself).
    assert metrics["velocity_error"] < 0.1
    assert math.isfinite(metrics["energy_error"])
    assert metrics["samples"] == run["steps"] + 1
    assert result.engines["carom"]["metrics"]["velocity_error"] <= ROUND_OFF


def test_pymunk_settings_are_recorded():
    _need("pymunk")
    run = compare(peer_scene(_head_on(0.64), name="h"), ["pymunk"]).engines["pymunk"]
    settings = run["settings"]
    assert settings["dt_s"] == 1 / 60
    # the product of the two circles' elasticities is the pair's restitution
    assert settings["body_elasticity"] == [pytest.approx(0.8, rel=1e-15)]
    assert settings["collision_slop_m"] == pytest.approx(0.01 * 0.1, rel=1e-6)
    assert settings["friction"] == 0.0
    assert settings["damping"] == 1.0


def test_pybullet_settings_are_recorded():
    _need("pybullet")
    settings = compare(peer_scene(_head_on(0.64), name="h"), ["pybullet"]).engines["pybullet"][
        "settings"
    ]
    info = settings["first_body_dynamics_info"]
    assert settings["dt_s"] == 1 / 240
    # sqrt(0.64), stored in double precision: within an ulp of 0.8 (1.4e-16 relative)
    assert info["restitution"] == pytest.approx(0.8, rel=1e-15)
    assert info["lateral_friction"] == 0.0
    assert settings["linear_angular_damping"] == 0.0


def test_mujoco_damping_gives_the_restitution_of_a_damped_oscillator():
    _need("mujoco")
    from carom.compare.engines.mujoco_engine import damping_ratio

    for e in (0.9, 0.5, 0.1):
        zeta = damping_ratio(e)
        # a linear spring-damper released at contact rebounds with exp(-pi z / sqrt(1 - z^2));
        # the round trip through log, sqrt and exp costs a few ulps, times |ln e| <= 2.3 for
        # the exponential: under 1e-14
        assert math.exp(-math.pi * zeta / math.sqrt(1 - zeta**2)) == pytest.approx(e, rel=1e-14)
    assert damping_ratio(1.0) == 0.0
    assert damping_ratio(0.0) == 1.0
    settings = compare(peer_scene(_head_on(0.5), name="h"), ["mujoco"]).engines["mujoco"][
        "settings"
    ]
    stiffness, damping = settings["solref_body_first"]
    # MuJoCo keeps solref in double precision: the same three operations, a few ulps
    assert stiffness == pytest.approx(-1 / (2 * 0.002) ** 2, rel=1e-15)
    assert -damping == pytest.approx(2 * damping_ratio(0.5) * math.sqrt(-stiffness), rel=1e-14)


@pytest.mark.parametrize(
    ("scene", "peers"), [("gas-2d", ["pymunk"]), ("gas-3d", ["pybullet", "mujoco"])]
)
def test_a_small_gas_runs_in_every_peer(scene, peers):
    for peer in peers:
        _need(peer)
    result = compare(scene, ["carom", *peers], until=0.05)
    carom = result.engines["carom"]["metrics"]
    # elastic: energy conserved to round-off over ~1000 bodies' sums (a few hundred ulps)
    assert abs(carom["energy_error"]) < 1e-13
    assert carom["max_penetration"] <= 1e-9
    assert not carom["tunnelled"]
    for peer in peers:
        metrics = result.engines[peer]["metrics"]
        assert math.isfinite(metrics["energy_error"])
        assert metrics["bodies_through_walls"] == 0  # slow bodies, solid walls


def test_a_2d_scene_stays_in_its_plane_in_3d_engines():
    for peer in ("pybullet", "mujoco"):
        _need(peer)
        sim = ENGINES[peer].start(peer_scene("case-4"))
        try:
            for _ in range(300):
                sim.step()
            x, v = sim.state()
            assert x.shape == (2, 2)
            assert np.all(np.isfinite(v))
        finally:
            sim.close()
