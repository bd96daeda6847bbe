"""A ball alone on a level cloth moves in closed form: the same at any rate, and the same as
the sliding-then-rolling motion written out (carom.engines.rigid3d.cloth)."""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

import carom
from carom.engines.stepped import islands
from carom.engines.stepped.settings import RigidSettings
from carom.shapes3d import Box, Sphere

G = 9.81
R = 0.028575  # a pool ball: radius [m], mass [kg]
M = 0.17
MU = 0.2  # the billiards-3d scene's cloth: friction [-], rolling resistance [m]
C = 3e-4
K = 0.4  # I / (m R^2) of a solid ball
UP = np.array([0.0, 0.0, 1.0])

#: shots of one ball: its velocity [m/s] and spin [rad/s] as the cue leaves it
SHOTS = {
    "stun": ([1.0, 0.0, 0.0], [0.0, 0.0, 0.0]),  # no spin: slides, then rolls at 5/7
    "follow": ([1.0, 0.0, 0.0], [0.0, 2.5 / R, 0.0]),  # topspin: speeds up to roll
    "draw": ([1.0, 0.0, 0.0], [0.0, -4.0 / R, 0.0]),  # backspin: stops and comes back
    "massé": ([0.6, 0.8, 0.0], [12.0, -30.0, 40.0]),  # oblique, with side spin
}


def closed_form(v0: np.ndarray, w0: np.ndarray, t: float) -> tuple[np.ndarray, ...]:
    """Where a ball on the cloth is after ``t`` [s]: (move, velocity, spin).

    The contact point is at -R n; its slip u = v + R n x w. Sliding, friction mu M g acts
    against u: M dv/dt = -mu M g u^ and I dw/dt = (-R n) x (-mu M g u^), so
    du/dt = -mu g (1 + 1/K) u^: u keeps its direction and vanishes at
    t_s = |u0| / (mu g (1 + 1/K)). Rolling, the torque C M g against the roll slows the ball
    at a = C g / (R (1 + K)) (carom.Material.rolling), with w in the plane n x v / R, until
    it stops at |v| / a. The spin about n never changes."""
    wn = float(w0 @ UP)
    u0 = v0 + R * np.cross(UP, w0)
    slip = float(np.linalg.norm(u0))
    e = u0 / slip if slip > 0.0 else np.zeros(3)  # (no slip: rolling from the start)
    t_s = slip / (MU * G * (1.0 + 1.0 / K))
    ts = min(t, t_s)
    move = v0 * ts - 0.5 * MU * G * e * ts**2
    v = v0 - MU * G * e * ts
    w = w0 + MU * G / (K * R) * np.cross(UP, e) * ts
    if t <= t_s:
        return move, v, w
    a = C * G / (R * (1.0 + K))
    speed = float(np.linalg.norm(v))
    if speed == 0.0:
        return move, v, wn * UP
    tr = min(t - t_s, speed / a)
    e = v / speed
    move = move + v * tr - 0.5 * a * e * tr**2
    v = v - a * e * tr if tr < speed / a else np.zeros(3)
    return move, v, np.cross(UP, v) / R + wn * UP


def shot(rate: float, v0: list[float], w0: list[float], until: float) -> carom.World:
    """One ball on the cloth, hit at ``v0``, ``w0``, run to ``until`` [s] at ``rate`` [Hz]."""
    world = carom.World(
        3, box=[8, 8, 1], boundary="open", gravity=[0, 0, -G],
        rigid=RigidSettings(rate=rate, sleep=False),
    )  # fmt: skip
    world.add_plane([0, 0, 0], [0, 0, 1], material=carom.Material(0.5, friction=MU, rolling=C))
    world.add_body(
        Sphere(R), [4.0, 4.0, R], velocity=v0, angular_velocity=w0, mass=M,
        material=carom.Material(0.95, friction=0.05),
    )  # fmt: skip
    world.run(until=until)
    return world


