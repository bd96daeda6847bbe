"""A ball meets a cushion as a billiards player meets it: at the cushion's nose, above the
ball's centre, and leaves it as Han's 2005 model says (carom.scene.layouts.cushion_rails, the
exact path of carom.engines.rigid3d.impacts, carom.engines.rigid3d.cloth)."""

from __future__ import annotations

import math

import numpy as np
import pytest

import carom
from carom.engines.stepped.settings import RigidSettings
from carom.errors import CaromError
from carom.scene import Scene
from carom.scene.layouts import cushion_rails
from carom.shapes3d import Hull, Sphere
from tests.engines.rigid3d.test_cloth import MU, C, G, R, closed_form

M = 0.17
E_CUSHION = 0.85  # the cushion's restitution and friction (pooltool's defaults)
MU_CUSHION = 0.2
H = 0.64 * 2 * R  # the nose's height above the cloth (pooltool's pocket table): 1.28 R
AREA = ([0.0, 0.0], [2.0, 1.0])
#: shots into the right-hand cushion (its nose at x = 2): the ball's start (x, y), velocity
#: [m/s] and spin [rad/s]
SHOTS = {
    "rolling, square": ([1.5, 0.5], [1.0, 0.0, 0.0], [0.0, 1.0 / R, 0.0]),
    "rolling, at an angle": ([1.6, 0.3], [1.2, 0.6, 0.0], [-0.6 / R, 1.2 / R, 0.0]),
    "side spin": ([1.5, 0.5], [1.0, 0.3, 0.0], [-0.3 / R, 1.0 / R, 40.0]),
    "draw": ([1.7, 0.5], [1.5, 0.0, 0.0], [0.0, -2.0 / R, 0.0]),
    "stun, hard": ([1.8, 0.5], [3.0, -1.0, 0.0], [0.0, 0.0, 0.0]),
}


def han_2005(
    v: np.ndarray, w: np.ndarray, height: float, e: float, mu: float
) -> tuple[np.ndarray, np.ndarray]:
    """A ball's velocity and spin after it meets a cushion whose normal is +x (into the
    cushion), by Han (2005), "Dynamics in carom and three cushion billiards", J. Mech. Sci.
    Tech. 19, eqs 14-23, as pooltool implements it.

    The nose touches the ball at theta = asin(h / R - 1) above its centre. In the contact's
    frame, the slip s of the ball's contact point (eq 14) and the approach c = -v_x cos
    theta; a solid ball's inverse effective masses A = 7 / 2m across the normal, B = 1 / m
    along it (eq 16). The normal impulse is Newton's, P_z = -(1 + e) c / B (eq 17); the
    tangential one stops the slip, s / A, if that is within Coulomb's cone mu P_z (eq 18),
    else it is mu P_z along the slip (eq 19); back to the rail's frame (eqs 21, 22), the
    impulse changes v and w (eq 23); the vertical velocity is left out (the cloth holds the
    ball)."""
    th = math.asin(height / R - 1.0)
    sin, cos = math.sin(th), math.cos(th)
    sx = v[0] * sin - v[2] * cos + R * w[1]
    sy = -v[1] - R * w[2] * cos + R * w[0] * sin
    c = -v[0] * cos
    a, b = 3.5 / M, 1.0 / M
    pz = -(1.0 + e) * c / b
    slip = math.hypot(sx, sy)
    if slip / a <= mu * pz:
        px, py = sx / a, sy / a
    else:
        px, py = mu * pz * sx / slip, mu * pz * sy / slip
    big_x = -px * sin - pz * cos
    big_y = py
    big_z = px * cos - pz * sin
    inertia = 0.4 * M * R * R
    v_after = np.array([v[0] + big_x / M, v[1] + big_y / M, 0.0])
    w_after = np.array(
        [
            w[0] - R / inertia * big_y * sin,
            w[1] + R / inertia * (big_x * sin - big_z * cos),
            w[2] + R / inertia * big_y * cos,
        ]
    )
    return v_after, w_after


def table(rate: float) -> carom.World:
    """A cloth (a plane) inside the four rails of AREA, the ball's material the cushions' (so
    that their pair's coefficients are the cushion's own)."""
    world = carom.World(
        3, box=[2.0, 1.0, 0.5], boundary="open", gravity=[0, 0, -G],
        rigid=RigidSettings(rate=rate, sleep=False),
    )  # fmt: skip
    world.add_plane([0, 0, 0], [0, 0, 1], material=carom.Material(0.5, friction=MU, rolling=C))
    cushion = carom.Material(E_CUSHION, friction=MU_CUSHION)
    for points, position, turn in cushion_rails(*AREA, height=H):
        world.add_body(Hull(points), position, orientation=turn, kind="static", material=cushion)
    return world


def shot_into_the_cushion(rate: float, name: str, until: float) -> carom.World:
    (x, y), v0, w0 = SHOTS[name]
    world = table(rate)
    world.add_body(
        Sphere(R), [x, y, R], velocity=v0, angular_velocity=w0, mass=M,
        material=carom.Material(E_CUSHION, friction=MU_CUSHION),
    )  # fmt: skip
    world.run(until=until)
    return world


