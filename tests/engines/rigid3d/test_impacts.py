"""Exact single impacts in 3D (issue 14, item 4): a box landing on an edge and on a corner, a
rod hitting the floor, a spinning ball landing with friction; closed-form velocities and
spins with the full inertia tensor (Hecker's formula), independent of the time step; momentum
kept in free flight; energy never gained."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

import carom
from carom.engines.stepped.settings import RigidSettings
from carom.shapes3d import Box, Capsule, Hull, Sphere, rotation_matrix

G = 9.81
UP = np.array([0.0, 0.0, 1.0])


def _drop(shape, orientation, e: float, mu: float = 0.0, rate: float = 60.0, **kw) -> carom.World:
    world = carom.World(
        3, box=[4, 4, 4], boundary="open", gravity=[0, 0, -G], rigid=RigidSettings(rate=rate)
    )
    floor = carom.Material(e, friction=mu) if mu else carom.Material(e)
    world.add_plane([0, 0, 0], UP, material=floor)
    world.add_body(shape, [0, 0, 1.0], orientation=orientation, material=floor, **kw)
    return world


def _first_impact(world: carom.World, until: float = 1.0) -> np.void:
    """Run until the first collision's step is over; return its record."""
    t = world.time
    while True:
        t += world.rigid_settings.dt
        world.run(until=t, log=True)
        if len(world.collisions):
            return world.collisions[0]
        assert t < until, "no impact"


def _first_exact_impact(world: carom.World, until: float) -> bool:
    """Run until the step of the pair's first contact is over; whether it was an impact
    solved exactly (logged), not a contact the solver took (the velocities changed with no
    record: free flight without gravity keeps them) nor a miss (no contact by ``until``)."""
    t = world.time
    v0 = world.velocities.copy()
    while t < until:
        t += world.rigid_settings.dt
        world.run(until=t, log=True)
        if len(world.collisions):
            return True
        if not np.array_equal(world.velocities, v0):
            return False
    return False


def _world_inertia(world: carom.World, i: int = 0) -> np.ndarray:
    r = rotation_matrix(world.orientations[i])
    return r @ world.bodies.inertia_tensor[i] @ r.T


def _hecker(m: float, inertia: np.ndarray, r: np.ndarray, un: float, e: float) -> float:
    """Hecker's impulse magnitude on a body against a static floor, normal up:
    ``j = -(1 + e) u_n / (1/m + n . ((I^-1 (r x n)) x r))``."""
    rn = np.cross(r, UP)
    return -(1.0 + e) * un / (1.0 / m + rn @ np.linalg.solve(inertia, rn))


def _check_against_hecker(world: carom.World, record: np.void, e: float) -> None:
    """The impact's impulse is Hecker's, and the body's motion at the end of the step follows
    from it in closed form: ``v = v_before + P/m + g tau`` and ``L = I w = r x P`` (the body
    fell without turning, and free flight keeps ``L``). Round-off: 1e-12."""
    m = float(world.masses[0])
    tau = world.time - float(record["time"])  # free flight after the impact [s]
    v_end, w_end = world.velocities[0], world.angular_velocities[0]
    x_impact = world.positions[0] - (v_end * tau - 0.5 * np.array([0, 0, -G]) * tau**2)
    x_impact = world.positions[0] - v_end * tau - 0.5 * G * tau**2 * UP
    r = np.asarray(record["point"]) - x_impact
    un = float(record["un_before"])
    # before the impact the body had not turned: its inertia then is the start's
    start = rotation_matrix(world.bodies.orientation[0])
    inertia_start = start @ world.bodies.inertia_tensor[0] @ start.T
    j = _hecker(m, inertia_start, r, un, e)
    impulse = np.asarray(record["impulse"])
    assert impulse == pytest.approx(j * UP, rel=1e-12, abs=1e-12 * abs(j))
    assert float(record["un_after"]) == pytest.approx(-e * un, rel=1e-12)
    v_before = np.array([0.0, 0.0, un])
    assert v_end == pytest.approx(v_before + impulse / m - G * tau * UP, rel=1e-12, abs=1e-12)
    assert _world_inertia(world) @ w_end == pytest.approx(
        np.cross(r, impulse), rel=1e-11, abs=1e-12 * abs(j)
    )


