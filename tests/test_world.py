"""The World's API: input errors, materials and laws inside the engine, logs, stepping."""

from __future__ import annotations

import math
import tracemalloc

import numpy as np
import pytest

import carom
from carom import CaromError
from carom.engines.base import PARTNER_BODY, PARTNER_WALL
from carom.scene import layouts

EPS = float(np.finfo(np.float64).eps)


@pytest.mark.parametrize(
    ("build", "pattern"),
    [
        (lambda: carom.World(4, [1, 1, 1, 1]), r"dim must be the whole number 2 or 3"),
        (lambda: carom.World(2, [1.0, -1.0]), r"box\[1\] = -1.0 must be positive"),
        (lambda: carom.World(2, [1, 1], "torus"), r"boundary must be 'walls', 'periodic' or"),
        (lambda: carom.World(2, [1, 1], gravity=[0, 0, -9.8]), r"gravity must be 2 finite"),
        (lambda: carom.World(2, [1, 1], walls=1.5), r"restitution must lie"),
        (lambda: carom.World(2, [1, 1], t_c=-1.0), r"t_c must be a number of seconds >= 0"),
        (lambda: carom.World(2, [1, 1], combine="sum"), r"combine must be one of"),  # type: ignore[arg-type]
        (lambda: carom.Material(restitution=2.0), r"restitution must lie in \[0, 1\]"),
        (lambda: carom.Material(beta=0.2, friction=0.1), r"beta .* or friction"),
    ],
)
def test_bad_settings_are_refused(build, pattern: str) -> None:  # type: ignore[no-untyped-def]
    with pytest.raises(CaromError, match=pattern):
        build()


def test_bad_spheres_are_refused_and_named() -> None:
    world = carom.World(2, [1.0, 1.0])
    with pytest.raises(CaromError, match=r"radius must be positive .* radius\[1\] = -0.1"):
        world.add_spheres([[0.2, 0.2], [0.5, 0.5]], radius=[0.1, -0.1])
    with pytest.raises(CaromError, match=r"positions\[0\] = \[nan, 0.5\] is not finite"):
        world.add_spheres([[math.nan, 0.5]], radius=0.1)
    with pytest.raises(CaromError, match=r"velocities has 3 rows; expected 2"):
        world.add_spheres([[0.2, 0.2], [0.5, 0.5]], [[1.0, 0.0]] * 3, radius=0.1)
    with pytest.raises(CaromError, match=r"mass must be positive"):
        world.add_spheres([[0.5, 0.5]], radius=0.1, mass=0.0)
    # (these two were accepted: negative rotational energy, and an energy of NaN)
    with pytest.raises(CaromError, match=r"inertia_factor must lie in \(0, 1\]"):
        world.add_spheres([[0.5, 0.5]], radius=0.1, inertia_factor=-1.0)
    with pytest.raises(CaromError, match=r"angular_velocities\[0\] = \[0.0, 0.0, nan\] is not"):
        world.add_spheres([[0.5, 0.5]], radius=0.1, angular_velocities=math.nan)
    with pytest.raises(CaromError, match=r"angular_velocities must have shape \(2,\)"):
        world.add_spheres([[0.2, 0.5], [0.5, 0.5]], radius=0.1, angular_velocities=[1, 2, 3])


def test_overlapping_spheres_at_the_start_are_refused() -> None:
    world = carom.World(3, [1.0, 1.0, 1.0])
    world.add_spheres([[0.3, 0.5, 0.5], [0.45, 0.5, 0.5]], radius=0.1)
    with pytest.raises(CaromError, match=r"spheres 0 and 1 overlap by 0.05 m"):
        world.run(until=1.0)


def test_overlap_across_a_periodic_boundary_is_refused() -> None:
    # 125 spheres 4 m apart in a 20 m periodic box; sphere 0 moved to x = 0.15 and sphere 124
    # to x = 19.85 on the same line: 0.3 m apart through the x = 0 face, so they overlap by
    # 1 - 0.3 = 0.7 m (and nothing else comes within 1.85 m)
    side = 20.0
    x = (np.indices((5, 5, 5)).reshape(3, -1).T * 4.0 + 2.0).astype(float)
    x[0] = [0.15, 2.0, 2.0]
    x[124] = [19.85, 2.0, 2.0]
    world = carom.World(3, [side] * 3, "periodic")
    world.add_spheres(x, np.random.default_rng(3).normal(size=(125, 3)), radius=0.5)
    with pytest.raises(CaromError, match=r"spheres 0 and 124 overlap by 0.7 m"):
        world.run(until=1.0)


def test_touching_spheres_are_accepted() -> None:
    # exactly touching (Newton's cradle) is legal; round-off overlaps of 1e-17 m are not errors
    world = carom.World(3, [1.0, 1.0, 1.0])
    start = np.array([[0.1 * k + 0.2, 0.5, 0.5] for k in range(5)])
    world.add_spheres(start, radius=0.05)
    world.run(until=0.1)
    # at rest and touching: nothing approaches, so nothing collides and nothing moves
    assert world.stats.collisions == 0
    assert world.positions.tobytes() == start.tobytes()


