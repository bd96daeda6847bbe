"""Pairs held in contact in an island solved exactly (a regression, issue 43's game loop).

A box kicked up into the box resting on it, with no restitution, stays pressed against it:
a contact held for a while, not an impact. The exact path used to meet such a pair again and
again at the same instant, each time with an impulse of round-off size (an approach of a few
ulps looks like an approach), up to the island's cap of about 270 impacts in one step, and
spent tens of milliseconds a step doing so (benchmarks/gameloop.py at 100 bodies: 14 ms a
frame). Now an approach within the round-off of the speeds it is computed from is a resting
touch, and a pair met with no impact, or a slow one, more than ``PAIR_LOOKS`` times in a step
ends its island's exact step (the solver takes the island from there).

Since the search follows a face as it turns (it no longer crawls at a turning face), a box
striking the wall corner-first with friction meets it again at once at its other corner, each
impact's friction turning that corner towards the wall: a converging run of ever slower
impacts (8.7 m/s down to 0.12 in twelve), which ends with the slow meetings' rule.
"""

from __future__ import annotations

import collections

import numpy as np
import pytest

import carom
from carom.engines.stepped.driver import SteppedEngine
from carom.engines.stepped.impacts import PAIR_LOOKS
from carom.materials import Material
from carom.shapes import Box
from carom.shapes3d import Box as Box3


@pytest.mark.parametrize("dim", [2, 3])
def test_boxes_kicked_into_each_other_meet_no_endless_impacts(dim: int) -> None:
    # nine 0.5 m boxes (0.25 kg in 2D, 0.125 kg in 3D) in a pit, e = 0, friction 0.6 (the
    # game loop benchmark's surfaces), three kicked up by 0.5 N s each frame for a second
    surface = Material(restitution=0.0, friction=0.6)
    size = [2.4, 10.0] if dim == 2 else [2.4, 10.0, 2.4]
    gravity = [0.0, -9.81] if dim == 2 else [0.0, -9.81, 0.0]
    world = carom.World(dim, size, gravity=gravity, boundary="walls", walls=surface)
    k = np.arange(9)
    at = np.column_stack((0.6 + 0.6 * (k % 3), 0.5 + 0.6 * (k // 3)))
    if dim == 3:
        at = np.column_stack((at, np.full(9, 1.2)))
    world.add_bodies(Box(0.5, 0.5) if dim == 2 else Box3([0.5, 0.5, 0.5]), at, material=surface)
    engine = world.build()
    assert isinstance(engine, SteppedEngine)
    for _ in range(60):
        engine.step()
    rng = np.random.default_rng(0)
    kick = np.zeros((3, dim))
    kick[:, 1] = 0.5
    impulses: list[np.ndarray] = []
    worst_slow = 0
    meetings = 0
    slow = min(1.0, 2.0 * 9.81 / 60.0)  # the engine's threshold for a slow meeting [m/s]
    for _ in range(60):
        engine.apply_impulses(rng.choice(9, size=3, replace=False), kick, None)
        records: list[np.ndarray] = []
        engine.step(records.append)
        if not records:
            continue
        log = np.concatenate(records)
        impulses.append(np.linalg.norm(log["impulse"], axis=1))
        speeds = collections.defaultdict(list)
        for body, partner, un in zip(
            log["body"].tolist(), log["partner"].tolist(), log["un_before"].tolist(), strict=True
        ):
            speeds[body, partner].append(-un)
        for approach in speeds.values():
            meetings = max(meetings, len(approach))
            worst_slow = max(worst_slow, sum(u < slow for u in approach))
    assert impulses, "no impact was solved exactly: the test no longer tests the exact path"
    # every impact logged changed something: the smallest real one here is 2e-8 N s; one
    # from an approach of round-off size (|u_n| ~ 1e-16 m/s, times an effective mass under
    # 0.25 kg) was under 1e-16 (the old path logged 5e-19)
    assert np.min(np.concatenate(impulses)) > 1e-15
    # a pair's slow meetings end at PAIR_LOOKS (the one that ends the island's step is
    # logged too); fast ones come from a new approach, at another corner or pushed by a
    # third body (twelve at the most here); the old path met one pair 337 times in a step
    assert worst_slow <= PAIR_LOOKS + 1
    assert meetings < 4 * PAIR_LOOKS
