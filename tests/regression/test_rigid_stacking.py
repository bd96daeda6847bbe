"""A resting stack stands and never gains energy (issue 13, item 5, on a small pyramid and on
the card house).

The 10-row pyramid of Box2D's benchmark set (unit boxes side by side, rows stacked exactly
touching, friction 0.6, ground below) is run for 5 s at 60 Hz, 4 substeps. Soft contacts
compress under load (a contact's static deflection is its load over its effective mass times
(2 pi f)^2, 0.3 mm for one box on a 30 Hz contact), so the top box sinks by the sum over the
rows: measured 8 mm for 10 rows. The bound here, 2% of the box's size, holds that within a
factor 2.5; the 1% target for the 100-row pyramid is open work (docs/rigid.md).
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from carom.engines.rigid.driver import RigidEngine
from carom.engines.rigid.model import build_model, new_state
from carom.engines.stepped.settings import RigidSettings
from carom.observables import kinetic_energy, potential_energy
from carom.scene import find_scene, load_scene
from carom.shapes import Box

G = 10.0


def pyramid(rows: int) -> tuple[RigidEngine, np.ndarray]:
    centres = [
        ((i + 1) * 0.5 + (j - i) - 0.5 * rows, (2 * i + 1) * 0.5)
        for i in range(rows)
        for j in range(i, rows)
    ]
    n = len(centres)
    box = Box(1.0, 1.0)
    props = box.mass_properties(1.0)
    model = build_model(
        [box.pieces()] * n + [Box(200.0, 2.0).pieces()],
        np.array([0] * n + [1]),
        np.array([props.mass] * n + [math.inf]),
        np.array([props.inertia] * n + [math.inf]),
        np.zeros(n + 1, int),
        np.array([[0.0]]),
        np.array([[0.6]]),
        np.array([0.0, -G]),
    )
    x = np.array([*centres, (0.0, -1.0)])
    state = new_state(model, x, np.zeros((n + 1, 2)), np.zeros(n + 1), np.zeros(n + 1))
    return RigidEngine(model, state, RigidSettings(sleep=False)), x


def test_small_pyramid_stands_and_never_gains_energy() -> None:
    eng, start = pyramid(10)
    n = start.shape[0] - 1
    inertia = 1.0 / 6.0  # unit square of 1 kg: (1 + 1)/12

    def energy() -> float:
        x, v, _, w = eng.sample()
        kinetic = 0.5 * np.sum(v[:n] ** 2) + 0.5 * inertia * np.sum(w[:n, 2] ** 2)
        return float(kinetic + G * np.sum(x[:n, 1]))

    e0 = energy()
    highest = e0
    for _ in range(300):
        eng.step()
        highest = max(highest, energy())
    x, v, angle, _ = eng.sample()
    # energy: the stack only settles (round-off allowance 1e-12 of the potential energy)
    assert highest <= e0 + 1e-12 * abs(e0)
    top = n - 1
    assert np.hypot(*(x[top] - start[top])) < 0.02
    assert np.degrees(np.abs(angle[:n, 0]).max()) < 1.0
    assert np.abs(v[:n]).max() < 1e-6  # at rest


def test_card_house_settles_and_stands() -> None:
    # Box2D's card house (the built-in scene card-house): 40 cards 0.4 m x 2 mm, friction
    # 0.7, in five storeys of pairs leaning at 25 degrees with flat cards across. The start
    # has gaps (the pairs' tops ~4 mm apart, the flat cards ~3 mm above, the first storey
    # 2 mm above the table): closing them lowers each storey by under 1 cm, so the top card,
    # started at 1.662 m, settles above 1.61 m; a collapse would bring it below 0.5 m and turn
    # cards by tens of degrees. Energy (kinetic plus potential) only ever goes down.
    world = load_scene(find_scene("card-house")).build()
    b = world.bodies
    cards = np.flatnonzero(b.mobile)
    assert cards.size == 40
    top = cards[np.argmax(world.positions[cards, 1])]
    start_angle = world.orientations[cards].copy()

    def energy() -> float:
        x, v, w = world.positions, world.velocities, world.angular_velocities
        return kinetic_energy(b, v, w) + potential_energy(b, x, world.gravity)

    e0 = highest = energy()
    for _ in world.frames(4.0, 0.05):
        highest = max(highest, energy())
    assert highest <= e0 + 1e-12 * abs(e0)  # round-off of the potential energy
    assert world.positions[top, 1] > 1.61
    assert np.degrees(np.abs(world.orientations[cards] - start_angle).max()) < 1.0
    # asleep: stopped, as Box2D stops a sleeping body, with the kinetic energy they kept
    # counted as lost, so the ledger E0 = E + lost - given still closes to round-off
    assert np.all(world.velocities[cards] == 0.0)
    c = world.counters()
    assert energy() + c.energy_lost - c.energy_given == pytest.approx(e0, rel=1e-12)