@pytest.mark.needs_jit  # 1800 steps a shot
@pytest.mark.parametrize("name", list(SHOTS))
def test_a_shot_on_the_cloth_is_its_closed_form_at_every_rate(name: str) -> None:
    # 1.3 s takes every shot through sliding into rolling; the 1000 Hz run is 1300 steps. Each
    # step composes the closed form's pieces, so the rates differ by round-off only: a few
    # ulps of the speeds (1 m/s, 30 rad/s x R) a step, 1e-12 after 1300 steps; 1e-9 is the
    # issue's bound.
    v0, w0 = SHOTS[name]
    until = 1.3
    move, v, w = closed_form(np.array(v0), np.array(w0), until)
    for rate in (60.0, 240.0, 1000.0):
        world = shot(rate, v0, w0, until)
        assert world.positions[0] - [4.0, 4.0, R] == pytest.approx(move, abs=1e-9)
        assert world.velocities[0] == pytest.approx(v, abs=1e-9)
        assert R * world.angular_velocities[0] == pytest.approx(R * w, abs=1e-9)
        assert world.positions[0, 2] == R  # held on the cloth, not sunk
        assert world.engine._role[0] == islands.ROLE_CLOTH


def test_the_rolling_ball_stops_where_the_closed_form_says() -> None:
    # a stun shot at 0.5 m/s: rolls at 5/7 of it after t_s, then stops after another
    # (5/14) / a seconds; from then on it does not move at all
    a = C * G / (R * (1.0 + K))
    v0 = np.array([0.5, 0.0, 0.0])
    stop = 0.5 / (MU * G * 3.5) + (0.5 / 1.4) / a
    move, _, _ = closed_form(v0, np.zeros(3), stop)
    world = shot(60.0, [0.5, 0.0, 0.0], [0.0, 0.0, 0.0], stop + 0.5)
    assert world.positions[0] - [4.0, 4.0, R] == pytest.approx(move, abs=1e-9)
    assert np.array_equal(world.velocities[0], np.zeros(3))
    assert np.array_equal(world.angular_velocities[0], np.zeros(3))


def test_the_ledger_books_what_the_cloth_takes() -> None:
    # Friction and rolling resistance take the ball's kinetic energy: E0 = E + lost, to
    # round-off of E0 (the ball stays at its height: no potential energy changes)
    v0, w0 = SHOTS["massé"]
    world = shot(60.0, v0, w0, 2.0)
    inertia = K * M * R**2
    e0 = 0.5 * M * float(np.dot(v0, v0)) + 0.5 * inertia * float(np.dot(w0, w0))
    v, w = world.velocities[0], world.angular_velocities[0]
    e = 0.5 * M * float(v @ v) + 0.5 * inertia * float(w @ w)
    c = world.counters()
    assert c.energy_given == 0.0
    assert e + c.energy_lost == pytest.approx(e0, rel=1e-12)
    assert c.energy_lost > 0.5 * e0


def test_a_ball_with_company_or_on_a_slope_is_left_to_the_solver() -> None:
    # Only a ball alone on a level plane is moved in closed form: two touching balls, or a
    # ball on an incline, keep the soft step (their motion has no closed form here)
    world = carom.World(3, box=[4, 4, 1], boundary="open", gravity=[0, 0, -G])
    world.add_plane([0, 0, 0], [0, 0, 1], material=carom.Material(0.5, friction=MU))
    world.add_body(Sphere(R), [1.0, 1.0, R], mass=M)
    world.add_body(Sphere(R), [1.0 + 2 * R, 1.0, R], mass=M)
    world.add_body(Sphere(R), [2.0, 2.0, R], velocity=[0.1, 0, 0], mass=M)
    world.run(until=0.2)
    role = world.engine._role[:3]  # (the plane is a static body after them)
    assert list(role) == [islands.ROLE_SOLVER, islands.ROLE_SOLVER, islands.ROLE_CLOTH]
    slope = math.radians(10.0)
    tilted = carom.World(3, box=[4, 4, 4], boundary="open", gravity=[0, 0, -G])
    normal = [-math.sin(slope), 0.0, math.cos(slope)]
    tilted.add_plane([0, 0, 0], normal, material=carom.Material(0.5, friction=MU))
    tilted.add_body(Sphere(R), np.array(normal) * R, mass=M)
    tilted.run(until=0.2)
    assert tilted.engine._role[0] == islands.ROLE_SOLVER


