"""Shots on the cloth in carom and in pooltool, the event-based billiards simulator.

carom moves a ball alone on a level cloth by the closed form of sliding, then rolling
(carom.engines.rigid3d.cloth); pooltool (Kiefl, ``pooltool-billiards`` on PyPI) solves the
same model event by event. This script plays the same shots in both, with the same ball and
cloth (pooltool's rolling friction ``u_r`` is carom's rolling resistance ``c`` as
``c / (R (1 + 2/5))``; its spinning friction, which carom does not have, at 1e-9, the least
it takes), and compares where the ball is, how fast it goes and spins at times before it
meets a cushion: carom at 60 Hz, each time a whole number of its steps. Then the two-ball
shot scenes (follow-shot, stun-shot, draw-shot, cut-shot) through ``carom compare``, as the
scenes are (e = 0.95) and with elastic balls (e = 1), where pooltool's ball-ball law and
carom's (Walton's, carom.collide) coincide (docs/compare.md).

pooltool cannot share carom's environment; it is installed when asked into its own
(:mod:`carom.compare.engines.pooltool_engine`, ``make pooltool``; ``--venv``, default
~/.cache/carom/pooltool) and runs there as a child process. Never in ``make test``.

Run:  python benchmarks/pooltool_shots.py [--venv DIR] [--no-record]
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import textwrap
from pathlib import Path

import numpy as np
from edmd import record  # benchmarks/edmd.py, beside this file

import carom
from carom.compare import compare
from carom.compare.engines.pooltool_engine import build, where
from carom.engines.stepped.settings import RigidSettings
from carom.scene import find_scene
from carom.shapes3d import Sphere

G = 9.81
R = 0.028575  # a pool ball's radius [m] and mass [kg], the billiards-3d scene's cloth
M = 0.17
MU = 0.2
C = 3e-4
RATE = 60.0
#: times to compare at [s]: whole numbers of carom's 60 Hz steps
TIMES = (0.1, 0.25, 0.5, 0.75)
#: velocity [m/s] and spin [rad/s] of each shot as the cue leaves the ball
SHOTS = {
    "stun": ([1.0, 0.0, 0.0], [0.0, 0.0, 0.0]),
    "follow": ([1.0, 0.0, 0.0], [0.0, 2.5 / R, 0.0]),
    "draw": ([1.0, 0.0, 0.0], [0.0, -4.0 / R, 0.0]),
    "draw back": ([0.6, 0.0, 0.0], [0.0, -5.0 / R, 0.0]),
    "oblique": ([0.6, 0.3, 0.0], [8.0, -20.0, 0.0]),
}
#: the two-ball scenes, held to pooltool by carom compare
SCENES = ("follow-shot", "stun-shot", "draw-shot", "cut-shot")

CHILD = textwrap.dedent(
    """
    import json, sys
    import numpy as np
    import pooltool as pt
    from pooltool.objects.ball.params import BallParams
    from pooltool.physics.engine import PhysicsEngine
    from pooltool.physics.resolve.resolver import default_resolver
    R, M, G, MU, C, shots, times = json.loads(sys.argv[1])
    table = pt.Table.default()
    found = {}
    for name, (v0, w0) in shots.items():
        ball = pt.Ball.create("cue", xy=(0.2 * table.w + 0.1, 0.5 * table.l))
        ball.params = BallParams(
            m=M, R=R, u_s=MU, u_r=C / (R * 1.4), u_sp_proportionality=1e-9, g=G
        )
        ball.state.rvw[1] = v0
        ball.state.rvw[2] = w0
        ball.state.s = 2  # sliding
        system = pt.System(cue=pt.Cue(cue_ball_id="cue"), table=table, balls={"cue": ball})
        # (an explicit engine: Resolver.default() would write ~/.config/pooltool)
        pt.simulate(system, engine=PhysicsEngine(resolver=default_resolver()), inplace=True)
        meets = [e.time for e in system.events if "cushion" in e.event_type.value]
        until = min(meets, default=float("inf"))
        rows = [t for t in times if t < until]  # (before the ball meets a cushion)
        pt.continuize(system, dt=0.05, inplace=True)
        states = system.balls["cue"].history_cts.states
        start = system.balls["cue"].history.states[0].rvw[0]
        out = []
        for t in rows:
            near = min(states, key=lambda s: abs(s.t - t))
            if abs(near.t - t) > 1e-9:
                continue
            rvw = np.array(near.rvw)
            out.append([t, *(rvw[0] - start).tolist(), *rvw[1].tolist(), *(R * rvw[2]).tolist()])
        found[name] = out
    print(json.dumps(found))
    """
)


def carom_shot(v0: list[float], w0: list[float], times: list[float]) -> list[np.ndarray]:
    """carom's ball at each of ``times`` [s] (ascending), in one run: its move, velocity and
    ``R`` times its spin (9,) at each."""
    world = carom.World(
        3, box=[8, 8, 1], boundary="open", gravity=[0, 0, -G],
        rigid=RigidSettings(rate=RATE, sleep=False),
    )  # fmt: skip
    world.add_plane([0, 0, 0], [0, 0, 1], material=carom.Material(0.5, friction=MU, rolling=C))
    start = np.array([4.0, 4.0, R])
    world.add_body(Sphere(R), start, velocity=v0, angular_velocity=w0, mass=M)
    found = []
    for t in times:
        world.run(until=t)
        found.append(
            np.concatenate(
                (world.positions[0] - start, world.velocities[0], R * world.angular_velocities[0])
            )
        )
    return found


HAN_CHILD = textwrap.dedent(
    """
    import json, sys
    import numpy as np
    from pooltool.physics.resolve.ball_cushion.han_2005.model import han2005
    s = json.loads(sys.stdin.read())
    out = []
    for v, w in s["states"]:
        rvw = np.array([[0.0, 0.0, s["R"]], v, w])
        after = han2005(rvw, np.array([1.0, 0.0, 0.0]), s["R"], s["m"], s["h"], s["e"], s["mu"])
        out.append([after[1].tolist(), after[2].tolist()])
    print(json.dumps(out))
    """
)


def cushions(python: Path) -> list[str]:
    """The cushion shots of tests/engines/rigid3d/test_cushion.py: each ball's state as it
    meets the nose (the closed form on the cloth), through Han's equations as the test writes
    them and through pooltool's own ``han2005``; and carom's run at 60, 240 and 1000 Hz
    against the closed form through Han's impact, 0.6 s after the shot."""
    import sys

    sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
    from tests.engines.rigid3d import test_cushion as t

    states, ours = [], []
    for name in t.SHOTS:
        (x, _), v0, w0 = t.SHOTS[name]
        reach = t.AREA[1][0] - t.R * np.cos(np.arcsin(t.H / t.R - 1.0)) - x
        lo, hi = 0.0, 1.0
        for _ in range(200):
            mid = 0.5 * (lo + hi)
            moved = t.closed_form(np.array(v0), np.array(w0), mid)[0][0]
            lo, hi = (mid, hi) if moved < reach else (lo, mid)
        _, v1, w1 = t.closed_form(np.array(v0), np.array(w0), lo)
        states.append([v1.tolist(), w1.tolist()])
        ours.append(t.han_2005(v1, w1, t.H, t.E_CUSHION, t.MU_CUSHION))
    given = {"states": states, "R": t.R, "m": t.M, "h": t.H, "e": t.E_CUSHION, "mu": t.MU_CUSHION}
    ran = subprocess.run(
        [str(python), "-c", HAN_CHILD], input=json.dumps(given), check=True,
        capture_output=True, text=True,
    )  # fmt: skip
    theirs = json.loads(ran.stdout.strip().splitlines()[-1])
    lines = [
        "Cushions (Han 2005, the nose 1.28 R above the cloth): the equations as "
        "tests/engines/rigid3d/test_cushion.py writes them against pooltool's han2005 on the "
        "same ball at the nose (largest difference of v and R w), and carom's run against "
        "the closed form through them 0.6 s after the shot (position, velocity, R w; the "
        "worst of 60, 240 and 1000 Hz):",
        "",
        "| shot | Han: test vs pooltool | carom: position [m] | velocity [m/s] | R w [m/s] |",
        "|---|---|---|---|---|",
    ]
    for k, name in enumerate(t.SHOTS):
        v, w = ours[k]
        pv, pw = np.array(theirs[k][0]), np.array(theirs[k][1])
        pv[2] = 0.0  # (pooltool leaves the vertical velocity as it was: 0 on the cloth)
        han = max(float(np.abs(v - pv).max()), float(np.abs(t.R * (w - pw)).max()))
        x, ve, we = t.expected(name, 0.6)
        worst = [0.0, 0.0, 0.0]
        for rate in (60.0, 240.0, 1000.0):
            world = t.shot_into_the_cushion(rate, name, 0.6)
            b = world.n_bodies - 1
            got = (world.positions[b] - x, world.velocities[b] - ve,
                   t.R * (world.angular_velocities[b] - we))  # fmt: skip
            worst = [max(a, float(np.abs(g).max())) for a, g in zip(worst, got, strict=True)]
        lines.append(f"| {name} | {han:.1e} | {worst[0]:.1e} | {worst[1]:.1e} | {worst[2]:.1e} |")
    return lines