def expected(name: str, until: float) -> tuple[np.ndarray, ...]:
    """The closed form: the ball on the cloth until its centre is R cos(theta) from the nose
    (x = 2), Han's impact, the ball on the cloth to ``until``: (position, velocity, spin)."""
    (x, y), v0, w0 = SHOTS[name]
    v0, w0 = np.array(v0), np.array(w0)
    reach = AREA[1][0] - R * math.cos(math.asin(H / R - 1.0)) - x
    lo, hi = 0.0, 1.0  # (bisection on the closed form: the ball moves towards +x until then)
    for _ in range(200):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if closed_form(v0, w0, mid)[0][0] < reach else (lo, mid)
    move, v1, w1 = closed_form(v0, w0, lo)
    v2, w2 = han_2005(v1, w1, H, E_CUSHION, MU_CUSHION)
    move2, v3, w3 = closed_form(v2, w2, until - lo)
    return np.array([x, y, R]) + move + move2, v3, w3


@pytest.mark.needs_jit  # 3 rates x 5 shots, up to 600 steps
@pytest.mark.parametrize("name", list(SHOTS))
def test_a_ball_leaves_the_cushion_as_han_2005_says(name: str) -> None:
    # The ball's state 0.6 s after the shot (its cushion met at 0.1-0.5 s; no second one) is
    # the closed form through Han's impact, at 60, 240 and 1000 Hz. The impulse is carom's
    # for a ball and a static piece touching at one point (Newton's restitution, Coulomb
    # friction: sticking or sliding along the slip), at the point the geometry gives: the
    # rail's nose, H above the cloth. What is left is the time of impact: found to a
    # billionth of the two pieces' reaches (impacts.py), here R + the 1 m rail's half
    # length, 5.3e-10 m; a ball that far off the nose sees it turned by 5.3e-10 sin(theta) /
    # (R cos(theta)) = 5.4e-9 rad, which turns what the impulse gives (up to 3 m/s) by
    # 1.6e-8 m/s. Measured: 3.7e-9 at worst (the square rolling shot at 240 Hz, its R w),
    # most below 1e-11.
    until = 0.6
    x, v, w = expected(name, until)
    for rate in (60.0, 240.0, 1000.0):
        world = shot_into_the_cushion(rate, name, until)
        ball = world.n_bodies - 1
        assert world.positions[ball] == pytest.approx(x, abs=2e-8)
        assert world.velocities[ball] == pytest.approx(v, abs=2e-8)
        assert R * world.angular_velocities[ball] == pytest.approx(R * w, abs=2e-8)
        assert world.positions[ball, 2] == R  # on the cloth throughout


def test_the_rails_noses_bound_the_playing_area() -> None:
    # every rail's nose (its points at the nose's height nearest the table) lies on the
    # rectangle's edge, H above the cloth; the rail lies behind it
    world = table(60.0)
    low, high = np.array(AREA[0]), np.array(AREA[1])
    inside = [(0.5, 0.5), (1.999, 0.5), (0.001, 0.5), (1.0, 0.999), (1.0, 0.001)]
    for x, y in inside:  # a ray down onto the playing area meets the cloth, not a rail
        hit = world.ray_cast([x, y, 1.0], [0.0, 0.0, -1.0])
        assert hit is not None
        assert hit.point[2] == pytest.approx(0.0, abs=1e-12)
    for x, y in [(2.001, 0.5), (-0.001, 0.5), (1.0, 1.001), (1.0, -0.001)]:
        hit = world.ray_cast([x, y, 1.0], [0.0, 0.0, -1.0])
        assert hit.point[2] == pytest.approx(H, abs=1e-12)  # the rail's top
    # a ray level with the nose, along +x from the middle, stops at x = 2
    hit = world.ray_cast([1.0, 0.5, H - 1e-9], [1.0, 0.0, 0.0])
    assert hit.point[0] == pytest.approx(high[0], abs=1e-6)
    assert low[0] == 0.0


def test_a_scene_builds_the_rails_from_a_cushions_table() -> None:
    scene = Scene.from_dict(
        {
            "world": {"dimension": 3, "box": [2.0, 1.0, 0.5], "gravity": [0, 0, -G]},
            "materials": [{"name": "cushion", "restitution": 0.85, "friction": 0.2}],
            "cushions": [{"area": [[0, 0], [2, 1]], "height": H, "material": "cushion"}],
            "bodies": [{"shape": "ball", "radius": R, "positions": [[1, 0.5, R]], "mass": M}],
            "run": {"until": 1.0},
        }
    )
    world = scene.build()
    assert world.n_bodies == 5
    assert np.isinf(world.masses[1:]).all()  # the four rails, static, after the ball
    with pytest.raises(CaromError, match="cushions are 3D"):
        Scene.from_dict(
            {
                "world": {"dimension": 2, "box": [2.0, 1.0]},
                "cushions": [{"area": [[0, 0], [2, 1]], "height": 0.04}],
                "bodies": [{"radius": 0.03, "positions": [[1, 0.5]]}],
                "run": {"until": 1.0},
            }
        ).build()