def test_a_ball_at_rest_on_the_cloth_stays_exactly_on_it() -> None:
    # alone on a rough level floor, a ball rests on it exactly: no soft contact, no sink, no
    # velocity; a ball dropped 1 mm (its impact taken exactly, e = 0: it lands with no
    # bounce) then rests on it at its radius too, within round-off of the landing
    world = carom.World(3, box=[4, 4, 1], boundary="open", gravity=[0, 0, -G])
    floor = carom.Material(0.0, friction=MU, rolling=C)
    world.add_plane([0, 0, 0], [0, 0, 1], material=floor)
    world.add_body(Sphere(R), [1.0, 1.0, R], mass=M, material=floor)
    world.add_body(Sphere(R), [2.0, 2.0, R + 1e-3], mass=M, material=floor)
    world.run(until=1.0)
    assert world.positions[0, 2] == R
    assert np.array_equal(world.velocities[0], np.zeros(3))
    assert world.positions[1, 2] == pytest.approx(R, abs=1e-15)
    assert np.abs(world.velocities[1]).max() < 1e-15
    # (at rest on the cloth for the sleep time, both are asleep by now)
    assert list(world.engine._role[:2]) == [islands.ROLE_ASLEEP] * 2


def test_a_ball_on_a_static_box_rolls_in_closed_form_and_still_falls_off_its_edge() -> None:
    # A table's top face is cloth as a plane is, while the ball's contact point cannot leave
    # it within the step; near the edge the ball goes back to the soft step, and it rolls off
    # and falls instead of rolling on in the air
    world = carom.World(3, box=[4, 4, 2], boundary="open", gravity=[0, 0, -G])
    cloth = carom.Material(0.5, friction=MU, rolling=C)
    world.add_body(Box([1.0, 1.0, 0.2]), [1.0, 1.0, 0.9], kind="static", material=cloth)
    top = 1.0
    world.add_body(
        Sphere(R), [0.6, 1.0, top + R], velocity=[1.0, 0, 0], angular_velocity=[0, 1.0 / R, 0],
        mass=M, material=cloth,
    )  # fmt: skip
    world.step()
    assert world.engine._role[1] == islands.ROLE_CLOTH
    # rolling (no slip), slowed by the rolling resistance only: the closed form's speed
    a = C * G / (R * (1.0 + K))
    assert world.velocities[1, 0] == pytest.approx(1.0 - a / 60.0, abs=1e-12)
    assert world.positions[1, 2] == top + R
    world.run(until=1.0)  # the edge is 0.9 m on: it left the table after about 0.9 s
    assert world.positions[1, 0] > 1.5
    assert world.positions[1, 2] < top + R - 0.01


def test_a_ball_sent_up_off_the_cloth_hops() -> None:
    # a ball on the cloth given 0.12 m/s upwards leaves it: a hop of u^2 / 2g = 0.73 mm, more
    # than the touching distance (a tenth of the linear slop, 0.5 mm), is not dropped; after
    # one step of 1/60 s it has risen u t - g t^2 / 2 (free flight, exact)
    world = carom.World(3, box=[4, 4, 1], boundary="open", gravity=[0, 0, -G])
    world.add_plane([0, 0, 0], [0, 0, 1], material=carom.Material(0.5, friction=MU, rolling=C))
    world.add_body(Sphere(R), [1.0, 1.0, R], mass=M)
    world.step()
    assert world.engine._role[0] == islands.ROLE_CLOTH
    world.set_velocities([0], [[0.0, 0.0, 0.12]])
    world.step()
    t = 1.0 / 60.0
    assert world.positions[0, 2] - R == pytest.approx(0.12 * t - 0.5 * G * t * t, rel=1e-12)
    assert world.engine._role[0] != islands.ROLE_CLOTH


# --- two balls on the cloth: the impact is carom.collide's, at its exact time -------------

