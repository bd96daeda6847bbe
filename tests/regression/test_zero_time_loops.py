"""Events that changed nothing and were predicted again at the same instant, forever.

Found running the rain-3d scene to its end (it hung at t = 0.537 s, then at 0.699 s): a ball
at the floor leaving it at 1e-16 m/s under gravity (the gap reopens for 2 u / g = 3e-17 s,
below the clock's resolution at 0.5 s), and a ball pressed onto another by gravity, or
meeting it at round-off approach speed, where the prediction says "now" and the impulse
law, in its own rounding, says "parting". Each test bounds the work by events, so a
regression fails instead of hanging.
"""

from __future__ import annotations

import numpy as np
import pytest

import carom
from carom.engines.edmd.settings import EdmdSettings
from carom.observables import potential_energy
from carom.scene import find_scene, load_scene


def _run_bounded(world: carom.World, until: float, max_events: int) -> None:
    """Advance past ``until``, ``max_events`` events at a time, failing if the clock stands
    still over that many events (a frozen clock is what these loops were)."""
    while world.time < until:
        before, events = world.time, world.stats.events_processed
        world.run_events(max_events)
        if world.stats.events_processed - events < max_events:
            return  # nothing left to happen: everything rests
        assert world.time > before, f"{max_events} events without time passing at {before} s"


@pytest.mark.needs_jit
def test_the_rain_reaches_its_pile() -> None:
    # The scene that hung, with the TC time it had then (1 us; the scene now uses 1 ms so
    # that its pile costs fewer events): past both places it froze. About 1.3 million events.
    scene = load_scene(find_scene("rain-3d"))
    scene.settings["edmd"] = EdmdSettings(t_c=1e-6)
    world = scene.build()
    _run_bounded(world, 0.72, 100_000)
    assert world.stats.collisions > 100_000


def test_a_ball_leaving_the_floor_at_round_off_speed_comes_to_rest() -> None:
    # On the floor (z = r), moving up at 1e-16 m/s under g: it comes back within t_c, so it
    # rests there (the rule for impacts), not bouncing within a tick of the clock.
    world = carom.World(3, [1.0, 1.0, 1.0], gravity=[0.0, 0.0, -9.81], walls=0.6)
    world.add_spheres([[0.5, 0.5, 0.04]], [[0.0, 0.0, 1e-16]], radius=0.04)
    _run_bounded(world, 1.0, 1000)
    assert world.resting[0] == 4  # the floor: face 2 * axis 2
    assert world.positions[0, 2] == 0.04


def test_a_ball_pressed_onto_a_resting_ball_does_not_freeze_the_clock() -> None:
    # A ball dropped onto one resting on the floor, slightly off centre: hard spheres have no
    # resting contact, so the upper one rattles at the TC scale (t_c = 1 ms here) and rolls
    # off; the run reaches its end in a bounded number of events, with no overlap beyond
    # round-off (1e-9 of a radius) and energy never gained beyond the TC kicks' bound
    # (m g^2 t_c^2 / 32 each: 3e-6 J per kick here, counted in the ledger).
    tc = 1e-3
    world = carom.World(3, [1.0, 1.0, 1.0], gravity=[0.0, 0.0, -9.81], walls=0.5, t_c=tc)
    world.add_spheres([[0.5, 0.5, 0.05], [0.51, 0.5, 0.3]], radius=0.05, restitution=0.5)
    e0 = world.stats.kinetic_energy + potential_energy(world.bodies, world.positions, world.gravity)
    _run_bounded(world, 3.0, 10_000)
    x = world.positions
    assert np.linalg.norm(x[0] - x[1]) > 0.1 * (1 - 1e-9)
    assert np.all(x[:, 2] >= 0.05 * (1 - 1e-9))
    e = world.stats.kinetic_energy + potential_energy(world.bodies, x, world.gravity)
    # the energy ledger closes: E0 = E + dissipated - given, to round-off of the total
    assert abs(e0 - e - world.stats.energy_lost + world.stats.energy_given) < 1e-9 * e0


def test_a_grazing_plastic_impact_ends() -> None:
    # e = 0 and a glancing approach: after the impact the normal speed is zero, and only
    # round-off decides whether they are "approaching"; they must part, once.
    world = carom.World(2, [4.0, 4.0])
    world.add_spheres(
        [[1.0, 2.0], [2.0, 2.0 + 0.2 - 1e-13]],
        [[1.0, 0.0], [0.0, 0.0]],
        radius=0.1,
        restitution=0.0,
    )
    _run_bounded(world, 1.5, 1000)
    assert world.stats.collisions >= 1
    assert world.stats.collisions <= 2