def test_spheres_outside_the_box_or_behind_a_plane_are_refused() -> None:
    world = carom.World(2, [1.0, 1.0])
    world.add_spheres([[0.95, 0.5]], radius=0.1)
    with pytest.raises(CaromError, match=r"sphere 0 at \[0.95, 0.5\] .* reaches outside the box"):
        world.run(until=1.0)
    tilted = carom.World(2, [2.0, 2.0])
    tilted.add_plane([1.0, 1.0], [0.0, 1.0])
    tilted.add_spheres([[0.5, 0.5]], radius=0.1)
    with pytest.raises(CaromError, match=r"on the wrong side of plane 0"):
        tilted.run(until=1.0)


def test_periodic_box_too_small_and_bad_run_arguments() -> None:
    tiny = carom.World(2, [1.0, 1.0], "periodic")
    tiny.add_spheres([[0.5, 0.5]], radius=0.3)
    with pytest.raises(CaromError, match=r"box is too small for periodic boundaries"):
        tiny.run(until=1.0)
    world = carom.World(2, [1.0, 1.0])
    with pytest.raises(CaromError, match=r"no bodies"):
        world.run(until=1.0)
    world.add_spheres([[0.5, 0.5]], [[1.0, 0.0]], radius=0.1)
    world.run(until=1.0)
    with pytest.raises(CaromError, match=r"until must be a finite time >= the current time"):
        world.run(until=0.5)
    with pytest.raises(CaromError, match=r"until must be a finite time .* got '2'"):
        world.run(until="2")  # type: ignore[arg-type]
    world.run(until=np.int64(2))  # any real number is a time
    with pytest.raises(CaromError, match=r"frame_interval must be a positive time"):
        world.run(until=2.0, frame_interval=0.0)
    with pytest.raises(CaromError, match=r"callback needs frame_interval"):
        world.run(until=2.0, callback=print)
    with pytest.raises(CaromError, match=r"log must be True, False or body indices"):
        world.run(until=2.0, log=[5])


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize(
    "material", [carom.Material(0.7, beta=0.4), carom.Material(0.8, friction=0.2, beta0=0.1)]
)
def test_rough_laws_in_the_engine_match_collide(dim: int, material: carom.Material) -> None:
    # Two spinning spheres meet once; the engine's impulse kernel (core/laws.py) must give what
    # carom.collide gives for the same contact, to round-off.
    a = 0.1
    rng = np.random.default_rng(dim)
    spins = rng.normal(size=(2, 3)) * 5
    if dim == 2:
        spins[:, :2] = 0.0
    world = carom.World(dim, [2.0] * dim)
    x1 = np.array([0.5, 0.95, 0.97][:dim])
    x2 = np.array([0.9, 1.0, 1.02][:dim])
    world.add_spheres(
        [x1, x2],
        [[1.0, 0.1, -0.1][:dim], [-0.5, 0.0, 0.2][:dim]],
        radius=a,
        mass=[1.0, 2.0],
        material=material,
        angular_velocities=spins if dim == 3 else spins[:, 2],
    )
    while len(world.collisions) == 0:  # shell rebuilds may come first; then their collision
        world.run_events(log=True)
    event = world.collisions[0]
    assert event["kind"] == PARTNER_BODY
    assert (event["body"], event["partner"]) in ((0, 1), (1, 0))
    t = event["time"]
    y1 = x1 + np.array([1.0, 0.1, -0.1][:dim]) * t
    y2 = x2 + np.array([-0.5, 0.0, 0.2][:dim]) * t
    kwargs = (
        {"beta": material.beta}
        if material.beta is not None
        else {"friction": material.friction, "beta0": material.beta0}
    )
    w1, w2 = (spins[0], spins[1]) if dim == 3 else (spins[0, 2], spins[1, 2])
    expected = carom.collide(
        y1,
        [1.0, 0.1, -0.1][:dim],
        1.0,
        y2,
        [-0.5, 0.0, 0.2][:dim],
        2.0,
        e=material.restitution,
        w1=w1,
        w2=w2,
        radius1=a,
        radius2=a,
        **kwargs,
    )  # type: ignore[arg-type]
    tol = 64 * EPS * 10
    np.testing.assert_allclose(world.velocities, [expected.v1, expected.v2], atol=tol, rtol=0)
    got_spins = world.angular_velocities if dim == 3 else world.angular_velocities[:, 2]
    np.testing.assert_allclose(got_spins, [expected.w1, expected.w2], atol=tol * 50, rtol=0)