GAP = 0.5  # the object ball's centre ahead of the cue ball's [m]
#: shots at an object ball at rest: the cue ball's velocity [m/s] and spin [rad/s], and the
#: object ball's offset across the line of the shot [m] (R: a half-ball cut)
MEETINGS = {
    "follow": ([2.0, 0.0, 0.0], [0.0, 2.0 / R, 0.0], 0.0),  # rolling: follows through
    "stun": ([2.0, 0.0, 0.0], [0.0, 0.0, 0.0], 0.0),  # no spin yet, sliding on impact
    "draw": ([2.0, 0.0, 0.0], [0.0, -2.5 / R, 0.0], 0.0),  # backspin: comes back
    "cut": ([2.0, 0.0, 0.0], [0.0, 2.0 / R, 0.0], R),  # half-ball, rolling
}
BALLS = {"smooth": None, "walton": 0.05}  # ball-ball friction: none, billiards-3d's


def _ball_material(friction: float | None) -> carom.Material:
    return carom.Material(0.95, friction=friction)


def meeting(
    rate: float, name: str, friction: float | None, until: float, *, sink: list | None = None
) -> carom.World:
    """The cue ball (body 0) shot at the object ball (1) on the cloth, run to ``until``."""
    v0, w0, offset = MEETINGS[name]
    world = carom.World(
        3, box=[8, 8, 1], boundary="open", gravity=[0, 0, -G],
        rigid=RigidSettings(rate=rate, sleep=False),
    )  # fmt: skip
    world.add_plane([0, 0, 0], [0, 0, 1], material=carom.Material(0.5, friction=MU, rolling=C))
    ball = _ball_material(friction)
    world.add_body(
        Sphere(R), [3.0, 4.0, R], velocity=v0, angular_velocity=w0, mass=M, material=ball
    )
    world.add_body(Sphere(R), [3.0 + GAP, 4.0 + offset, R], mass=M, material=ball)
    world.run(until=until, on_collisions=None if sink is None else sink.append)
    return world


def meeting_closed_form(name: str, friction: float | None, until: float) -> dict[str, Any]:
    """The shot's piecewise closed form: the cue ball slides and rolls (:func:`closed_form`)
    until its centre is 2R from the object ball's (the time found by bisection on the closed
    form: the cue ball moves along x, ever forward until then); carom.collide's impact of
    the two (Walton's law with the balls' friction, or smooth; I = K m R^2); the velocity
    across the cloth that the impulse gave dropped (the cloth holds both); then each ball's
    closed form to ``until``."""
    v0, w0, offset = MEETINGS[name]
    v0, w0 = np.array(v0), np.array(w0)
    reach = GAP - math.sqrt(4.0 * R * R - offset * offset)  # the cue's travel to contact
    lo, hi = 0.0, 1.0
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if closed_form(v0, w0, mid)[0][0] < reach else (lo, mid)
    t_hit = lo
    move, v1, w1 = closed_form(v0, w0, t_hit)
    x1 = np.array([3.0, 4.0, R]) + move
    x2 = np.array([3.0 + GAP, 4.0 + offset, R])
    r = carom.collide(
        x1, v1, M, x2, np.zeros(3), M, e=0.95, w1=w1, w2=np.zeros(3), radius1=R, radius2=R,
        friction=friction, q=K,
    )  # fmt: skip
    ends = []
    for x, v, w in ((x1, r.v1, r.w1), (x2, r.v2, r.w2)):
        v = np.array(v, dtype=float)
        v[2] = 0.0
        move, v, w = closed_form(v, np.array(w, dtype=float), until - t_hit)
        ends.append((x + move, v, w))
    return {"t_hit": t_hit, "impact": r, "ends": ends}