def test_box_landing_on_an_edge_takes_heckers_impulse() -> None:
    # a 1 x 0.5 x 0.3 box turned 45 degrees about x: its lower long edge lands first, both
    # its ends at once. The two-point complementarity problem is solved exactly: by symmetry,
    # one impulse at the edge's middle, Hecker's j (frictionless, e = 0.5)
    q = [math.cos(math.pi / 8), math.sin(math.pi / 8), 0.0, 0.0]
    world = _drop(Box([1.0, 0.5, 0.3]), q, 0.5)
    record = _first_impact(world)
    assert abs(float(record["point"][0])) == pytest.approx(0.5, rel=1e-12)  # an end of it
    # the lever arm of the edge's middle: the record's point less its x
    m = float(world.masses[0])
    tau = world.time - float(record["time"])
    v_end = world.velocities[0]
    centre = world.positions[0] - v_end * tau - 0.5 * G * tau**2 * UP
    r = np.asarray(record["point"]) - centre
    r[0] = 0.0
    un = float(record["un_before"])
    q0 = rotation_matrix(q)
    j = _hecker(m, q0 @ world.bodies.inertia_tensor[0] @ q0.T, r, un, 0.5)
    assert np.asarray(record["impulse"]) == pytest.approx(j * UP, rel=1e-12, abs=1e-14)
    assert float(record["un_after"]) == pytest.approx(-0.5 * un, rel=1e-12)
    # it spins about x alone (a principal axis of the turned box): steady in free flight
    w_end = world.angular_velocities[0]
    assert w_end[1:] == pytest.approx([0.0, 0.0], abs=1e-12 * abs(w_end[0]))
    inertia = q0 @ world.bodies.inertia_tensor[0] @ q0.T
    assert inertia @ w_end == pytest.approx(np.cross(r, j * UP), rel=1e-12, abs=1e-14)


def _corner_down() -> list[float]:
    """A turn that puts the box's corner (-, -, -) lowest with a lever arm off every axis."""
    axis = np.array([1.0, -0.7, 0.2])
    axis /= np.linalg.norm(axis)
    half = 0.4
    return [math.cos(half), *(math.sin(half) * axis)]


def test_box_landing_on_a_corner_takes_heckers_impulse_with_the_full_tensor() -> None:
    # one corner lands: K = 1/m + [r]x I^-1 [r]x with the world tensor of a turned
    # 1 x 0.5 x 0.3 box (no principal axis along r or n); frictionless, e = 0.7
    world = _drop(Box([1.0, 0.5, 0.3]), _corner_down(), 0.7)
    record = _first_impact(world)
    _check_against_hecker(world, record, 0.7)


def test_rod_hitting_the_floor() -> None:
    # a capsule rod (1 m between cap centres, radius 0.05) tilted 30 degrees from vertical:
    # its lower cap lands; the classic j = -(1 + e) u_n / (1/m + d^2 / I) with d the
    # horizontal lever and I the rod's moment about the axis normal to the tilt plane
    tilt = math.radians(30.0)
    q = [math.cos(tilt / 2), 0.0, math.sin(tilt / 2), 0.0]
    world = _drop(Capsule(1.0, 0.05), q, 0.4)
    record = _first_impact(world)
    _check_against_hecker(world, record, 0.4)
    # the same in the textbook's scalar form
    i_yy = float(world.bodies.inertia_tensor[0][0, 0])  # capsule: I_xx = I_yy about centre
    d = 0.5 * math.sin(tilt)
    un = float(record["un_before"])
    j = -(1.4) * un / (1.0 / float(world.masses[0]) + d * d / i_yy)
    assert float(record["impulse"][2]) == pytest.approx(j, rel=1e-9)


@pytest.mark.parametrize("rate", [60.0, 250.0])
def test_impact_does_not_depend_on_the_time_step(rate: float) -> None:
    # the same corner landing at 60 and 250 Hz: the time of impact (conservative advancement
    # to 1e-9 of the reach) and the impulse agree to 1e-8, whatever the step
    world = _drop(Box([1.0, 0.5, 0.3]), _corner_down(), 0.7, rate=rate)
    record = _first_impact(world)
    reference = _drop(Box([1.0, 0.5, 0.3]), _corner_down(), 0.7, rate=1000.0)
    expected = _first_impact(reference)
    assert float(record["time"]) == pytest.approx(float(expected["time"]), rel=1e-8)
    assert np.asarray(record["impulse"]) == pytest.approx(np.asarray(expected["impulse"]), rel=1e-8)


