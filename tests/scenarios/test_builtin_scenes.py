"""The built-in scenes: each loads, builds and runs for a short time, keeping what it should."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

import carom
from carom.observables import potential_energy
from carom.reference.exact import smooth_exact
from carom.scene import builtin_scenes, find_scene
from carom.studies.two_spheres import CASES, ROUND_OFF

CASE_SCENES = {f"case-{case.number}" for case in CASES}
EXPECTED = CASE_SCENES | {
    "billiards-break",
    "bouncing-ball",
    "gas-2d",
    "gas-3d",
    "galton-board",
    "granular-cooling",
    "hard-disk-gas",
    "hard-sphere-gas",
    "newtons-cradle",
    "rain-3d",
}
#: the rigid-body scenes (tests/scene/test_rigid_scenes.py runs them)
RIGID = {
    "bullet",
    "card-house",
    "dominoes",
    "pyramid",
    "large-pyramid",
    "many-pyramids",
    "rod-drop",
    "tumbler",
}
#: the 3D rigid-body scenes (tests/scene/test_rigid3d_scenes.py runs them; the impacts and
#: the bullets are carom compare's, tests/compare/test_rigid3d_compare.py)
RIGID3D = {
    "billiards-3d",
    "bowl",
    "box-corner-3d",
    "box-edge-3d",
    "bullet-3d",
    "cut-shot",
    "draw-shot",
    "dominoes-3d",
    "follow-shot",
    "pyramid-3d",
    "ring-toss",
    "rod-drop-3d",
    "spin-ball-3d",
    "stun-shot",
    "three-cushion",
    "tumbler-3d",
    "wall-and-ball",
}


#: the scenes with joints (tests/scene/test_joint_scenes.py runs them)
JOINTED = {"car", "chain-bridge", "cradle-on-strings", "pendulums", "ragdoll-pile", "rope-3d"}


def test_the_built_in_scenes_are_all_there() -> None:
    assert set(builtin_scenes()) == EXPECTED | RIGID | RIGID3D | JOINTED


@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_each_built_in_scene_runs_a_little(name: str) -> None:
    scene = carom.load_scene(find_scene(name))
    assert scene.scene["title"]
    assert scene.scene["description"]
    world = scene.build()
    ke0 = world.stats.kinetic_energy
    p0 = world.stats.momentum
    world.run(until=min(scene.run["until"], 0.3), log=False)
    assert world.time == min(scene.run["until"], 0.3)  # a run stops at its end exactly
    # nothing overlaps (to the engine's round-off bound, 1e-9 of the sum of radii) and every
    # moving body is inside a walled box
    x, r = world.positions, world.radii
    d = x[:, None] - x[None]
    if world.boundary == "periodic":
        d -= world.box * np.round(d / world.box)
    gap = np.linalg.norm(d, axis=-1) - (r[:, None] + r[None]) + np.eye(len(r)) * 1e9
    assert gap.min() > -1e-9 * 2 * r.max()
    if world.boundary == "walls":
        assert np.all(x - r[:, None] >= -1e-9)
        assert np.all(x + r[:, None] <= world.box + 1e-9)
    no_gravity = not np.any(world.gravity)
    elastic = all(m.restitution == 1.0 for m in world.materials) and all(
        m.restitution == 1.0 for m in world.walls
    )
    if no_gravity and elastic:
        # energy kept to round-off (1e-10 relative over these short runs)
        assert world.stats.kinetic_energy == pytest.approx(ke0, rel=1e-10, abs=0.0)
    if world.boundary == "periodic":
        np.testing.assert_allclose(world.stats.momentum, p0, rtol=0, atol=1e-9 * (1 + ke0))


def test_newtons_cradle_scene_hands_on_the_momentum() -> None:
    # e = 1, equal masses: each impact swaps velocities; the 1 m/s of the first ball ends in
    # the last one, the rest at rest (to round-off). The strike is at t = 0.3 s and the last
    # ball meets the wall at 0.75 s: look at 0.6 s.
    world = carom.load_scene(find_scene("newtons-cradle")).build()
    world.run(until=0.6, log=False)
    np.testing.assert_allclose(world.velocities[:, 0], [0, 0, 0, 0, 1.0], rtol=0, atol=1e-12)


@pytest.mark.parametrize("case", CASES, ids=lambda case: f"case-{case.number}")
def test_each_two_sphere_scene_is_its_case(case: carom.studies.two_spheres.Case) -> None:
    # The scene starts the spheres 0.5 s before the case's contact configuration: they meet
    # once, at t = 0.5 s, where the case says, and leave with the exact velocities of the
    # study (smooth_exact, rational arithmetic) to round-off (ROUND_OFF relative to the
    # approach speed); no wall is reached.
    scene = carom.load_scene(find_scene(f"case-{case.number}"))
    world = scene.build()
    e = case.restitutions[0]
    x0 = world.positions
    world.run(until=scene.run["until"], log=True)
    events = world.collisions
    assert world.stats.collisions == 1
    assert world.stats.wall_collisions == 0
    # the contact quadratic's root, and the centres flown there, to round-off: measured at
    # most 2 eps of 0.5 s and 4 eps of the metre-sized positions; 16 eps leaves room
    eps = float(np.finfo(np.float64).eps)
    assert events["time"][0] == pytest.approx(0.5, rel=0, abs=16 * eps * 0.5)
    v = np.array([case.v1, case.v2])
    contact = x0 + v * events["time"][0]
    np.testing.assert_allclose(
        contact[0] - contact[1], np.subtract(case.x1, case.x2), rtol=0, atol=16 * eps
    )
    v1, v2, _ = smooth_exact(case.x1, case.v1, case.m1, case.x2, case.v2, case.m2, e)
    speed = float(np.linalg.norm(v[0] - v[1]))
    np.testing.assert_allclose(world.velocities, [v1, v2], rtol=0, atol=ROUND_OFF * speed)


def test_an_unknown_scene_name_lists_the_built_in_ones() -> None:
    with pytest.raises(carom.SceneError, match=r"no-such: no such scene file, .* bouncing-ball"):
        find_scene("no-such")


def test_carom_scenes_lists_them() -> None:
    done = subprocess.run(
        [sys.executable, "-m", "carom", "scenes"],
        capture_output=True,
        text=True,
        stdin=subprocess.DEVNULL,
        timeout=120,
    )
    assert done.returncode == 0, done.stderr
    for name in EXPECTED:
        assert f"{name}\n" in done.stdout


@pytest.mark.needs_jit
@pytest.mark.parametrize("name", sorted(EXPECTED))
def test_each_built_in_scene_runs_to_its_end(name: str) -> None:
    # the whole run, as carom run does it, 100k events at a time: the clock must move on in
    # each step (a zero-time loop of events froze two scenes once), and the energy ledger
    # closes (E0 = E + dissipated - given by the parting floor, kinetic plus potential, to
    # 1e-9 of E0)
    scene = carom.load_scene(find_scene(name))
    world = scene.build()
    until = scene.run["until"]
    e0 = world.stats.kinetic_energy + potential_energy(world.bodies, world.positions, world.gravity)
    while world.time < until:
        before, events = world.time, world.stats.events_processed
        world.run_events(100_000)
        if world.stats.events_processed - events < 100_000:
            break  # no events left: everything rests
        assert world.time > before, f"{name}: 100000 events without time passing at {before} s"
        _assert_inside_and_apart(world)
    _assert_inside_and_apart(world)
    e = world.stats.kinetic_energy + potential_energy(world.bodies, world.positions, world.gravity)
    # each event rounds the energy and its loss by a few eps of e0; over the up to 4e5
    # events of a scene (galton-board) that is ~2e-10 of e0 even if every rounding went the
    # same way, and ~1e-12 for a random walk
    assert abs(e0 - e - world.stats.energy_lost + world.stats.energy_given) <= 1e-9 * abs(e0)


def _assert_inside_and_apart(world: carom.World) -> None:
    """No overlap and nothing through a wall, beyond round-off (1e-9 of the largest radius);
    a ball once fell through the Galton board's floor, 7 cm by the end."""
    x, r = world.positions, world.radii
    tol = 1e-9 * r.max()
    if world.boundary == "walls":
        assert np.all(x - r[:, None] >= -tol)
        assert np.all(x + r[:, None] <= world.box + tol)
    d = x[:, None] - x[None]
    if world.boundary == "periodic":
        d -= world.box * np.round(d / world.box)
    gap = np.linalg.norm(d, axis=-1) - (r[:, None] + r[None]) + np.eye(len(r)) * 1e9
    assert gap.min() > -tol
