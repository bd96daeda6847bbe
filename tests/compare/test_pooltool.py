"""pooltool, the event-based billiards simulator, in ``carom compare``.

pooltool lives in its own environment (``make pooltool``; it cannot share carom's,
carom.compare.engines.pooltool_engine). What needs no pooltool is tested always: the scenes it
refuses and why, what a missing pooltool says, and how the others are held to it state by
state. The runs against pooltool itself are skipped, with the reason, where its environment is
not made (as the other peers' tests are where they are not installed).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from carom.cli import main
from carom.compare import compare
from carom.compare.driver import against_reference, peer_scene
from carom.compare.engines import ENGINES
from carom.compare.engines.pooltool_engine import _read
from carom.errors import CaromError
from carom.scene import find_scene

SHOTS = ["follow-shot", "stun-shot", "draw-shot", "cut-shot"]


def _nowhere(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    monkeypatch.setenv("CAROM_POOLTOOL", str(tmp_path / "no-pooltool"))


def test_a_missing_pooltool_says_how_to_make_it(
    monkeypatch: pytest.MonkeyPatch, tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _nowhere(monkeypatch, tmp_path)
    problem = ENGINES["pooltool"].missing()
    assert problem is not None
    assert "make pooltool" in problem
    with pytest.raises(CaromError, match="make pooltool"):
        compare("follow-shot", ["carom", "pooltool"])
    # not asked for by name: carom runs, and pooltool is named among the engines skipped
    result = compare("follow-shot")
    assert "carom" in result.engines
    assert "make pooltool" in result.skipped["pooltool"]
    # the command line: exit 2, the reason, no traceback, nothing written
    out = tmp_path / "out"
    code = main(["compare", "follow-shot", "--engines", "pooltool", "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2
    assert "make pooltool" in err
    assert "Traceback" not in err
    assert not out.exists()


@pytest.mark.parametrize(
    ("scene", "pattern"),
    [
        ("pyramid-3d", r"body 0 .* is not a dynamic sphere"),
        ("spin-ball-3d", r"is not a dynamic sphere|rest on a cloth"),
        ("wall-and-ball", r"not a dynamic sphere|rest on a cloth"),
    ],
)
def test_pooltool_takes_balls_on_a_cloth_only(scene: str, pattern: str) -> None:
    with pytest.raises(CaromError, match=pattern):
        _read(peer_scene(scene))  # type: ignore[arg-type]


def test_pooltool_is_given_the_scenes_ball_and_cloth() -> None:
    # pooltool's parameters are carom's materials: the cloth's friction (u_s), its rolling
    # resistance c as a deceleration over g (u_r = c / (R (1 + 2/5))), the balls' friction
    # and restitution; every ball's position, velocity and spin as the scene starts
    given, settings = _read(peer_scene("follow-shot"))  # type: ignore[arg-type]
    r = 0.028575
    assert given["R"] == r
    assert given["m"] == 0.17
    assert given["u_s"] == 0.2
    assert given["u_r"] == pytest.approx(3e-4 / (r * 1.4), rel=1e-15)
    assert (given["u_b"], given["e_b"]) == (0.05, 0.95)
    assert given["balls"][0] == pytest.approx([0.5, 1.0, r, 2.0, 0, 0, 0, 2.0 / r, 0])
    assert given["balls"][1][:3] == pytest.approx([1.0, 1.000001, r])
    assert settings["ball_ball"] == "frictional_inelastic"


def test_the_engines_are_held_to_the_reference_state_by_state() -> None:
    # two engines' traces: the differences are the largest over the times both observed, up
    # to the reference's first cushion (0.25 s here: the 0.3 s sample is not compared)
    def trace(offset: float) -> dict[str, list]:
        times = [0.0, 0.1, 0.2, 0.3]
        x = [np.full((2, 3), t + (offset if t < 0.25 else 9.0)) for t in times]
        return {"time": times, "x": x, "v": [2 * a for a in x], "w": [3 * a for a in x]}

    runs = {
        "pooltool": {"metrics": {}, "trace": trace(0.0), "reference_until_s": 0.25},
        "carom": {"metrics": {}, "trace": trace(1e-3)},
    }
    against_reference(runs)
    held = runs["carom"]["metrics"]["reference"]
    assert held["engine"] == "pooltool"
    assert held["position_m"] == pytest.approx(1e-3)
    assert held["velocity_m_s"] == pytest.approx(2e-3)
    assert held["omega_rad_s"] == pytest.approx(3e-3)
    assert held["until_s"] == 0.2


def _need_pooltool() -> None:
    problem = ENGINES["pooltool"].missing()
    if problem is not None:
        pytest.skip(problem)


#: how far carom may be from pooltool on each shot with elastic balls: position [m],
#: velocity [m/s], angular velocity [rad/s] (the test says why)
ELASTIC = {
    "follow-shot": (2e-6, 1e-8, 1e-6),
    "stun-shot": (2e-6, 1e-8, 1e-6),
    "draw-shot": (2e-6, 1e-8, 1e-6),
    "cut-shot": (5e-5, 4e-5, 2e-3),
}


@pytest.mark.parametrize("name", SHOTS)
def test_carom_is_pooltool_on_the_shots_with_elastic_balls(name: str, tmp_path: Path) -> None:
    # With e = 1 carom's impact (Walton's law, carom.collide) and pooltool's
    # frictional_inelastic agree (pooltool's friction impulse is u_b e v_n, Coulomb's
    # u_b (1 + e) / 2 v_n: the same at e = 1). What is left is pooltool's spacer: it sets the
    # balls s = 1 um apart along their paths before the impact. Head-on that moves the
    # balls by s (measured 1.0e-6 m) and the velocities by round-off (6e-10 m/s); in the
    # half-ball cut it turns the line of centres by s tan(30 deg) / 2R = 1.0e-5 rad, which
    # turns the velocities by up to 2 m/s x 1.0e-5 = 2e-5 m/s (measured 1.7e-5) and moves
    # the balls by that over the 1.3 s after (measured 1.8e-5 m)
    _need_pooltool()
    path = tmp_path / f"{name}.toml"
    path.write_text(find_scene(name).read_text().replace("restitution = 0.95", "restitution = 1.0"))
    result = compare(path, ["carom", "pooltool"])
    held = result.engines["carom"]["metrics"]["reference"]
    assert held["until_s"] == pytest.approx(1.5)
    position, velocity, omega = ELASTIC[name]
    assert held["position_m"] < position
    assert held["velocity_m_s"] < velocity
    assert held["omega_rad_s"] < omega