@pytest.mark.parametrize("mu", [0.5, 0.05], ids=["sticks", "slides"])
def test_spinning_ball_landing_with_friction(mu: float) -> None:
    # a ball (R = 0.1) falling with 2 m/s along x and -30 rad/s about y, onto a floor of
    # restitution 0.6. The impulse acts at the contact point, so the angular momentum about
    # that point is kept: L_c = I w + m (R n) x v. Sticking (mu = 0.5): the contact point
    # stops, v_x' = (5 v_x + 2 R w_y) / 7 (the rolling rule). Sliding (mu = 0.05): the slip
    # keeps its sign and v_x loses mu (1 + e) |u_n|.
    radius, e = 0.1, 0.6
    world = _drop(
        Sphere(radius), None, e, mu=mu, velocity=[2.0, 0, 0], angular_velocity=[0, -30.0, 0]
    )
    record = _first_impact(world)
    m = float(world.masses[0])
    inertia = 0.4 * m * radius**2
    tau = world.time - float(record["time"])
    v = world.velocities[0] + G * tau * UP  # the velocity right after the impact
    w = world.angular_velocities[0]
    un = float(record["un_before"])
    assert v[2] == pytest.approx(-e * un, rel=1e-12)
    before = np.array([2.0, 0.0, un])
    w0 = np.array([0.0, -30.0, 0.0])
    # angular momentum about the contact point, kept through the impact (the point is
    # midway across the gap the time of impact leaves, below 1e-9 m: the arm is measured)
    centre = world.positions[0] - world.velocities[0] * tau - 0.5 * G * tau**2 * UP
    arm = centre - np.asarray(record["point"])
    assert arm == pytest.approx(radius * UP, abs=1e-9)
    assert inertia * w + m * np.cross(arm, v) == pytest.approx(
        inertia * w0 + m * np.cross(arm, before), rel=1e-12, abs=1e-15
    )
    slip = v + np.cross(w, -arm)  # the contact point's velocity
    if mu == 0.5:
        assert slip == pytest.approx([0.0, 0.0, -e * un], abs=1e-12)
        # rolling: v_x' = a w_y' with L_c = I w_y + m a v_x kept, so v_x' = (I w_y + m a
        # v_x) a / (I + m a^2): at a = R, (5 v_x + 2 R w_y) / 7 (the rolling rule), here
        # v_x = 2, w_y = -30 and a = R + 1e-10 (the arm measured above)
        a = float(arm[2])
        rolling = (inertia * -30.0 + m * a * 2.0) * a / (inertia + m * a * a)
        assert v[0] == pytest.approx(rolling, rel=1e-12)
        assert rolling == pytest.approx((5 * 2.0 + 2 * radius * -30.0) / 7.0, rel=1e-8)
    else:
        assert v[0] == pytest.approx(2.0 - mu * (1 + e) * abs(un), rel=1e-12)


def _pair(seed: int, e: float, mu: float) -> carom.World:
    """Two random hulls thrown at each other in free space, spinning."""
    rng = np.random.default_rng(seed)
    world = carom.World(3, box=[4, 4, 4], boundary="open")
    material = carom.Material(e, friction=mu) if mu else carom.Material(e)
    for side in (-1.0, 1.0):
        points = rng.normal(size=(10, 3)) * rng.uniform(0.05, 0.2, size=3)
        world.add_body(
            Hull(points),
            [0.6 * side, rng.uniform(-0.1, 0.1), rng.uniform(-0.1, 0.1)],
            velocity=[-side * rng.uniform(1.0, 3.0), *rng.normal(size=2) * 0.2],
            angular_velocity=rng.normal(size=3) * 5.0,
            orientation=rng.normal(size=4),
            material=material,
            density=rng.uniform(500.0, 2000.0),
        )
    return world


def _momenta(world: carom.World) -> tuple[np.ndarray, np.ndarray, float]:
    m = world.masses
    x, v, w = world.positions, world.velocities, world.angular_velocities
    linear = (m[:, None] * v).sum(axis=0)
    angular = np.cross(x, m[:, None] * v).sum(axis=0)
    energy = 0.5 * float(np.sum(m * np.sum(v * v, axis=1)))
    for i in range(world.n_bodies):
        spin = _world_inertia(world, i) @ w[i]
        angular = angular + spin
        energy += 0.5 * float(w[i] @ spin)
    return linear, angular, energy


@pytest.mark.needs_jit  # 25 engine runs: 90 s without the compiler, 2 s with it
@settings(max_examples=25, deadline=None)
@given(
    seed=st.integers(0, 10_000),
    e=st.floats(0.0, 1.0),
    mu=st.floats(0.0, 1.0),
)
def test_free_flight_impacts_keep_momentum_and_never_gain_energy(seed, e, mu) -> None:
    # Two random hulls meet in free space; the step of their first impact is solved exactly
    # (free flight to the time of impact, the impulse, free flight on). Each impact acts on
    # both at one point, equal and opposite, so linear momentum and angular momentum (about
    # the origin) are kept to round-off (free flight keeps both exactly); Newton's
    # restitution with e <= 1 and Coulomb friction never gain kinetic energy. (Later steps
    # may go to the soft solver, whose anchors stay fixed while the bodies move within a
    # step: it keeps linear momentum only.)
    world = _pair(seed, e, mu)
    p0, l0, e0 = _momenta(world)
    # A pair that first meets grazing (touching, closing slower than the restitution
    # threshold) is a resting contact by design (islands.plan): the solver takes it and logs
    # no impact, and this law is not the solver's; a pair that misses says nothing. Such
    # examples are left out (Hypothesis fails the test if it finds too few others).
    assume(_first_exact_impact(world, until=2.0))
    p1, l1, e1 = _momenta(world)
    scale = float(np.sum(world.masses)) * 3.0
    assert np.abs(p1 - p0).max() <= 1e-12 * scale
    assert np.linalg.norm(l1 - l0) <= 1e-12 * (np.linalg.norm(l0) + scale)
    assert e1 <= e0 * (1.0 + 1e-12)
