"""carom play's live world (carom.play.live): real time, the page's commands, frames.

A clock the test moves stands in for real time, so every count of steps is exact.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from carom.play.live import MOST_BALLS, MOST_STEPS, Live
from carom.play.wire import Command, Refused, unpack
from tests.play.scenes import SMALL_PYRAMID


class Clock:
    """Real time as the test says [s]."""

    def __init__(self) -> None:
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


@pytest.fixture
def small(tmp_path: Path) -> tuple[Live, Clock]:
    path = tmp_path / "small-pyramid.toml"
    path.write_text(SMALL_PYRAMID)
    clock = Clock()
    return Live(str(path), clock=clock), clock


def cmd(op: str, **fields: object) -> Command:
    """A command as read_command makes it (vectors as arrays)."""
    return Command(
        op, {k: np.asarray(v, float) if isinstance(v, list) else v for k, v in fields.items()}
    )


def test_real_time_takes_the_engines_own_steps(small: tuple[Live, Clock]) -> None:
    live, clock = small
    dt = live.dt
    assert dt == pytest.approx(1 / 60)
    steps = 0
    for _ in range(10):  # 0.05 s a call: 3 steps of 1/60 s each (to round-off: 30 in all)
        clock.now += 0.05
        steps += live.advance()
    assert live.world.steps == steps
    assert steps in (29, 30)
    clock.now += 10.0  # far behind: at most MOST_STEPS, the rest dropped and counted
    assert live.advance() == MOST_STEPS
    assert live.behind == pytest.approx(10.0 - (MOST_STEPS + 1) * dt, abs=dt)


def test_slow_motion_and_pause(small: tuple[Live, Clock]) -> None:
    live, clock = small
    live.obey(cmd("slow", factor=0.25))
    steps = 0
    for _ in range(4):  # a second at a quarter: 0.25 s of simulated time, 15 steps
        clock.now += 0.25
        steps += live.advance()
    assert steps == 15
    live.obey(cmd("pause"))
    t = live.world.time
    clock.now += 5.0
    assert live.advance() == 0
    assert live.world.time == t
    live.obey(cmd("step"))  # one step of the engine's length, still paused
    assert live.world.time == pytest.approx(t + live.dt, abs=1e-15)
    assert live.paused
    live.obey(cmd("play"))
    clock.now += 0.2  # playing again from now: 0.2 s at a quarter, 3 steps
    assert live.advance() == 3


def test_reset_gives_the_same_bits(small: tuple[Live, Clock]) -> None:
    live, _ = small
    first = live.world.positions.copy()
    for _ in range(30):
        live.single_step()
    after = live.world.positions.copy()
    live.obey(cmd("reset"))
    assert live.world.time == 0.0
    np.testing.assert_array_equal(live.world.positions, first)
    for _ in range(30):
        live.single_step()
    np.testing.assert_array_equal(live.world.positions, after)  # same input, same bits


def test_a_shot_ball_flies_the_exact_parabola(small: tuple[Live, Clock]) -> None:
    live, _ = small
    n = live.world.n_bodies
    p, v = np.array([2.0, 9.0]), np.array([3.0, 1.0])
    reply = live.obey(cmd("shoot", point=list(p), velocity=list(v)))
    assert reply == {"op": "shot", "body": n}
    assert live.world.n_bodies == n + 1
    steps = 12
    for _ in range(steps):
        live.single_step()
    # free flight is exact in the rigid engine: x = p + v t + g t^2 / 2 (no contact for 0.2 s:
    # the ball is 8 m above the pyramid's top)
    t = steps * live.dt
    g = np.array([0.0, -10.0])
    expected = p + v * t + 0.5 * g * t * t
    np.testing.assert_allclose(live.world.body(n).position, expected, rtol=0, atol=1e-12)
    np.testing.assert_allclose(live.world.body(n).velocity, v + g * t, rtol=0, atol=1e-12)


def test_shots_refused_leave_the_world_alone(small: tuple[Live, Clock]) -> None:
    live, _ = small
    n = live.world.n_bodies
    top = live.world.positions[n - 1]  # the pyramid's top box
    with pytest.raises(Refused, match="inside a body"):
        live.obey(cmd("shoot", point=list(top), velocity=[0.0, 0.0]))
    assert live.world.n_bodies == n
    # no more than MOST_BALLS at once: the oldest go
    for k in range(MOST_BALLS + 2):
        spot = [1.0 + 1.6 * (k % 12), 20.0 + 1.6 * (k // 12)]  # (balls of 0.71 m)
        live.obey(cmd("shoot", point=spot, velocity=[0.0, 0.0]))
    alive = live.world.alive
    assert np.count_nonzero(alive[n:]) == MOST_BALLS
    assert not alive[n]
    assert not alive[n + 1]


def test_a_drag_pulls_a_box_up(small: tuple[Live, Clock]) -> None:
    live, _ = small
    top = live.world.n_bodies - 1
    x0 = live.world.positions[top].copy()
    reply = live.obey(cmd("grab", point=list(x0 + np.array([0.2, 0.1]))))
    assert reply is not None
    assert reply["body"] == top
    live.obey(cmd("drag", target=list(x0 + np.array([0.2, 3.1]))))
    for _ in range(120):
        live.single_step()
    x = live.world.positions[top]
    # the target joint (a 5 Hz spring, damping 0.7) has brought the grabbed point near the
    # target in 2 s: the box hangs under it, 3 m up
    assert x[1] - x0[1] > 2.5
    live.obey(cmd("release"))
    assert live.world.joint_rows[0][-1, 0] < 0  # the joint is removed


def test_grab_in_open_space_holds_nothing(small: tuple[Live, Clock]) -> None:
    live, _ = small
    reply = live.obey(cmd("grab", point=[1.0, 11.0]))
    assert reply is not None
    assert reply["body"] == -1
    with pytest.raises(Refused, match="nothing is held"):
        live.obey(cmd("drag", target=[1.0, 5.0]))


def test_settings_apply_at_once(small: tuple[Live, Clock]) -> None:
    live, _ = small
    live.obey(cmd("set", name="gravity", value=2.5))
    np.testing.assert_array_equal(live.world.gravity, [0.0, -2.5])
    live.obey(cmd("set", name="substeps", value=8.0))
    assert live.world.rigid_settings.substeps == 8
    live.obey(cmd("set", name="friction", value=0.2))
    live.obey(cmd("set", name="restitution", value=0.5))
    assert all(m.friction == 0.2 and m.restitution == 0.5 for m in live.world.materials)
    # a ball shot now falls at the new gravity, exactly
    n = live.world.n_bodies
    live.obey(cmd("shoot", point=[2.0, 10.0], velocity=[0.0, 0.0]))
    for _ in range(6):
        live.single_step()
    t = 6 * live.dt
    assert live.world.body(n).position[1] == pytest.approx(10.0 - 0.5 * 2.5 * t * t, abs=1e-12)
    with pytest.raises(Refused, match="between 0 and 100"):
        live.obey(cmd("set", name="gravity", value=1e9))


def test_frames_carry_the_world(small: tuple[Live, Clock]) -> None:
    live, _ = small
    for _ in range(5):
        live.single_step()
    header, arrays = unpack(live.frame())
    assert header["type"] == "frame"
    assert header["steps"] == 5
    np.testing.assert_allclose(arrays["x"], live.world.positions, rtol=1e-6)
    assert arrays["x"].dtype == np.float32
    assert arrays["state"].dtype == np.uint8
    e = header["energy"]
    # the ledger closes: E0 + work = E + lost - given (docs/engine.md), to round-off of the
    # sums (potential energy of ~15 boxes at ~2 m, 10 m/s^2: ~300 J)
    miss = e["kinetic"] + e["potential"] + e["lost"] - e["given"] - e["start"] - e["work"]
    assert abs(miss) < 1e-9 * e["start"]
    assert "contacts" not in arrays
    live.obey(cmd("draw", name="contacts", on=True))
    live.obey(cmd("draw", name="boxes", on=True))
    live.single_step()
    _, arrays = unpack(live.frame())
    c = arrays["contacts"]
    assert c.shape[1] == 5
    assert c.shape[0] >= header["contacts"]
    # unit normals; the impulses of a standing pyramid hold its weight up
    np.testing.assert_allclose(np.hypot(c[:, 2], c[:, 3]), 1.0, rtol=1e-6)
    assert arrays["boxes"].shape[1] == 4
    shapes, geometry = unpack(live.shapes())
    assert shapes["type"] == "shapes"
    assert shapes["dim"] == 2
    assert geometry["ring_start"][-1] == len(geometry["ring"])


def test_the_drag_that_divided_by_zero() -> None:
    # issue 44: this drag in the pyramid scene stopped the 2D solver with ZeroDivisionError
    # (a struck box closing on another at a speed whose product with the substep was zero);
    # same input, same bits: it is replayed exactly
    live = Live("pyramid", clock=Clock())
    for _ in range(6):
        live.single_step()
    live.obey(cmd("shoot", point=[3.0, 15.0], velocity=[10.0, 0.0]))
    live.single_step()
    live.single_step()
    x = live.world.positions[5].copy()
    assert live.obey(cmd("grab", point=list(x)))["body"] == 5  # type: ignore[index]
    live.obey(cmd("drag", target=list(x + np.array([0.0, 1.0]))))
    for _ in range(60):
        live.single_step()
    assert np.all(np.isfinite(live.world.positions))
    assert live.world.positions[5, 1] > x[1] + 0.2


def test_scenes_switch_and_unknown_ones_are_refused(small: tuple[Live, Clock]) -> None:
    live, _ = small
    with pytest.raises(Refused, match="no scene"):
        live.obey(cmd("scene", name="no-such-scene"))
    live.obey(cmd("scene", name="gas-2d"))
    assert live.world.engine_name == "edmd"
    assert live.dt is None
    assert live.scene_name == "gas-2d"


def test_the_gas_takes_hands_too() -> None:
    live = Live("gas-2d", clock=Clock())
    x = live.world.positions
    reply = live.obey(cmd("grab", point=list(x[0])))
    assert reply is not None
    assert reply["body"] == 0
    target = x[0] + [1.0, 0.0]
    live.obey(cmd("drag", target=list(target)))
    live.single_step()
    # the held sphere is sent toward the pointer: a tenth of the gap in a tenth of a second
    v = live.world.body(0).velocity
    assert v[0] > 0
    assert abs(v[1]) < abs(v[0])
    live.obey(cmd("release"))
    n = live.world.n_bodies
    # a ball shot into a gap of the gas
    gaps = [np.array([a, b]) for a in np.linspace(2, 49, 48) for b in np.linspace(2, 49, 48)]
    free = next(p for p in gaps if np.min(np.hypot(*(live.world.positions - p).T)) > 1.1)
    live.obey(cmd("shoot", point=list(free), velocity=[1.0, 0.0]))
    assert live.world.n_bodies == n + 1
    before = live.world.counters()
    ke = 0.5 * np.sum(live.world.masses * np.sum(live.world.velocities**2, axis=1))
    for _ in range(30):
        live.single_step()
    after = live.world.counters()
    ke_after = 0.5 * np.sum(live.world.masses * np.sum(live.world.velocities**2, axis=1))
    # elastic gas, no gravity, nothing held: kinetic energy is kept to round-off
    assert ke_after == pytest.approx(ke, rel=1e-12)
    assert after.collisions > before.collisions


def test_the_ledger_closes_through_what_the_hands_do(small: tuple[Live, Clock]) -> None:
    # E0 + work = E + lost - given (docs/engine.md): a ball shot and a change of gravity
    # move the ledger's start by the energy they add by hand (the ball's kinetic and
    # potential energy; every body's potential energy), a drag's target joint does work
    live, _ = small

    def miss() -> float:
        e = unpack(live.frame())[0]["energy"]
        total = e["kinetic"] + e["potential"] + e["lost"] - e["given"] - e["start"] - e["work"]
        return float(total / e["start"])

    for _ in range(10):
        live.single_step()
    live.obey(cmd("shoot", point=[2.0, 9.0], velocity=[3.0, 1.0]))
    assert abs(miss()) < 1e-12
    for _ in range(10):
        live.single_step()
    live.obey(cmd("set", name="gravity", value=4.0))
    live.single_step()
    assert abs(miss()) < 1e-12
    top = live.world.n_bodies - 2  # (the pyramid's top box; the ball is last)
    x = live.world.positions[top]
    live.obey(cmd("grab", point=list(x)))
    live.obey(cmd("drag", target=list(x + np.array([0.0, 2.0]))))
    for _ in range(30):
        live.single_step()
    # (round-off of sums of a few hundred joules over 50 steps)
    assert abs(miss()) < 1e-12


def test_joints_and_sleeping_islands_are_drawn() -> None:
    # the ragdoll pile: ten bodies and nine revolute joints a ragdoll; its bodies sleep
    live = Live("ragdoll-pile", clock=Clock())
    live.obey(cmd("draw", name="joints", on=True))
    live.obey(cmd("draw", name="sleeping", on=True))
    live.single_step()
    _, arrays = unpack(live.frame())
    ints, _ = live.world.joint_rows
    # each joint's two anchors (J, 2, 2), where the engine has them now
    assert arrays["joints"].shape == (ints.shape[0], 2, 2)
    np.testing.assert_allclose(arrays["joints"], live.world.joint_anchors(), rtol=1e-6, atol=1e-6)
    # each body's island (the root a sleeping body sleeps under; its own index otherwise)
    assert arrays["island"].shape == (live.world.n_bodies,)


def test_a_3d_grab_casts_a_ray_and_drags() -> None:
    # the 3D page sends the eye and the pointer's direction; the first body the ray meets is
    # held at the point it meets, and pulled toward the targets that follow
    live = Live("pyramid-3d", clock=Clock())
    x = live.world.positions
    top = int(np.argmax(x[:, 2]))
    eye = x[top] + np.array([0.0, 0.0, 5.0])
    reply = live.obey(cmd("grab", point=list(eye), direction=[0.0, 0.0, -1.0]))
    assert reply is not None
    assert reply["body"] == top
    # the point met: the top face of the top box (unit boxes), straight below the eye
    assert reply["point"][2] == pytest.approx(x[top, 2] + 0.5, abs=1e-9)
    live.obey(cmd("drag", target=list(x[top] + np.array([0.0, 0.0, 2.5]))))
    for _ in range(120):
        live.single_step()
    assert live.world.positions[top, 2] > x[top, 2] + 1.5