def test_pair_restitution_combines_and_can_be_overridden() -> None:
    # head-on, equal masses: v' = (1 - e)/2 v1 for the first sphere, e from the pair rule
    def first_velocity(world: carom.World) -> float:
        world.run(until=0.2)
        return float(world.velocities[0, 0])

    for combine, expected_e in (
        ("mean", 0.6),
        ("min", 0.4),
        ("max", 0.8),
        ("geometric", math.sqrt(0.32)),
        ("product", 0.32),
    ):
        world = carom.World(2, [2.0, 1.0], combine=combine)  # type: ignore[arg-type]
        world.add_spheres([[0.5, 0.5]], [[1.0, 0.0]], radius=0.1, restitution=0.8)
        world.add_spheres([[0.8, 0.5]], radius=0.1, restitution=0.4)
        # a few float64 operations on unit speeds: a few ulps of 1 (2.2e-16 each)
        assert first_velocity(world) == pytest.approx((1 - expected_e) / 2, abs=1e-15)
    world = carom.World(2, [2.0, 1.0])
    steel = world.add_material(carom.Material(0.8))
    rubber = world.add_material(carom.Material(0.4))
    world.set_pair(steel, rubber, 0.1)
    world.add_spheres([[0.5, 0.5]], [[1.0, 0.0]], radius=0.1, material=steel)
    world.add_spheres([[0.8, 0.5]], radius=0.1, material=rubber)
    assert first_velocity(world) == pytest.approx(0.45, abs=1e-15)  # as above


def test_log_can_be_filtered_and_switched_off() -> None:
    def world() -> carom.World:
        w = carom.World(2, [1.0, 1.0])
        w.add_spheres([[0.2, 0.5], [0.5, 0.5], [0.8, 0.2]], [[1, 0], [0, 0], [0, 1]], radius=0.05)
        return w

    everything = world()
    everything.run(until=1.0, log=True)
    only_two = world()
    only_two.run(until=1.0, log=[2])
    silent = world()
    silent.run(until=1.0, log=False)
    log = everything.collisions
    involves_two = (log["body"] == 2) | ((log["kind"] == PARTNER_BODY) & (log["partner"] == 2))
    assert involves_two.any()  # the filter has work to do
    assert not involves_two.all()
    assert only_two.collisions.tobytes() == log[involves_two].tobytes()
    assert len(silent.collisions) == 0
    assert silent.stats.collisions == everything.stats.collisions  # it still ran
    assert everything.describe_partner(PARTNER_WALL, 0) == "wall x-"
    assert everything.describe_partner(PARTNER_WALL, 3) == "wall y+"


def test_step_moves_to_the_next_event() -> None:
    world = carom.World(2, [1.0, 1.0])
    world.add_spheres([[0.5, 0.5]], [[1.0, 0.0]], radius=0.1)
    world.run_events(log=True)
    assert len(world.collisions) <= 1  # a shell rebuild may come first
    while len(world.collisions) == 0:
        world.run_events(log=True)
    # the wall x+ at 1 - 0.1: reached after 0.4 s
    assert world.time == pytest.approx(0.4, abs=1e-15)
    assert (world.collisions[0]["kind"], world.collisions[0]["partner"]) == (PARTNER_WALL, 1)


def _gas_2d() -> carom.World:
    return layouts.lattice_gas(2, 20, 0.3, seed=3)  # 400 disks: about 900 collisions a second


def test_collisions_are_not_kept_unless_asked() -> None:
    # regression: World.run kept every collision in memory by default (64 B each: 10^8
    # collisions needed 6.4 GB); now the default keeps none
    world = _gas_2d()
    world.run(until=5.0)
    assert world.stats.collisions > 1000
    assert len(world.collisions) == 0


@pytest.mark.needs_jit
def test_streamed_collisions_keep_memory_flat() -> None:
    # with on_collisions every collision passes through and nothing stays: a run of ten times
    # as many collisions allocates no more at its peak than a short one (the engine's log
    # buffer is fixed at 65536 records, and each block handed over is dropped after use)
    def peak(until: float) -> tuple[int, int]:
        world = layouts.lattice_gas(2, 40, 0.5, seed=3)  # 1600 disks
        world.prepare()
        seen = [0]

        def count(block: np.ndarray) -> None:
            seen[0] += block.size

        tracemalloc.start()
        world.run(until=until, on_collisions=count)
        _, top = tracemalloc.get_traced_memory()
        tracemalloc.stop()
        assert seen[0] == world.stats.collisions + world.stats.wall_collisions
        return top, seen[0]

    short, n_short = peak(60.0)
    long, n_long = peak(600.0)
    assert n_short > 4 * 65536  # the short run already fills the log buffer several times
    assert n_long > 9 * n_short
    # kept, the extra collisions would take 64 B each, (n_long - n_short) * 64 > 100 MB;
    # streamed, the peaks differ by less than one buffer's block, 65536 * 64 B = 4.2 MB
    assert abs(long - short) < 65536 * 64


def test_the_in_memory_log_is_bounded(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(carom.collision_log, "LOG_LIMIT", 100)
    world = _gas_2d()
    with pytest.warns(carom.CaromWarning, match=r"collision log is full \(100 collisions"):
        world.run(until=1.0, log=True)
    total = world.stats.collisions + world.stats.wall_collisions
    assert len(world.collisions) == 100
    assert world.collisions_dropped == total - 100
    assert np.all(np.diff(world.collisions["time"]) >= 0)  # the first 100, in time order
