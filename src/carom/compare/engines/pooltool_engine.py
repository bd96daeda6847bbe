"""pooltool, the event-based billiards simulator, as a ``carom compare`` engine.

pooltool (Kiefl, ``pooltool-billiards`` on PyPI) moves balls on a cloth by the closed forms
of sliding, rolling and spinning and resolves each collision as an event; carom's stepped
engine moves a ball on a level cloth by the same closed forms (:mod:`carom.engines.rigid3d.cloth`)
and meets two balls by :func:`carom.collide`'s law. A scene of balls on a level cloth runs in
both, and ``carom compare`` reports how far apart they are.

pooltool cannot share carom's environment: 0.6.0 pins llvmlite < 0.46 (carom's Numba needs a
newer one) and, on Linux, a development build of panda3d that is not on PyPI. :func:`build`
installs it into its own virtual environment (``make pooltool``, or ``python -m
carom.compare.engines.pooltool_engine``): its dependencies from PyPI with panda3d 1.10.16,
then pooltool itself without its pins (``pip --no-deps``). The environment is
``$CAROM_POOLTOOL``, or ``~/.cache/carom/pooltool``. A comparison runs pooltool there as a
child process, which simulates the whole run as events at once and hands back every ball's
state at each of carom's steps.

Settings, by pooltool's names (its documentation, "Ball parameters" and "Modular physics"):

- ``u_s``: the cloth's sliding friction, carom's ball-cloth friction;
- ``u_r``: rolling friction as a deceleration over g, carom's rolling resistance ``c`` as
  ``c / (R (1 + 2/5))`` (carom's ``c g / (R (1 + k))``);
- ``u_sp_proportionality``: 1e-9, the least it takes (carom has no spinning friction);
- ``u_b``, ``e_b``: the balls' friction and restitution, with the ``frictional_inelastic``
  ball-ball model and its ``average`` friction (a constant, as carom's; pooltool's default
  is Alciatore's speed-dependent fit); ``e_c``, ``f_c``: the cushions', from the walls'
  material (pooltool's Stronge compliant cushion model against carom's box walls: the
  cushions differ, and :func:`carom.compare.driver.compare` compares the states only before
  pooltool's first ball-cushion event);
- an explicit physics engine, so that pooltool's ``Resolver.default()`` does not write its
  resolver file under ``~/.config``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

from carom.compare.rigid3d import RigidScene3D
from carom.engines.rigid3d.model import PIECE_PLANE, PIECE_ROUND
from carom.errors import CaromError
from carom.laws.kinds import KIND_DYNAMIC, KIND_STATIC

__all__ = ["POOLTOOL", "PooltoolSimulation", "build", "missing", "start_rigid", "version"]

FloatArray = NDArray[np.float64]

#: the release compared against
POOLTOOL = "pooltool-billiards==0.6.0"
#: pooltool's dependencies, pinned where its own pins cannot be met from PyPI
PINNED = (
    "numba>=0.59,<0.62",
    "llvmlite<0.46",
    "numpy",
    "scipy",
    "attrs",
    "cattrs",
    "msgpack",
    "msgpack-numpy",
    "pyyaml",
    "click",
    "pillow",
    "h5py",
    "rich",
    "numpy-quaternion",
    "panda3d==1.10.16",
    "panda3d-gltf",
    "panda3d-simplepbr",
)
#: a ball's moment of inertia over m R^2 in pooltool (its ball-ball model's 2/5)
SOLID = 0.4
#: balls must sit on the cloth and have pooltool's inertia to this [-] (relative)
SNUG = 1e-9
#: how long pooltool may take on a scene [s] (a few balls take it under a second)
PATIENCE = 300.0

CHILD = textwrap.dedent(
    """
    import json, sys, time
    from importlib.metadata import version
    import attrs
    import numpy as np
    import pooltool as pt
    from pooltool.objects.ball.params import BallParams
    from pooltool.objects.table.specs import BilliardTableSpecs
    from pooltool.physics.engine import PhysicsEngine
    from pooltool.physics.resolve.resolver import default_resolver
    from pooltool.physics.resolve.ball_ball.frictional_inelastic import FrictionalInelastic
    from pooltool.physics.resolve.ball_ball.friction import AverageBallBallFriction
    s = json.loads(sys.stdin.read())
    table = pt.Table.from_table_specs(BilliardTableSpecs(l=s["l"], w=s["w"]))
    params = BallParams(
        m=s["m"], R=s["R"], u_s=s["u_s"], u_r=s["u_r"], u_sp_proportionality=1e-9,
        u_b=s["u_b"], e_b=s["e_b"], e_c=s["e_c"], f_c=s["f_c"], g=s["g"],
    )
    balls = {}
    for i, row in enumerate(s["balls"]):
        ball = pt.Ball.create(str(i), xy=(row[0], row[1]))
        ball.params = params
        ball.state.rvw[0] = row[0:3]
        ball.state.rvw[1] = row[3:6]
        ball.state.rvw[2] = row[6:9]
        moving = any(row[3:9])
        ball.state.s = 2 if moving else 0  # sliding, or stationary
        balls[str(i)] = ball
    resolver = attrs.evolve(
        default_resolver(), ball_ball=FrictionalInelastic(friction=AverageBallBallFriction())
    )
    system = pt.System(cue=pt.Cue(cue_ball_id="0"), table=table, balls=balls)
    began = time.perf_counter()
    pt.simulate(system, engine=PhysicsEngine(resolver=resolver), inplace=True,
                t_final=s["until"])
    solved = time.perf_counter() - began
    meets = [e.time for e in system.events if "cushion" in e.event_type.value]
    pt.continuize(system, dt=s["dt"], inplace=True)
    times = [k * s["dt"] for k in range(s["steps"] + 1)]
    out = np.zeros((len(times), len(balls), 3, 3))
    for i in range(len(balls)):
        states = system.balls[str(i)].history_cts.states
        stamps = np.array([st.t for st in states])
        for k, t in enumerate(times):
            j = int(np.argmin(np.abs(stamps - t)))
            if abs(stamps[j] - t) > 1e-9 and t > stamps[-1]:
                j = len(states) - 1  # (at rest since its last state)
            elif abs(stamps[j] - t) > 1e-9:
                raise SystemExit(f"pooltool has no state at {t} s")
            out[k, i] = states[j].rvw
    print(json.dumps({
        "version": version("pooltool-billiards"), "solved_s": solved,
        "events": len(system.events), "cushion_s": min(meets, default=None),
        "rvw": out.tolist(),
    }))
    """
)


def where() -> Path:
    """pooltool's environment: ``$CAROM_POOLTOOL``, or ``~/.cache/carom/pooltool``."""
    given = os.environ.get("CAROM_POOLTOOL")
    return Path(given) if given else Path.home() / ".cache" / "carom" / "pooltool"