def two_balls() -> list[str]:
    """The two-ball scenes through carom compare, as they are and with elastic balls: the
    largest difference from pooltool of any ball's position, velocity and angular velocity
    over the run (accuracy only: one run each is no measure of speed)."""
    lines = [
        "Two balls (carom compare SCENE --engines carom,pooltool), held to pooltool state by "
        "state at carom's 60 Hz steps to 1.5 s:",
        "",
        "| scene | balls | position [m] | velocity [m/s] | spin [rad/s] |",
        "|---|---|---|---|---|",
    ]
    for name in SCENES:
        text = find_scene(name).read_text()
        for label, e in (("e = 0.95", None), ("e = 1", "restitution = 1.0")):
            path = Path(os.environ.get("TMPDIR", "/tmp")) / f"pooltool-{name}-{label[4:]}.toml"
            path.write_text(text if e is None else text.replace("restitution = 0.95", e))
            result = compare(path, ["carom", "pooltool"])
            held = result.engines["carom"]["metrics"]["reference"]
            lines.append(
                f"| {name} | {label} | {held['position_m']:.2g} | {held['velocity_m_s']:.2g} | "
                f"{held['omega_rad_s']:.2g} |"
            )
    return lines


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--venv", type=Path, default=where())
    parser.add_argument("--no-record", action="store_true", help="do not append to RESULTS.md")
    args = parser.parse_args()
    python = build(args.venv)
    os.environ["CAROM_POOLTOOL"] = str(args.venv)  # (carom compare's pooltool: the same)
    given = json.dumps([R, M, G, MU, C, SHOTS, TIMES])
    ran = subprocess.run(
        [str(python), "-c", CHILD, given], check=True, capture_output=True, text=True
    )
    theirs = json.loads(ran.stdout.strip().splitlines()[-1])
    lines = [
        "| shot | t [s] | position [m] | velocity [m/s] | R x spin [m/s] |",
        "|---|---|---|---|---|",
    ]
    worst = 0.0
    for name, (v0, w0) in SHOTS.items():
        rows = theirs[name]
        for row, ours in zip(rows, carom_shot(v0, w0, [row[0] for row in rows]), strict=True):
            t, other = row[0], np.array(row[1:])
            gaps = [float(np.abs(ours[k : k + 3] - other[k : k + 3]).max()) for k in (0, 3, 6)]
            worst = max(worst, *gaps)
            lines.append(f"| {name} | {t:g} | " + " | ".join(f"{g:.1e}" for g in gaps) + " |")
    body = "\n".join(
        [
            f"One ball: carom at {RATE:g} Hz against pooltool, largest difference of any "
            "component:",
            "",
            *lines,
            "",
            f"largest difference over all: {worst:.1e}",
            "",
            *two_balls(),
            "",
            *cushions(python),
        ]
    )
    print(body)
    if not args.no_record:
        record("pooltool_shots: shots on the cloth, carom and pooltool", body + "\n")


if __name__ == "__main__":
    main()
