"""An elastic box bouncing on a frictionless floor keeps its energy (issue 45, item 5).

With e = 1 and no friction, every impact is Newton's law solved exactly at its time of impact
and free flight between is exact, so the mechanical energy after 200 bounces is the energy at
the start to round-off: a few ulps an impact and a step, 1e-9 relative bounds it with room.

Found and fixed here: in 2D, two steps of the 200 each lost 8e-4 J. A bounce that ends just
before a step leaves the box touching the floor (within a tenth of the slop) and leaving it;
the 2D engine gave such a contact to the solver, whose soft contact took energy from it. A
contact that separates faster than a tenth of the restitution threshold has just bounced and
flies apart exactly, as the 3D engine already did. And in 3D, a tilted box rocking onto a
corner while touching the floor (0.8 m/s, under the restitution threshold) went to the solver,
which made it plastic: a touching contact closing faster than twice what gravity adds in a step
is an impact (a resting one starts its step hardly closing).

Not yet: the tilted box in 3D still loses 5e-4 J (3.4e-4 of its energy) in one step of 200
bounces, a graze: a corner touching the floor and leaving it at 0.016 m/s while the box spins at
8 rad/s, given to the solver as a resting contact, which meets the corner plastically later in
the step. (Rapier, e = 1 on the same box for the same 54.6 s, measured 2026-11-28: its energy
grew 8.3 times.)

A resting stack, sleep off: the 1e-6 J of issue 45 is met neither here nor by the peers
(benchmarks/stacks.py); what is tested is that it settles onto its closed-form rest.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.engines.stepped.settings import RigidSettings

G = 9.81


def _box_on_a_floor(dim: int, tilt: float) -> carom.World:
    elastic = carom.Material(1.0, friction=0.0)
    settings = RigidSettings(sleep=False)
    if dim == 2:
        from carom.shapes import Box

        world = carom.World(2, [10.0, 10.0], gravity=[0.0, -G], boundary="open", rigid=settings)
        world.add_body(Box(20.0, 1.0), [5.0, -0.5], kind="static", material=elastic)
        world.add_body(Box(1.0, 0.5), [5.0, 1.0], angle=tilt, material=elastic)
        return world
    from carom.shapes3d import Box as Box3D

    world = carom.World(3, [10.0] * 3, gravity=[0.0, 0.0, -G], boundary="open", rigid=settings)
    world.add_body(Box3D([20.0, 20.0, 1.0]), [5.0, 5.0, -0.5], kind="static", material=elastic)
    half = 0.5 * tilt
    turn = [math.cos(half), 0.6 * math.sin(half), 0.8 * math.sin(half), 0.0]
    world.add_body(Box3D([1.0, 0.5, 0.3]), [5.0, 5.0, 1.0], orientation=turn, material=elastic)
    return world


@pytest.mark.parametrize(
    ("dim", "tilt"),
    [(2, 0.0), (2, 0.3), (3, 0.0)],
    ids=["2d-flat", "2d-tilted", "3d-flat"],
)
def test_an_elastic_box_keeps_its_energy_over_200_bounces(dim: int, tilt: float) -> None:
    world = _box_on_a_floor(dim, tilt)
    engine = world.build()
    start = engine.energy()
    worst_step = 0.0
    before = start
    while engine.counters().collisions + engine.counters().wall_collisions < 200:
        engine.step()
        now = engine.energy()
        worst_step = max(worst_step, abs(now - before))
        before = now
        assert engine.time < 300.0, "fewer than 200 bounces in 300 s"
    # no step changes the energy by more than round-off, and none adds up over 200 bounces
    assert worst_step < 1e-9 * start
    assert abs(engine.energy() - start) < 1e-9 * start
    assert np.isfinite(engine.state.x).all()


def test_a_resting_stack_of_ten_cubes_sinks_to_its_soft_contacts_rest_and_no_further() -> None:
    """Ten unit cubes (1 kg) stacked exactly touching on a static floor, friction 0.6, sleep
    off, 60 Hz and 4 substeps.

    Found here: the clip of two faces that line up names the same corner by another pair of
    features from one step to the next, so the stack's warm start was lost at almost every step;
    it sank 34 mm (8.5 mm below its rest), sprang back and rocked: 0.575 J above an earlier
    minimum, 3.3 cm of sway, and a stack of 20 fell. A point whose feature id changed now takes
    the impulse of the cached point nearest it in A's body frame (within two slops).

    The rest, in closed form: a soft contact point's spring holds its load ``F`` at a depth
    ``F / (m_n omega^2)`` (the soft step's steady state, ``m_n`` the point's effective normal
    mass, ``omega = 2 pi f``). A cube corner has ``|r x n|^2 = 1/2`` and ``I = 1/6`` kg m^2, so
    ``m_n = 1/4`` kg against the floor (60 Hz, twice as stiff) and ``1/8`` kg between two cubes
    (30 Hz); four corners share each load. The energy's largest rise above an earlier minimum
    is the peers' on the same stack: Rapier 1.5e-4 J (Box2D v3 on the 2D stack: 6.1e-5 J); the
    1e-6 J of issue 45 is met by neither (docs/rigid.md).
    """
    from carom.shapes3d import Box as Box3D

    n = 10
    grip = carom.Material(0.0, friction=0.6)
    world = carom.World(
        3, [10.0, 10.0, 20.0], gravity=[0.0, 0.0, -G], boundary="open",
        rigid=RigidSettings(sleep=False),
    )  # fmt: skip
    world.add_body(Box3D([20.0, 20.0, 1.0]), [5.0, 5.0, -0.5], kind="static", material=grip)
    for k in range(n):
        world.add_body(Box3D([1.0, 1.0, 1.0]), [5.0, 5.0, 0.5 + k], material=grip)
    engine = world.build()
    energy = [engine.energy()]
    top = []
    sway = 0.0
    while engine.time < 30.0:
        engine.step()
        energy.append(engine.energy())
        top.append(engine.state.x[-1, 2] - (n - 0.5))
        sway = max(sway, float(np.abs(engine.state.x[1:, :2] - 5.0).max()))
    floor, pair = 2.0 * math.pi * 60.0, 2.0 * math.pi * 30.0
    rest = G * n / (4 * 0.25 * floor**2) + sum(G * k / (4 * 0.125 * pair**2) for k in range(1, n))
    # at rest (25.5 mm): the stack's remaining lean at 30 s lowers the top by L theta^2 / 2,
    # under 1e-5 m
    assert abs(top[-1] + rest) < 1e-5
    # it settles onto its rest without sinking past it (before: 8.5 mm past)
    assert min(top) > -rest - 1e-5
    assert sway < 0.02
    e = np.array(energy)
    assert (e - np.minimum.accumulate(e)).max() < 1e-3