def _python(env: Path) -> Path:
    return env / "bin" / "python"


def missing() -> str | None:
    """None when pooltool's environment is ready, else how to make it."""
    if (where() / ".ready").exists() and _python(where()).exists():
        return None
    return (
        f"pooltool is not installed in its own environment ({where()}); run `make pooltool` "
        "(it cannot share carom's: its pins conflict with carom's Numba)"
    )


def version() -> str:
    """pooltool's version in its environment (the pinned release)."""
    return POOLTOOL.split("==")[1]


def build(env: Path | None = None) -> Path:
    """Make pooltool's own environment at ``env`` (default :func:`where`) once, as the module
    docstring says; return its Python."""
    env = env or where()
    python = _python(env)
    if not (env / ".ready").exists():
        subprocess.run([sys.executable, "-m", "venv", str(env)], check=True)
        pip = [str(python), "-m", "pip", "install", "-q"]
        subprocess.run([*pip, *PINNED], check=True)
        subprocess.run([*pip, "--no-deps", POOLTOOL], check=True)
        (env / ".ready").touch()
    return python


class PooltoolSimulation:
    """A scene of balls on a level cloth, solved by pooltool in its own process at the
    start; each step reads the next of carom's steps from the answer."""

    def __init__(self, scene: RigidScene3D) -> None:
        self.dt = scene.dt
        given, self.settings = _read(scene)
        self.notes = [
            "pooltool solves the whole run at once, event by event, in its own environment "
            "(make pooltool); wall time is its own simulate() call",
            "frictional_inelastic ball-ball model with average (constant) friction: Walton's "
            "law with no sticking restitution, the velocity across the cloth dropped",
            "u_r = c / (R (1 + 2/5)): carom's rolling resistance as a deceleration over g",
            "u_sp_proportionality = 1e-9: carom has no spinning friction",
            "cushions: pooltool's Stronge compliant model, carom's box walls; the states are "
            "compared before pooltool's first ball-cushion event",
        ]
        problem = missing()
        if problem is not None:
            raise CaromError(problem)
        steps = scene.steps(self.dt)
        payload = json.dumps({**given, "dt": self.dt, "steps": steps, "until": steps * self.dt})
        try:
            ran = subprocess.run(
                [str(_python(where())), "-c", CHILD],
                input=payload,
                capture_output=True,
                text=True,
                check=False,
                timeout=PATIENCE,
            )
        except subprocess.TimeoutExpired:
            raise CaromError(
                f"pooltool did not finish scene {scene.name!r} in {PATIENCE:g} s (0.6.0 loops "
                "on exactly head-on ball-ball impacts: set the balls a micrometre off the line)"
            ) from None
        if ran.returncode != 0:
            tail = ran.stderr.strip().splitlines()[-1:] or ["(no message)"]
            raise CaromError(f"pooltool failed on scene {scene.name!r}: {tail[0]}")
        answer = json.loads(ran.stdout.strip().splitlines()[-1])
        self.solved_in = float(answer["solved_s"])
        self.cushion_s = answer["cushion_s"]
        self.settings["events"] = answer["events"]
        self._rvw = np.asarray(answer["rvw"], float)  # (steps + 1, N, 3, 3)
        self._n = scene.n
        self._k = 0

    def step(self) -> None:
        self._k += 1

    def state(self) -> tuple[FloatArray, FloatArray, FloatArray, FloatArray]:
        rvw = self._rvw[min(self._k, self._rvw.shape[0] - 1)]
        turn = np.zeros((self._n, 4))
        turn[:, 0] = 1.0  # (pooltool keeps no orientation: a ball's does not matter)
        return rvw[:, 0].copy(), rvw[:, 1].copy(), turn, rvw[:, 2].copy()

    def close(self) -> None:
        """Nothing to release: the child has ended."""


