"""The solver's layout: contacts coloured so that no two of a group share a body that impulses
move, cut into groups of LANES lanes solved together (:func:`carom.engines.stepped.solver.
color_groups`), and a body with more contacts than there are colours (the overflow, each such
contact in a group of its own) still held up.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.engines.rigid.contacts import CONTACT_INTS, I_FLAGS
from carom.engines.stepped.rows import FLAG_EXACT, I_BODY_A, I_BODY_B
from carom.engines.stepped.settings import RigidSettings
from carom.engines.stepped.solver import COLORS, LANES, color_groups
from carom.shapes import Box

G = 9.81


def _contacts(pairs: list[tuple[int, int]], exact: tuple[int, ...] = ()) -> np.ndarray:
    ci = np.zeros((len(pairs) + 3, CONTACT_INTS), np.int64)  # spare rows past nc
    for m, (a, b) in enumerate(pairs):
        ci[m, I_BODY_A] = a
        ci[m, I_BODY_B] = b
        if m in exact:
            ci[m, I_FLAGS] = FLAG_EXACT
    return ci


def _check(lanes: np.ndarray, ci: np.ndarray, nc: int, inv_mass: np.ndarray) -> None:
    """Every contact not solved exactly is in one lane; no group has a moving body twice."""
    rows = lanes[lanes >= 0]
    expected = [m for m in range(nc) if not ci[m, I_FLAGS] & FLAG_EXACT]
    assert sorted(rows.tolist()) == expected
    for group in lanes:
        moving = [
            body
            for m in group[group >= 0]
            for body in ci[m, [I_BODY_A, I_BODY_B]].tolist()
            if inv_mass[body] > 0.0
        ]
        assert len(moving) == len(set(moving)), group


def test_random_contact_graphs_are_coloured_into_disjoint_groups() -> None:
    rng = np.random.default_rng(7)
    for _ in range(100):
        n = int(rng.integers(2, 40))
        inv_mass = np.where(rng.random(n) < 0.2, 0.0, 1.0)  # a fifth static or kinematic
        nc = int(rng.integers(0, 120))
        pairs = [tuple(sorted(rng.choice(n, 2, replace=False).tolist())) for _ in range(nc)]
        exact = tuple(np.flatnonzero(rng.random(nc) < 0.1).tolist())
        ci = _contacts(pairs, exact)  # type: ignore[arg-type]
        lanes = color_groups(ci, nc, inv_mass, I_FLAGS)
        assert lanes.shape[1] == LANES
        _check(lanes, ci, nc, inv_mass)


def test_contacts_with_one_static_body_share_groups_and_a_hub_overflows_into_single_lanes() -> None:
    spokes = COLORS + 6
    inv_mass = np.ones(spokes + 1)
    ci = _contacts([(0, k) for k in range(1, spokes + 1)])
    # body 0 moves: each of its contacts needs a colour of its own, so the first 64 fill one
    # lane of a group each and the other 6 get a group each (the overflow)
    lanes = color_groups(ci, spokes, inv_mass, I_FLAGS)
    _check(lanes, ci, spokes, inv_mass)
    assert lanes.shape[0] == spokes
    assert np.all(np.count_nonzero(lanes >= 0, axis=1) == 1)
    # body 0 static (the ground): every contact can share one colour, sixteen to a group
    inv_mass[0] = 0.0
    lanes = color_groups(ci, spokes, inv_mass, I_FLAGS)
    _check(lanes, ci, spokes, inv_mass)
    assert lanes.shape[0] == math.ceil(spokes / LANES)


def test_contacts_with_a_static_body_are_solved_after_those_between_two_moving_ones() -> None:
    # A stack: ground 0, boxes 1, 2, 3. As Box2D v3 colours them, colour 0 is kept for
    # contacts between two moving bodies, so a pass solves the boxes' contacts with each other
    # before the ground's (the ground's first in a pass made a stack of boxes sway more:
    # issue 45). Groups come colour by colour: (1, 2) in colour 0, then (0, 1) and (2, 3).
    inv_mass = np.array([0.0, 1.0, 1.0, 1.0])
    ci = _contacts([(0, 1), (1, 2), (2, 3)])
    lanes = color_groups(ci, 3, inv_mass, I_FLAGS)
    _check(lanes, ci, 3, inv_mass)
    assert lanes[0, 0] == 1
    assert np.all(lanes[0, 1:] == -1)
    assert sorted(lanes[1][lanes[1] >= 0].tolist()) == [0, 2]


@pytest.mark.needs_jit  # 4 s of 161 contacts: 70 s as plain Python
def test_a_plate_holds_more_boxes_than_there_are_colours() -> None:
    # 80 boxes (0.1 m, 1 kg) in a row centred on one plate (8.4 m x 0.1 m, 80 kg) on the
    # ground: the plate has 81 contacts, more than the 64 colours, so 17 of them are solved in
    # the overflow. A box whose contact went unsolved would fall through the plate.
    #
    # At rest a soft contact point's impulse per substep j = m g h / 2 (each box on its two
    # corners) holds the soft step's update at zero: 0 = -k (s_mass un + s_mass rate s) - s_imp j
    # with un = 0, so the point sinks by s = s_imp j / (k s_mass rate) = j / (k h omega^2)
    # (softness: s_mass = a2 a3, s_imp = a3, rate = omega / a1, a2 = h omega a1), where
    # 1/k = 1/m + 1/M + (r x n)^2/I + (r_p x n)^2/I_p is the point's effective mass: a box
    # corner at 0.05 m from its centre gives (r x n)^2/I = 0.0025 / (1/600) = 1.5 per kg, the
    # plate 1/80 and r_p^2 / I_p at the box's distance r_p from the plate's centre. So each box
    # rests s = g (2.5 + 1/80 + r_p^2 m/I_p) / (2 omega^2) below the plate's top, 0.35 mm at
    # omega = 2 pi 30 Hz. The stack converges to this exponentially (measured 2.5e-6 after 4 s
    # with sleep off); 1e-4 leaves room.
    still = RigidSettings(sleep=False)
    world = carom.World(2, [10.0, 10.0], boundary="open", gravity=[0.0, -G], rigid=still)
    world.add_plane([0.0, 0.0], [0.0, 1.0])
    plate = world.add_body(Box(8.4, 0.1), [5.0, 0.05], mass=80.0)
    boxes = [world.add_body(Box(0.1, 0.1), [0.892 + 0.104 * k, 0.15], mass=1.0) for k in range(80)]
    world.run(4.0)
    omega = 2.0 * math.pi * still.contact_hertz
    plate_inertia = 80.0 * (8.4**2 + 0.1**2) / 12.0
    r_p = world.positions[boxes, 0] - world.positions[plate, 0]
    sink = G * (2.5 + 1.0 / 80.0 + r_p**2 / plate_inertia) / (2.0 * omega**2)
    top = world.positions[plate, 1] + 0.05
    np.testing.assert_allclose(top + 0.05 - world.positions[boxes, 1], sink, rtol=1e-4)
    assert np.abs(world.velocities[boxes]).max() < 1e-5
    assert np.abs(world.orientations[boxes]).max() < 1e-5
