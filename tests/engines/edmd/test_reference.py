"""The fast engine against the slow O(N^2) reference (carom/reference/edmd.py).

Two checks. (1) From the same start both produce the same sequence of events. A hard-sphere
gas is chaotic: a round-off difference of 1e-16 grows roughly tenfold per collision in the
dilute periodic systems here (measured), so the sequences are compared over the first events,
where the amplified difference is still below the 1e-12 asked for. (2) Shadowing, over many
events: after every event of the engine, the reference starts from the engine's exact state
and its first event must be the engine's next one, pair and time (1e-12 relative), so every
single prediction is checked with no chaos in between.
"""

from __future__ import annotations

import numpy as np
import pytest

import carom
from carom.engines.base import PARTNER_BODY, PARTNER_WALL
from carom.reference.edmd import reference_events

CASES = [
    (dim, periodic, gravity, e)
    for dim in (2, 3)
    for periodic, gravity in ((False, False), (False, True), (True, False))
    for e in (1.0, 0.7)
]


def random_system(dim: int, n: int, gravity: bool, seed: int):  # type: ignore[no-untyped-def]
    rng = np.random.default_rng(seed)
    box = np.full(dim, 4.0)
    radius = rng.uniform(0.15, 0.3, n)
    mass = rng.uniform(0.5, 2.0, n)
    x: list[np.ndarray] = []
    while len(x) < n:
        p = rng.uniform(0.35, 3.65, dim)
        if all(np.linalg.norm(p - q) > radius[len(x)] + radius[k] + 0.01 for k, q in enumerate(x)):
            x.append(p)
    v = rng.normal(size=(n, dim))
    g = np.array([0.0] * (dim - 1) + [-9.81]) if gravity else None
    return np.array(x), v, radius, mass, box, g


def make_world(dim, periodic, g, e, x, v, radius, mass, box):  # type: ignore[no-untyped-def]
    world = carom.World(dim, box, "periodic" if periodic else "walls", g, walls=e)
    for i in range(len(x)):
        world.add_spheres(x[i], v[i], radius=radius[i], mass=mass[i], restitution=e)
    return world


def same_partners(ref_a: int, ref_b: int, a: int, b: int) -> bool:
    if ref_b < 0:
        return (ref_a, ref_b) == (a, b)
    return {ref_a, ref_b} == {a, b}


def face_code(record: np.void, dim: int) -> int:
    """A collision's partner as the reference numbers it: a body, or ``-1 - face`` with the
    walls' faces 0 .. 2 dim - 1 and the planes after them."""
    kind, partner = int(record["kind"]), int(record["partner"])
    if kind == PARTNER_BODY:
        return partner
    return -1 - (partner if kind == PARTNER_WALL else 2 * dim + partner)


@pytest.mark.parametrize(("dim", "periodic", "gravity", "e"), CASES)
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_same_event_sequence(dim: int, periodic: bool, gravity: bool, e: float, seed: int) -> None:
    x, v, radius, mass, box, g = random_system(dim, 12, gravity, seed)
    n_events = 12 if periodic else 25
    ref = reference_events(
        x,
        v,
        radius,
        mass,
        box,
        periodic=periodic,
        gravity=g,
        e=e,
        wall_e=e,
        t_c=1e-6,
        n_events=n_events,
    )
    assert len(ref) == n_events
    world = make_world(dim, periodic, g, e, x, v, radius, mass, box)
    world.run(until=ref[-1].time * (1 + 1e-9), log=True)
    events = world.collisions
    assert len(events) == n_events
    for k, (r, f) in enumerate(zip(ref, events, strict=True)):
        assert same_partners(r.a, r.b, int(f["body"]), face_code(f, dim))
        # round-off (1e-16) amplified about tenfold per collision (measured, periodic 3D):
        # below 1e-12 for the first 8 events, and still far below 1e-9 at the 25th
        assert abs(f["time"] - r.time) <= (1e-12 if k < 8 else 1e-9) * r.time


@pytest.mark.parametrize(("dim", "periodic", "gravity", "e"), CASES)
def test_every_prediction_shadowed(dim: int, periodic: bool, gravity: bool, e: float) -> None:
    x, v, radius, mass, box, g = random_system(dim, 10, gravity, 7)
    world = make_world(dim, periodic, g, e, x, v, radius, mass, box)
    checked = 0
    while checked < 150:
        # synchronise: every body at the engine's time, exactly as the engine sees it
        now = world.time
        xs, vs = world.positions, world.velocities
        resting = world.resting
        ref = reference_events(
            xs,
            vs,
            radius,
            mass,
            box,
            periodic=periodic,
            gravity=g,
            e=e,
            wall_e=e,
            t_c=0.0,
            n_events=1,
            resting=resting,
        )
        before = len(world.collisions)
        while len(world.collisions) == before:  # skip neighbour-list rebuilds
            world.run_events(log=True)
        got = world.collisions[-1]
        expected_time = now + ref[0].time
        assert same_partners(ref[0].a, ref[0].b, int(got["body"]), face_code(got, dim))
        assert abs(got["time"] - expected_time) <= 1e-12 * max(expected_time, 1.0)
        checked += 1