def _read(scene: RigidScene3D) -> tuple[dict[str, Any], dict[str, Any]]:
    """The scene as pooltool's child takes it, and the settings chosen; a CaromError names
    what pooltool cannot take."""
    n, m = scene.n, scene.model
    kind = scene.kind
    gravity = np.asarray(scene.gravity, float)
    g = float(-gravity[2])
    if not (g > 0.0 and gravity[0] == 0.0 and gravity[1] == 0.0):
        raise CaromError(f"pooltool takes gravity straight down -z; this scene's is {gravity}")
    radius = mass = -1.0
    for i in range(n):
        pieces = scene.pieces[i]
        ball = (
            len(pieces) == 1
            and pieces[0].kind == PIECE_ROUND
            and pieces[0].vertices.shape[0] == 1
            and not np.any(pieces[0].vertices)
        )
        if kind[i] != KIND_DYNAMIC or not ball:
            raise CaromError(
                f"pooltool takes balls on a cloth only: body {i} of scene {scene.name!r} is not "
                "a dynamic sphere"
            )
        r, mi = float(pieces[0].radius), float(scene.mass[i])
        if radius < 0.0:
            radius, mass = r, mi
        if r != radius or mi != mass:
            raise CaromError(
                f"pooltool's ball-ball model takes balls of one radius and mass: body {i} has "
                f"R = {r} m and m = {mi} kg, body 0 R = {radius} m and m = {mass} kg"
            )
        ratio = float(scene.inertia[i][0, 0]) / (mi * r * r)
        if abs(ratio - SOLID) > SNUG * SOLID:
            raise CaromError(f"pooltool's balls are solid (I = 2/5 m R^2); body {i} has {ratio}")
    cloth = _cloth(scene, radius)
    world = scene.world()
    box = np.asarray(world.box, float)
    walls = [row for row in range(n, kind.shape[0]) if kind[row] == KIND_STATIC and row != cloth]
    ball_mat = int(m.material[0])
    if any(int(m.material[i]) != ball_mat for i in range(n)):
        raise CaromError("pooltool's balls share one set of parameters: give them one material")
    cloth_mat = int(m.material[cloth])
    cushion_mat = int(m.material[walls[0]]) if walls else cloth_mat
    given = {
        "R": radius,
        "m": mass,
        "g": g,
        "u_s": float(m.mu_table[ball_mat, cloth_mat]),
        "u_r": float(m.rolling_table[ball_mat, cloth_mat]) / (radius * (1.0 + SOLID)),
        "u_b": float(m.mu_table[ball_mat, ball_mat]),
        "e_b": float(m.e_table[ball_mat, ball_mat]),
        "e_c": float(m.e_table[ball_mat, cushion_mat]),
        "f_c": float(m.mu_table[ball_mat, cushion_mat]),
        "w": float(box[0]),
        "l": float(box[1]),
        "balls": [[*scene.position[i], *scene.velocity[i], *scene.omega[i]] for i in range(n)],
    }
    settings = {
        key: given[key] for key in ("R", "m", "g", "u_s", "u_r", "u_b", "e_b", "e_c", "f_c")
    }
    settings.update(
        u_sp_proportionality=1e-9,
        ball_ball="frictional_inelastic",
        ball_ball_friction="average",
        table=f"BilliardTableSpecs(l={given['l']}, w={given['w']})",
    )
    return given, settings


