"""Rigid bodies in a World (issue 13, item 6): add_body, the engine it picks, walls and planes
as static bodies, the energy ledger, checkpoints, and bad input refused.

Closed forms are derived where used; tolerances follow from the arithmetic.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.engines.base import PARTNER_PLANE, PARTNER_WALL
from carom.errors import CaromError
from carom.observables import kinetic_energy, potential_energy
from carom.shapes import Box, Capsule, Circle, Compound, Polygon, Segment

G = 9.81


def test_add_body_puts_the_shape_origin_where_asked_and_reports_the_centre_of_mass() -> None:
    # an L of two unit-density boxes: 2 x 1 with its centre at (1, 0.5) and 1 x 1 at (0.5, 1.5);
    # centroid = (2 (1, 0.5) + 1 (0.5, 1.5)) / 3 = (2.5/3, 2.5/3)
    shape = Compound([(Box(2.0, 1.0), (1.0, 0.5)), (Box(1.0, 1.0), (0.5, 1.5))])
    world = carom.World(2, [10.0, 10.0], boundary="open")
    i = world.add_body(shape, [3.0, 4.0], angle=math.pi / 2, density=2.0)
    c = np.array([2.5 / 3, 2.5 / 3])
    turned = np.array([-c[1], c[0]])  # a quarter turn anticlockwise
    np.testing.assert_allclose(world.positions[i], np.array([3.0, 4.0]) + turned, atol=1e-15)
    assert world.orientations[i] == pytest.approx(math.pi / 2, rel=1e-15)
    assert world.masses[i] == pytest.approx(6.0, rel=1e-15)  # area 3 m^2 at 2 kg/m^2
    # parallel axis: each box m (w^2 + h^2)/12 + m d^2 about the common centroid
    d1 = np.array([1.0, 0.5]) - c
    d2 = np.array([0.5, 1.5]) - c
    inertia = 4.0 * (4 + 1) / 12 + 4.0 * d1 @ d1 + 2.0 * (1 + 1) / 12 + 2.0 * d2 @ d2
    assert world.bodies.inertia[i] == pytest.approx(inertia, rel=1e-13)
    assert world.engine_name == "rigid"


def test_auto_runs_spheres_event_driven_and_anything_else_rigid() -> None:
    spheres = carom.World(2, [1.0, 1.0])
    spheres.add_spheres([[0.5, 0.5]], radius=0.1)
    assert spheres.engine_name == "edmd"
    spheres.add_body(Circle(0.1), [0.2, 0.2])
    assert spheres.engine_name == "rigid"
    forced = carom.World(2, [1.0, 1.0], engine="edmd")
    forced.add_body(Box(0.1, 0.1), [0.5, 0.5])
    with pytest.raises(CaromError, match=r"body 0 is not a sphere.*engine='rigid'"):
        forced.run(0.1)


def test_a_box_slides_down_an_incline_as_coulomb_says() -> None:
    # a box released on a plane at 30 deg with mu = 0.3 accelerates at a = g (sin - mu cos)
    # along it. The step is symplectic Euler over the substeps (h = dt / substeps): velocity
    # n h a exactly, distance a h^2 n (n + 1) / 2 (the sum of the velocities).
    theta, mu = math.radians(30.0), 0.3
    normal = np.array([-math.sin(theta), math.cos(theta)])
    down = -np.array([math.cos(theta), math.sin(theta)])
    world = carom.World(2, [10.0, 10.0], boundary="open", gravity=[0.0, -G])
    rough = carom.Material(0.0, friction=mu)
    world.add_plane([0.0, 0.0], normal, material=rough)
    start = -5.0 * down + 0.05 * normal
    world.add_body(Box(0.2, 0.1), start, angle=theta, material=rough)
    world.run(1.0)
    a = G * (math.sin(theta) - mu * math.cos(theta))
    settings = world.rigid_settings
    n = round(1.0 * settings.rate) * settings.substeps
    h = 1.0 / n
    # velocity: a few hundred float64 additions of O(1) numbers
    assert world.velocities[0] @ down == pytest.approx(a * n * h, rel=1e-9)
    # distance: to 1e-4 of it, the box settles its 5 mm slop in the first step
    assert (world.positions[0] - start) @ down == pytest.approx(
        a * h * h * n * (n + 1) / 2, rel=1e-4
    )
    # it slides, never tips: the soft contact lets the friction's moment tilt it by a few
    # 1e-4 rad (the two points' springs compressed unequally), a rigid box not at all
    assert world.orientations[0] == pytest.approx(theta, abs=1e-3)


def test_a_thrown_disk_meets_a_wall_at_the_right_time_with_e_v() -> None:
    # no gravity: a disk of radius 0.1 at x = 0.5 moving at 2 m/s meets the wall x+ = 1 at
    # t = 0.4 / 2 = 0.2 s and comes back at e * 2 = 1 m/s, not spinning (smooth wall)
    world = carom.World(2, [1.0, 1.0], walls=0.5)
    world.add_body(Circle(0.1), [0.5, 0.5], velocity=[2.0, 0.0], restitution=0.5)
    world.run(0.5, log=True)
    (impact,) = world.collisions
    assert impact["kind"] == PARTNER_WALL
    assert impact["partner"] == 1  # wall x+
    assert world.describe_partner(int(impact["kind"]), int(impact["partner"])) == "wall x+"
    # the time of impact: it falls on a step's end here, and is found to 1e-3 of the slop
    assert impact["time"] == pytest.approx(0.2, abs=1e-6)
    np.testing.assert_allclose(world.velocities[0], [-1.0, 0.0], rtol=0, atol=1e-12)
    assert world.angular_velocities[0, 2] == 0.0
    # after the impact: 0.3 s at 1 m/s back from x = 0.9
    assert world.positions[0, 0] == pytest.approx(0.9 - 0.3, abs=1e-6)
    assert world.counters().wall_collisions == 1


def test_a_plane_is_a_partner_of_its_own_kind() -> None:
    world = carom.World(2, [4.0, 4.0], boundary="open", gravity=[0.0, -G])
    world.add_plane([0.0, 1.0], [0.0, 1.0], restitution=0.5)
    world.add_body(Box(0.2, 0.2), [2.0, 2.0], restitution=0.5)
    world.run(1.0, log=True)
    first = world.collisions[0]
    assert first["kind"] == PARTNER_PLANE
    assert first["partner"] == 0
    # dropped from 0.9 m above the plane (1.1 - 0.2/2 - 1.0): it meets it at sqrt(2 h / g)
    # at sqrt(2 g h) and leaves flat at half that (a face landing square: no spin)
    # (the time of impact is found to 1e-3 of the linear slop, 5e-6 m, at 4.2 m/s: 1.2e-6 s)
    assert first["time"] == pytest.approx(math.sqrt(2 * 0.9 / G), abs=2e-6)
    assert first["un_after"] == pytest.approx(-0.5 * first["un_before"], rel=1e-12)


def test_the_energy_ledger_closes_to_round_off() -> None:
    # E0 = E + lost - given at every frame: exact impacts book their loss, free flight keeps
    # kinetic plus potential energy, and the solver's change is booked step by step
    world = carom.World(2, [4.0, 3.0], gravity=[0.0, -G], walls=carom.Material(0.5, friction=0.5))
    rng = np.random.default_rng(1)
    bouncy = carom.Material(0.6, friction=0.4)
    for k in range(30):
        world.add_body(
            Polygon.regular(int(rng.integers(3, 8)), 0.12),
            [0.3 + 0.25 * (k % 14), 0.4 + 0.3 * (k // 14)],
            velocity=rng.normal(size=2),
            angular_velocity=float(rng.normal()),
            material=bouncy,
        )

    def energy(frame: carom.Frame) -> float:
        b = world.bodies
        kinetic = kinetic_energy(b, frame.velocities, frame.angular_velocities)
        return kinetic + potential_energy(b, frame.positions, world.gravity)

    e0 = energy(world.frame())
    lost = 0.0
    for frame in world.frames(2.0, 0.25):
        c = world.counters()
        assert c.energy_lost >= lost  # dissipation never reverses
        lost = c.energy_lost
        # a few thousand O(10 J) terms summed: 1e-12 relative
        assert energy(frame) + c.energy_lost - c.energy_given == pytest.approx(e0, abs=1e-10)
    assert lost > 0.5 * e0 * 0.1  # the pile did lose energy: the check is not vacuous
    assert world.counters().collisions + world.counters().wall_collisions > 10


def test_a_kinematic_body_keeps_its_own_motion_and_pushes() -> None:
    world = carom.World(2, [4.0, 2.0], boundary="open")
    paddle = world.add_body(
        Box(0.1, 0.6), [0.5, 1.0], velocity=[1.0, 0.0], angular_velocity=0.0, kind="kinematic"
    )
    ball = world.add_body(Circle(0.1), [1.0, 1.0])
    world.run(1.0)
    np.testing.assert_allclose(world.positions[paddle], [1.5, 1.0], rtol=0, atol=1e-12)
    assert world.velocities[ball, 0] >= 1.0 - 1e-9  # pushed ahead, never through
    assert world.positions[ball, 0] > world.positions[paddle, 0] + 0.05 + 0.1 - 0.005


def test_a_checkpoint_continues_bit_for_bit(tmp_path) -> None:  # type: ignore[no-untyped-def]
    world = carom.World(2, [3.0, 3.0], gravity=[0.0, -G])
    grip = carom.Material(0.3, friction=0.6)
    for row in range(4):
        for k in range(4 - row):
            world.add_body(
                Box(0.3, 0.3), [0.5 + 0.15 * row + 0.3 * k, 0.15 + 0.3 * row], material=grip
            )
    world.add_body(Capsule(0.3, 0.1), [2.5, 2.0], angular_velocity=4.0, material=grip)
    world.run(0.5)
    world.save(tmp_path / "pile.npz")
    again = carom.World.load(tmp_path / "pile.npz")
    assert again.engine_name == "rigid"
    assert again.time == world.time
    world.run(1.5)
    again.run(1.5)
    assert np.array_equal(world.positions, again.positions)
    assert np.array_equal(world.velocities, again.velocities)
    assert np.array_equal(world.orientations, again.orientations)
    assert world.counters() == again.counters()


@pytest.mark.parametrize(
    ("build", "pattern"),
    [
        (
            lambda w: w.add_body(Box(0.2, 0.2), [0.5, 0.5], kind="floating"),
            r"kind must be one of \('dynamic', 'static', 'kinematic'\)",
        ),
        (lambda w: w.add_body("box", [0.5, 0.5]), r"shape must be a carom.shapes shape"),
        (lambda w: w.add_body(Box(0.2, 0.2), [math.nan, 0.5]), r"position\[0\] .* not finite"),
        (lambda w: w.add_body(Box(0.2, 0.2), [0.5, 0.5], angle=math.inf), r"angle must be finite"),
        (
            lambda w: w.add_body(Segment((0, 0), (1, 0)), [0.5, 0.5]),
            r"a segment with no area has no mass.*static",
        ),
        (
            lambda w: w.add_body(Box(0.2, 0.2), [0.5, 0.5], mass=0.0),
            r"mass must be",
        ),
        (
            lambda w: w.add_body(Box(0.2, 0.2), [0.5, 0.5], density=1.0, mass=1.0),
            r"give density .* or mass .* \(one of them\)",
        ),
        (
            lambda w: w.add_body(Box(0.2, 0.2), [0.5, 0.5], kind="static", mass=1.0),
            r"a static body is not moved by impacts and has no mass",
        ),
        (
            lambda w: w.add_body(Box(0.2, 0.2), [0.5, 0.5], kind="static", velocity=[1, 0]),
            r"a static body never moves.*kinematic",
        ),
    ],
)
def test_bad_bodies_are_refused_where_they_are_added(build, pattern: str) -> None:  # type: ignore[no-untyped-def]
    world = carom.World(2, [1.0, 1.0])
    with pytest.raises(CaromError, match=pattern):
        build(world)
    assert world.n_bodies == 0


@pytest.mark.parametrize(
    ("setup", "pattern"),
    [
        (
            lambda w: (
                w.add_body(Box(0.2, 0.2), [0.5, 0.5]),
                w.add_body(Box(0.2, 0.2), [0.6, 0.5]),
            ),
            r"body 0 and body 1 overlap by 0.1 m at the start",
        ),
        (
            lambda w: w.add_body(Box(0.2, 0.2), [0.95, 0.5]),
            r"body 0 and wall x\+ overlap by 0.05 m",
        ),
        (
            lambda w: w.add_body(Box(0.2, 0.2), [0.5, 0.5], material=carom.Material(0.5, beta=0.1)),
            r"tangential restitution.*friction=",
        ),
    ],
)
def test_bad_starts_are_refused_when_run(setup, pattern: str) -> None:  # type: ignore[no-untyped-def]
    world = carom.World(2, [1.0, 1.0])
    setup(world)
    with pytest.raises(CaromError, match=pattern):
        world.run(0.1)
    assert world.time == 0.0


def test_rigid_bodies_match_the_worlds_dimension_and_are_walled_or_open() -> None:
    with pytest.raises(CaromError, match=r"Box is a 2D shape .* this world is 3D"):
        carom.World(3, [1.0, 1.0, 1.0]).add_body(Box(0.1, 0.1), [0.5, 0.5, 0.5])
    periodic = carom.World(2, [1.0, 1.0], "periodic")
    periodic.add_body(Box(0.1, 0.1), [0.5, 0.5])
    with pytest.raises(CaromError, match=r"no periodic boundary"):
        periodic.run(0.1)
    open_spheres = carom.World(2, [1.0, 1.0], "open")
    open_spheres.add_spheres([[0.5, 0.5]], [3.0, 0.0], radius=0.1)
    assert open_spheres.engine_name == "rigid"  # no walls: the event-driven engine has none
    open_spheres.run(1.0)
    assert open_spheres.positions[0, 0] == pytest.approx(3.5, rel=1e-12)  # out, unwalled


def test_settings_assigned_after_the_engine_is_built_take_effect() -> None:
    # issue 45: they were kept in the world and ignored by the engine already built. A box
    # falls freely: after the new settings its step is 1 ms, and the fall goes on from where
    # it was (free fall is exact at any step: y = y0 - g t^2 / 2 to round-off)
    from carom.engines.stepped.settings import RigidSettings

    world = carom.World(2, [4.0, 40.0], gravity=[0.0, -9.81])
    world.add_body(Box(0.2, 0.2), [2.0, 30.0])
    world.run(0.1)
    assert world.engine is not None
    assert world.engine.dt == pytest.approx(1.0 / 60.0)
    world.engine_settings["rigid"] = RigidSettings(rate=1000.0)
    world.run(0.5)
    assert world.engine is not None
    assert world.engine.dt == pytest.approx(1e-3)
    t = world.time
    assert world.positions[0, 1] == pytest.approx(30.0 - 0.5 * 9.81 * t * t, abs=1e-9)
    with pytest.raises(CaromError, match=r"settings\['rigid'\]: the rigid engine takes"):
        world.engine_settings["rigid"] = 1.0 / 60.0
    with pytest.raises(CaromError, match=r"every engine keeps its settings"):
        del world.engine_settings["rigid"]


@pytest.mark.parametrize("dim", [2, 3])
def test_run_and_record_reach_every_time_asked(dim: int, tmp_path) -> None:  # type: ignore[no-untyped-def]
    # issue 45: run(0.01) with a step of 1/60 s stopped at t = 0 and said it had arrived;
    # now a shorter last step ends on the time asked. A box in free fall: its height is the
    # closed form y0 - g t^2 / 2 at each of those times (free flight is exact at any step;
    # the tolerance is round-off of 30 m)
    from carom.shapes3d import Box as Box3D

    g = 9.81
    box = [4.0, 40.0] if dim == 2 else [4.0, 4.0, 40.0]
    world = carom.World(dim, box, gravity=[0.0] * (dim - 1) + [-g])
    world.add_body(Box(0.2, 0.2) if dim == 2 else Box3D([0.2] * 3), [2.0] * (dim - 1) + [30.0])
    world.run(0.01)
    assert world.time == 0.01
    assert world.positions[0, -1] == pytest.approx(30.0 - 0.5 * g * 0.01**2, abs=1e-13)
    times = np.array([0.04, 0.045, 0.05])
    rec = world.record(times)
    assert np.array_equal(rec.times, times)
    fall = 30.0 - 0.5 * g * times**2
    np.testing.assert_allclose(rec.positions[:, 0, -1], fall, rtol=0.0, atol=1e-12)
    # a checkpoint taken between two whole steps continues bit for bit
    world.save(tmp_path / "fall.npz")
    again = carom.World.load(tmp_path / "fall.npz")
    assert again.time == world.time
    world.run(0.5)
    again.run(0.5)
    assert world.time == again.time == 0.5
    assert np.array_equal(world.positions, again.positions)
    assert np.array_equal(world.velocities, again.velocities)
    assert world.positions[0, -1] == pytest.approx(30.0 - 0.5 * g * 0.25, abs=1e-12)


def test_run_events_on_a_stepped_world_takes_that_many_steps() -> None:
    # once an OverflowError (the engine's target step from an infinite time): a stepped
    # engine's events are its steps, so the clock moves on by count steps of 1/60 s
    world = carom.World(2, [4.0, 4.0], gravity=[0.0, -9.81])
    world.add_body(Box(0.2, 0.2), [2.0, 2.0])
    world.run_events(5)
    assert world.time == pytest.approx(5.0 / 60.0, rel=1e-15)