@pytest.mark.needs_jit  # up to 1300 steps a run, 24 runs
@pytest.mark.parametrize("balls", list(BALLS))
@pytest.mark.parametrize("name", list(MEETINGS))
def test_two_balls_meet_as_collide_says_at_every_rate(name: str, balls: str) -> None:
    # The shots: each ball's position, velocity and spin 1.3 s after the shot (the
    # impact at about 0.22-0.25 s, every ball rolling again by then) are the same at 60, 240
    # and 1000 Hz and equal to the piecewise closed form, to 1e-9 (the bound). The
    # time of impact is found to a billionth of the balls' reaches (5.7e-11 m of gap,
    # impacts.py): about 3e-11 s at 2 m/s, which moves nothing by 1e-9.
    until = 1.3
    expect = meeting_closed_form(name, BALLS[balls], until)
    for rate in (60.0, 240.0, 1000.0):
        log: list = []
        world = meeting(rate, name, BALLS[balls], until, sink=log)
        records = np.concatenate(log)
        assert records.shape[0] == 1  # one impact, between the balls, solved exactly
        assert records["time"][0] == pytest.approx(expect["t_hit"], abs=1e-10)
        for i, (x, v, w) in enumerate(expect["ends"]):
            assert world.positions[i] == pytest.approx(x, abs=1e-9)
            assert world.velocities[i] == pytest.approx(v, abs=1e-9)
            assert R * world.angular_velocities[i] == pytest.approx(R * w, abs=1e-9)
        assert list(world.engine._role[:2]) == [islands.ROLE_CLOTH] * 2


@pytest.mark.parametrize("balls", list(BALLS))
def test_an_impact_on_the_cloth_is_collides_to_the_bit(balls: str) -> None:
    # Two balls touching at the start, the cue ball rolling into the other at 2 m/s: the
    # impact is at t = 0, from the state given, and its impulse is carom.collide's, the same
    # bits (the same arithmetic: carom.laws.batch.law_block). After the step each ball has
    # rolled on from collide's velocities and spins, its velocity across the cloth dropped:
    # the closed form to round-off.
    friction = BALLS[balls]
    world = carom.World(3, box=[4, 4, 1], boundary="open", gravity=[0, 0, -G])
    world.add_plane([0, 0, 0], [0, 0, 1], material=carom.Material(0.5, friction=MU, rolling=C))
    ball = _ball_material(friction)
    x1, x2 = np.array([1.0, 1.0, R]), np.array([1.0 + 2.0 * R, 1.0, R])
    v1, w1 = np.array([2.0, 0.0, 0.0]), np.array([0.0, 2.0 / R, 0.0])
    world.add_body(Sphere(R), x1, velocity=v1, angular_velocity=w1, mass=M, material=ball)
    world.add_body(Sphere(R), x2, mass=M, material=ball)
    log: list = []
    world.run(until=1.0 / 60.0, on_collisions=log.append)
    records = np.concatenate(log)
    assert records.shape[0] == 1
    assert records["time"][0] == 0.0
    q = world.engine.model.inertia[0][0, 0] / (M * R * R)  # the ball's own I / (m R^2)
    r = carom.collide(
        x1, v1, M, x2, np.zeros(3), M, e=0.95, w1=w1, w2=np.zeros(3), radius1=R, radius2=R,
        friction=friction, q=q,
    )  # fmt: skip
    assert np.array_equal(records["impulse"][0], r.impulse)
    if friction is not None:  # topspin against the object ball: friction lifts the cue ball
        assert r.v1[2] > 0.0
        assert r.v2[2] < 0.0
    for i, (v, w) in enumerate(((r.v1, r.w1), (r.v2, r.w2))):
        v = np.array(v, dtype=float)
        v[2] = 0.0
        _, v_end, w_end = closed_form(v, np.array(w, dtype=float), 1.0 / 60.0)
        assert world.velocities[i] == pytest.approx(v_end, abs=1e-12)
        assert R * world.angular_velocities[i] == pytest.approx(R * w_end, abs=1e-12)
        assert world.positions[i, 2] == R


def test_the_ledger_closes_over_an_impact_on_the_cloth() -> None:
    # E0 = E + lost - given, to round-off of E0: the impact's loss (its log), the friction
    # before and after it, and the velocity across the cloth the impulse gave (dropped)
    world = meeting(60.0, "follow", 0.05, 1.3)
    inertia = K * M * R**2
    v0, w0, _ = MEETINGS["follow"]
    e0 = 0.5 * M * float(np.dot(v0, v0)) + 0.5 * inertia * float(np.dot(w0, w0))
    v, w = world.velocities, world.angular_velocities
    e = 0.5 * M * float((v * v).sum()) + 0.5 * inertia * float((w * w).sum())
    c = world.counters()
    assert e + c.energy_lost - c.energy_given == pytest.approx(e0, rel=1e-12)