def _cloth(scene: RigidScene3D, radius: float) -> int:
    """The static body every ball rests on, a level face at z = 0 (the box's floor, or a
    plane); a CaromError when the balls are not on one."""
    heights = scene.position[: scene.n, 2]
    if np.any(np.abs(heights - radius) > SNUG * radius):
        raise CaromError(
            f"pooltool's balls rest on a cloth at z = 0: scene {scene.name!r} has ball centres "
            f"at heights {np.unique(heights)} m, not R = {radius} m"
        )
    for row in range(scene.n, scene.kind.shape[0]):
        if scene.kind[row] != KIND_STATIC:
            continue
        for piece in scene.pieces[row]:
            normals = piece.normals
            up = np.flatnonzero((normals[:, 2] == 1.0) & (normals[:, 0] == 0.0))
            for f in up:
                corner = piece.vertices if piece.kind == PIECE_PLANE else None
                top = scene.position[row, 2] + (
                    corner[0, 2]
                    if corner is not None
                    else piece.vertices[piece.corners[piece.face_first[f]], 2]
                )
                if abs(top) <= SNUG * radius:
                    return row
    raise CaromError(f"pooltool needs a level cloth at z = 0 under the balls of {scene.name!r}")


def start_rigid(scene: RigidScene3D) -> PooltoolSimulation:
    return PooltoolSimulation(scene)


def main() -> None:
    """``python -m carom.compare.engines.pooltool_engine``: make pooltool's environment."""
    parser = argparse.ArgumentParser(description="make pooltool's own environment")
    parser.add_argument("--venv", type=Path, default=None, help=f"default: {where()}")
    args = parser.parse_args()
    print(build(args.venv))


if __name__ == "__main__":
    main()
