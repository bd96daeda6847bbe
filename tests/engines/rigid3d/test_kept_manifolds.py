"""Manifolds kept from step to step in 3D (carom.engines.rigid3d.contacts): a kept manifold
measures what a new one would, and a pair found apart is tested again before it can touch. A
checkpoint carries the kept manifolds, so a resumed run continues bit for bit
(tests/test_world_rigid3d.py, a settled pile)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom import CaromError
from carom.engines.stepped.settings import RigidSettings
from carom.shapes3d import Box, rotation_matrix

G = 9.81
#: the soft contact's angular frequency against a static body: twice 30 Hz [rad/s]
OMEGA = 2.0 * math.pi * 60.0


def _yaw(angle: float) -> list[float]:
    """The unit quaternion turning by ``angle`` [rad] about z."""
    return [math.cos(angle / 2), 0.0, 0.0, math.sin(angle / 2)]


def test_kept_manifold_of_a_box_gliding_on_a_slab_measures_what_a_new_one_would() -> None:
    # A 1 m cube glides without friction on a static slab (turned 30 degrees about z, so no
    # frame is the world's) at 12 mm/s while turning about z at 0.01 rad/s: 0.2 mm and
    # 0.14 mm of corner travel a step, so the manifold (box-box, separating axes and
    # clipping) is kept for a step or two and then made again, all run long. No tangential
    # force acts: the box goes on at constant velocity and spin (x = v t to round-off, and
    # yaw = w t). It sinks into the soft contact by the static deflection g / omega^2
    # (tests/engines/rigid3d/test_solver.py) only if every kept separation is the gap a new
    # manifold would measure (the faces are flat: the corners' gaps do not change as they
    # slide). A kept point sits midway between its two material points, which part by the
    # slide since the manifold was made (at most the 0.5 mm tolerance), so the normal
    # impulses act up to 0.25 mm off the corners: a torque of m g times that, which rocks
    # the box by nanometres (measured: sink 1.9e-5 relative from the closed form, vertical
    # speed 8e-10 m/s; manifolds made anew every step: 5e-12 and 3e-16). 1e-4 and 1e-8 m/s
    # bound that rocking; a separation measured wrong by as little as 0.1 um would show.
    world = carom.World(
        3, box=[8, 8, 8], boundary="open", gravity=[0, 0, -G], rigid=RigidSettings(sleep=False)
    )
    ice = carom.Material(0.0, friction=0.0)
    world.add_body(Box([4.0, 4.0, 0.2]), [0, 0, -0.1], orientation=_yaw(math.pi / 6),
                   kind="static", material=ice)  # fmt: skip
    v, spin = 0.012, 0.01
    world.add_body(Box([1.0, 1.0, 1.0]), [0, 0, 0.5], velocity=[v, 0, 0],
                   angular_velocity=[0, 0, spin], material=ice)  # fmt: skip
    world.run(until=2.0)
    x = world.positions[1]
    assert x[0] == pytest.approx(v * 2.0, rel=1e-12)
    assert abs(x[1]) < 1e-12
    assert 0.5 - x[2] == pytest.approx(G / OMEGA**2, rel=1e-4)
    assert abs(world.velocities[1, 2]) < 1e-8
    # the yaw to the turn's own integration error (measured 1.7e-8 relative, the same with
    # manifolds made anew every step)
    r = rotation_matrix(world.orientations[1])
    assert math.atan2(r[1, 0], r[0, 0]) == pytest.approx(spin * 2.0, rel=1e-7)


def test_kept_manifolds_change_a_resting_stack_by_less_than_their_tolerance() -> None:
    # Five cubes stacked on the floor, each turned a little, for 2 s: manifolds kept while
    # the bodies move less than 0.5 mm against made anew every step (manifold_reuse = 0).
    # A kept point lies within the tolerance of where a new manifold would put it, so the
    # two stacks settle to within a fraction of the tolerance. There is no closed form for
    # the difference: measured 3.3e-5 m; the bound is a fifth of the tolerance, 1e-4 m.
    runs = []
    for reuse in (0.1, 0.0):
        world = carom.World(3, box=[8, 8, 8], boundary="open", gravity=[0, 0, -G],
                            rigid=RigidSettings(sleep=False, manifold_reuse=reuse))  # fmt: skip
        world.add_plane([0, 0, 0], [0, 0, 1], material=carom.Material(0.0, friction=0.6))
        for k in range(5):
            world.add_body(Box([1.0, 1.0, 1.0]), [0.01 * k, 0, 0.5 + k],
                           orientation=_yaw(0.02 * k),
                           material=carom.Material(0.0, friction=0.6))  # fmt: skip
        world.run(until=2.0)
        runs.append(world.positions)
    tolerance = 0.1 * 0.005  # manifold_reuse times the linear slop [m]
    assert np.abs(runs[0] - runs[1]).max() < tolerance / 5


def test_a_pair_found_apart_is_tested_again_before_it_can_touch() -> None:
    # A rod 1 m long spins at 3 rad/s about its centre, held 0.4 m above a static slab, in
    # free space, frictionless and elastic; its ends reach 0.5 m, so one strikes the slab
    # at about 0.9 m/s. In the slab's frame (the piece that reaches further) the rod's centre
    # never moves: found apart by a separating axis, the pair is tested again only once the
    # turn alone, its reach times the change of the rotation, may have closed the gap. Were
    # the turn left out, the pair would never be tested again and the rod would pass
    # through the slab. The impact is isolated and exact: Newton's restitution with e = 1
    # keeps the kinetic energy to round-off (restitution_threshold below the impact speed:
    # above it impacts are solved exactly).
    world = carom.World(3, box=[8, 8, 8], boundary="open",
                        rigid=RigidSettings(restitution_threshold=0.2))  # fmt: skip
    bounce = carom.Material(1.0, friction=0.0)
    world.add_body(Box([4.0, 4.0, 0.2]), [0, 0, -0.1], kind="static", material=bounce)
    world.add_body(Box([1.0, 0.05, 0.05]), [0, 0, 0.4], angular_velocity=[0, 3.0, 0],
                   material=bounce)  # fmt: skip
    before = world.stats.kinetic_energy
    world.run(until=1.0)
    assert world.counters().wall_collisions + world.counters().collisions >= 1
    assert world.positions[1, 2] > 0.4  # thrown back up
    assert world.stats.kinetic_energy == pytest.approx(before, rel=1e-12)


def test_manifold_reuse_must_be_a_number_at_least_zero() -> None:
    with pytest.raises(CaromError, match=r"manifold_reuse must be a number >= 0 \[-\]; got -1"):
        RigidSettings(manifold_reuse=-1.0)
