"""The event-driven engine against closed forms (PHYSICS.md sections 4 and 6)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.engines.base import PARTNER_BODY, PARTNER_PLANE, PARTNER_WALL
from tests.worlds import gas

EPS = float(np.finfo(np.float64).eps)
G = 9.81


def test_dropped_ball_rebounds_to_e_squared_k_h0() -> None:
    # A ball dropped from h0 hits the floor at sqrt(2 g h0); each bounce scales the speed by e,
    # so the k-th rebound rises to h_k = (e^k sqrt(2 g h0))^2 / (2 g) = e^(2k) h0 and lasts
    # 2 e^k sqrt(2 h0 / g) (PHYSICS.md section 6). Each bounce adds a few roundings: after
    # 30 bounces the relative error stays far below the 1e-9 asked for.
    h0, a, e = 1.0, 0.05, 0.8
    world = carom.World(3, [1.0, 1.0, 3.0], gravity=[0, 0, -G], walls=e)
    world.add_spheres([0.5, 0.5, a + h0], radius=a)
    world.run(until=10.0, log=True)  # Zeno: infinitely many bounces in 2 sqrt(2 h0/g)(1+e)/(1-e) s
    floor = world.collisions[
        (world.collisions["kind"] == PARTNER_WALL) & (world.collisions["partner"] == 4)
    ]  # face 4: the lower wall of z
    assert world.stats.wall_collisions == len(floor)
    u_after = floor["un_after"]
    bounces = 30
    k = np.arange(1, bounces + 1)
    heights = u_after[:bounces] ** 2 / (2 * G)
    np.testing.assert_allclose(heights, e ** (2 * k) * h0, rtol=1e-9, atol=0)
    durations = np.diff(floor["time"][: bounces + 1])
    np.testing.assert_allclose(durations, 2 * e**k * math.sqrt(2 * h0 / G), rtol=1e-9, atol=0)
    # first impact at sqrt(2 h0 / g)
    assert floor["time"][0] == pytest.approx(math.sqrt(2 * h0 / G), rel=8 * EPS, abs=0)
    # the run ended: the ball came to rest on the floor in finitely many events
    assert world.resting[0] == 4  # on the floor (face 4: z-)
    # at rest: the rest rule zeroes the normal speed and the ball never moved sideways; 1e-9
    # m/s is far below the last bounce it cut short, at most g t_c / 2 = 5e-6 m/s
    np.testing.assert_allclose(world.velocities[0], 0.0, atol=1e-9)
    # touching the floor: its centre at a, to round-off of 1 m (a few 1e-16 m); 1e-12 m is the
    # highest bounce the rest rule cuts short, g (t_c / 2)^2 / 2 = 1.2e-12 m
    assert world.positions[0, 2] == pytest.approx(a, abs=1e-12)
    # total time to rest is finite: t_rest = sqrt(2 h0/g) (1 + e)/(1 - e) (geometric series).
    # The ball rests once a bounce would last less than t_c; the bounces left out sum to at
    # most t_c e/(1 - e) < t_c/(1 - e).
    t_rest = math.sqrt(2 * h0 / G) * (1 + e) / (1 - e)
    assert abs(floor["time"][-1] - t_rest) <= world.settings.t_c / (1 - e)


def test_newtons_cradle_passes_momentum_to_the_last_ball() -> None:
    # Five equal balls touching in a row, e = 1, the first arriving at v: each impact between
    # equal masses exchanges velocities (section 1), so the momentum runs down the row and
    # only the last ball leaves, at v.
    a, v = 0.1, 2.0
    world = carom.World(3, [3.0, 1.0, 1.0])
    x0 = 1.0
    row = [[x0 + 2 * a * k, 0.5, 0.5] for k in range(5)]
    world.add_spheres([[0.3, 0.5, 0.5]], [[v, 0.0, 0.0]], radius=a)
    world.add_spheres(row[1:], radius=a)
    # ball 0 first touches ball 1 after (x0 + 2a - 2a - 0.3)/v = 0.35 s; stop before the wall
    world.run(until=0.5, log=True)
    velocities = world.velocities
    np.testing.assert_allclose(velocities[:4], 0.0, atol=8 * EPS * v)
    np.testing.assert_allclose(velocities[4], [v, 0.0, 0.0], atol=8 * EPS * v)
    pair_events = world.collisions[world.collisions["kind"] == PARTNER_BODY]
    assert len(pair_events) == 4
    # the strike at 0.35 s (the gap and speed above, to round-off: a few 1e-16 s), and the
    # three hand-overs at the same instant, between touching balls; 1e-12 s is generous
    assert pair_events["time"] == pytest.approx([0.35] * 4, abs=1e-12)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_1000_m_s_sphere_never_tunnels(dim: int) -> None:
    # A sphere at 1000 m/s in a 1 m box crosses it every millisecond: a time-stepped engine at
    # 60 Hz would be gone after one step. Here every wall and sphere contact is an exact
    # event: check on 2000 frames that it stays inside and never overlaps the other spheres.
    rng = np.random.default_rng(3)
    a = 0.02
    world = carom.World(dim, [1.0] * dim)
    direction = rng.normal(size=dim)
    world.add_spheres([0.5] * dim, 1000.0 * direction / np.linalg.norm(direction), radius=a)
    others = rng.uniform(0.1, 0.9, size=(20, dim))
    others = others[np.linalg.norm(others - 0.5, axis=1) > 4 * a]
    keep = [0]
    for i in range(1, len(others)):
        if np.all(np.linalg.norm(others[keep] - others[i], axis=1) > 2.5 * a):
            keep.append(i)
    world.add_spheres(others[keep], radius=a)
    worst_outside = 0.0
    worst_overlap = 0.0
    for frame in world.frames(until=0.2, frame_interval=1e-4, log=False):
        x = frame.positions
        worst_outside = max(worst_outside, float(np.max(a - x)), float(np.max(x + a - 1.0)))
        d = np.linalg.norm(x[:, None, :] - x[None, :, :], axis=-1) + np.eye(len(x)) * 10
        worst_overlap = max(worst_overlap, float(np.max(2 * a - d)))
    assert world.stats.wall_collisions > 100  # it really did bounce around
    assert worst_outside <= 1e-12  # round-off of positions of order 1 m
    assert worst_overlap <= 1e-12
    ke = 0.5 * float(np.sum(world.velocities**2))
    assert ke == pytest.approx(0.5 * 1000.0**2, rel=1e-12)  # elastic: energy kept


def test_ball_falls_onto_a_static_peg() -> None:
    # A ball above a static sphere (peg), released at rest: relative motion is accelerated
    # (quartic time of impact). Contact when the centre has fallen h - R:
    # t = sqrt(2 (h - R) / g), and an elastic rebound leaves at the impact speed g t.
    a, peg, h = 0.05, 0.1, 0.5
    world = carom.World(2, [1.0, 2.0], gravity=[0.0, -G])
    world.add_static_spheres([[0.5, 0.5]], radius=peg)
    world.add_spheres([[0.5, 0.5 + h]], radius=a)
    world.run(until=0.35, log=True)
    hit = world.collisions[0]
    t_hit = math.sqrt(2 * (h - a - peg) / G)
    # the engine polishes the quartic's root to round-off (geometry/toi.py): both the time and
    # the speed g t came out 1 eps off (measured); 16 eps leaves room for another libm
    assert hit["time"] == pytest.approx(t_hit, rel=16 * EPS, abs=0)
    assert hit["un_after"] == pytest.approx(G * t_hit, rel=16 * EPS, abs=0)
    assert world.positions[0].tolist()[0] == pytest.approx(0.5, abs=1e-15)  # straight up


def test_ball_lands_on_an_inclined_plane() -> None:
    # Plane through the origin with unit normal n; a ball released at rest at height above it:
    # the gap n.x - a closes under g.n, contact at t = sqrt(2 (n.x0 - a) / (-g.n)).
    n = np.array([-0.6, 0.8])
    a = 0.05
    world = carom.World(2, [2.0, 2.0], gravity=[0.0, -G])
    world.add_plane([1.0, 0.25], n, restitution=0.5)
    x0 = np.array([1.0, 1.5])
    world.add_spheres(x0, radius=a)
    world.run(until=0.5, log=True)
    gap = float(n @ (x0 - [1.0, 0.25])) - a
    t_hit = math.sqrt(2 * gap / (G * 0.8))
    # a quadratic root under constant acceleration: exact to round-off (measured 0 eps)
    assert world.collisions[0]["time"] == pytest.approx(t_hit, rel=16 * EPS, abs=0)
    assert (world.collisions[0]["kind"], world.collisions[0]["partner"]) == (PARTNER_PLANE, 0)
    # e = 0.5: the normal speed is halved
    assert world.collisions[0]["un_after"] == pytest.approx(
        -0.5 * world.collisions[0]["un_before"], rel=1e-14
    )


@pytest.mark.needs_jit
@pytest.mark.parametrize(("dim", "boundary"), [(3, "periodic"), (2, "walls")])
def test_elastic_gas_keeps_energy_and_never_overlaps(dim: int, boundary: str) -> None:
    # Elastic collisions conserve kinetic energy exactly; each collision rounds it by a few eps,
    # a random walk: after C collisions about sqrt(C) * few eps (1e6: ~1e-13) << 1e-10.
    world = gas(dim, 10 if dim == 3 else 30, 0.3, seed=1, boundary=boundary)
    ke0 = world.stats.kinetic_energy
    worst = 0.0
    collisions = 0
    while collisions < 1_000_000:
        world.run(until=world.time + 5.0, log=False)
        collisions = world.stats.collisions
        x = world.positions
        worst = max(worst, _worst_overlap(world, x))
    assert abs(world.stats.kinetic_energy - ke0) <= 1e-10 * ke0
    if boundary == "periodic":
        np.testing.assert_allclose(world.stats.momentum, 0.0, atol=1e-10)
    assert worst <= 1e-9  # of the sum of radii (= 1: unit diameters)


def _worst_overlap(world: carom.World, x: np.ndarray) -> float:
    """Largest overlap between any two spheres, by a cell search (sum of radii = 1)."""
    box = world.box
    periodic = world.boundary == "periodic"
    cells = np.floor(x / 1.0).astype(int)
    order = {}
    for i, c in enumerate(map(tuple, cells)):
        order.setdefault(c, []).append(i)
    worst = -1.0
    dim = x.shape[1]
    offsets = np.stack(np.meshgrid(*([[-1, 0, 1]] * dim), indexing="ij"), -1).reshape(-1, dim)
    ncell = np.floor(box).astype(int)
    for c, members in order.items():
        for off in offsets:
            nb = np.array(c) + off
            if periodic:
                nb %= ncell
            for j_list in [order.get(tuple(nb), [])]:
                for i in members:
                    for j in j_list:
                        if j <= i:
                            continue
                        d = x[i] - x[j]
                        if periodic:
                            d -= box * np.floor(d / box + 0.5)
                        worst = max(worst, 1.0 - float(np.sqrt(d @ d)))
    return worst


@pytest.mark.parametrize(
    ("dim", "material", "boundary"),
    [
        (3, carom.Material(restitution=0.8), "periodic"),
        (3, carom.Material(restitution=0.9, beta=0.3), "periodic"),
        (2, carom.Material(restitution=0.85, friction=0.2, beta0=0.4), "walls"),
    ],
)
def test_energy_lost_is_the_kinetic_energy_that_went(
    dim: int, material: carom.Material, boundary: str
) -> None:
    # stats.energy_lost sums, collision by collision, minus the work of each impulse,
    # J . (g_before + g_after) / 2 (and (1 - e^2) m u^2 / 2 at a wall); over a run it must equal
    # KE(0) - KE(t), translation and rotation, without gravity. Each collision rounds its
    # term by a few eps of its pair's energy, so the ledger closes to at worst n_collisions x
    # a few 1e-16 of the total: 1e-12 relative for the 1e3 to 5e3 collisions here (measured
    # about 1e-15).
    start = gas(dim, 12 if dim == 2 else 6, 0.3, seed=5, boundary=boundary)
    world = carom.World(dim, start.box, boundary, walls=0.7)  # type: ignore[arg-type]
    rng = np.random.default_rng(2)
    spins = rng.normal(size=(start.n_bodies, 3)) if dim == 3 else None
    world.add_spheres(
        start.positions, start.velocities, radius=0.5, material=material, angular_velocities=spins
    )
    ke0 = world.stats.kinetic_energy
    world.run(until=20.0, log=False)
    assert world.stats.collisions > 1000
    lost = world.stats.energy_lost
    assert lost > 0.05 * ke0  # the test means something: a good part of the energy went
    given = world.stats.energy_given  # by the parting floor (grazing impacts): ~1e-30 J here
    assert lost - given == pytest.approx(ke0 - world.stats.kinetic_energy, rel=1e-12, abs=0.0)
