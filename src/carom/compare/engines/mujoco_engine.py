"""MuJoCo in a comparison, set up as its Modeling chapter recommends.

* The default step ``0.002`` s, Euler integrator, Newton solver.
* Each body a ``freejoint`` with a ``sphere`` geom; walls are ``plane`` geoms, one per box
  face (a 2D scene runs in the plane z = 0 without walls across z).
* ``condim = 1``: frictionless contact, as the scene has no friction.
* MuJoCo has no coefficient of restitution. Its Modeling chapter ("Restitution") gives the
  recipe: ``solref`` in the direct form ``(-stiffness, -damping)``, "stiffness some reasonably
  large value and damping zero" for restitution 1. For ``e < 1`` the damping comes from the
  damped oscillator ``e = exp(-pi zeta / sqrt(1 - zeta^2))``, ``damping = 2 zeta
  sqrt(stiffness)``. The stiffness is ``1 / (2 dt)^2``: the stiffest the docs advise (time
  constant at least two steps).
* Walls carry ``priority = 1`` so their own ``solref`` (the wall's restitution) decides body-
  wall contacts; between bodies MuJoCo averages the two geoms' ``solref`` (``solmix``).
"""

from __future__ import annotations

import math
from typing import Any

import mujoco
import numpy as np

from carom.compare.spec import PeerScene
from carom.errors import CaromError

__all__ = ["damping_ratio", "start"]

DT = 0.002


def damping_ratio(e: float) -> float:
    """The damping ratio zeta of a linear spring-damper whose bounce has restitution ``e``:
    ``e = exp(-pi zeta / sqrt(1 - zeta^2))``; 1 (critical, no bounce) for ``e = 0``."""
    if e <= 0.0:
        return 1.0
    log_e = math.log(e)
    return -log_e / math.sqrt(math.pi**2 + log_e**2)


class MujocoSimulation:
    def __init__(self, scene: PeerScene) -> None:
        pair = scene.pair_restitution
        body_e = np.diag(pair).copy()
        stiffness = 1.0 / (2.0 * DT) ** 2
        body_damping = np.array([2.0 * damping_ratio(e) * math.sqrt(stiffness) for e in body_e])
        mixed = 0.5 * (body_damping[:, None] + body_damping[None, :])
        wanted = np.array(
            [[2.0 * damping_ratio(e) * math.sqrt(stiffness) for e in row] for row in pair]
        )
        if np.any(np.abs(mixed - wanted) > 1e-9 * np.maximum(1.0, wanted)):
            raise CaromError(
                f"MuJoCo averages the two geoms' damping, which cannot give the pair "
                f"restitutions of scene {scene.name!r}; give the bodies one restitution"
            )
        walls = scene.wall_restitution
        if np.any(walls != walls[0]):
            raise CaromError(
                f"MuJoCo: the walls of scene {scene.name!r} meet bodies of different "
                f"restitutions; give the bodies one restitution"
            )
        dim = self.dim = scene.dim

        def three(v: np.ndarray) -> str:
            return " ".join(repr(float(c)) for c in [*v, *[0.0] * (3 - dim)])

        geoms = []
        for face in range(2 * dim):
            axis, upper = divmod(face, 2)
            normal = np.zeros(3)
            normal[axis] = -1.0 if upper else 1.0
            point = np.zeros(3)
            point[axis] = scene.box[axis] if upper else 0.0
            damping = 2.0 * damping_ratio(float(walls[0, face])) * math.sqrt(stiffness)
            geoms.append(
                f'<geom type="plane" size="0 0 1" pos="{three(point[:dim])}" '
                f'zaxis="{three(normal[:dim])}" priority="1" condim="1" '
                f'solref="{-stiffness!r} {-damping!r}"/>'
            )
        bodies = [
            f'<body pos="{three(scene.positions[i])}"><freejoint/>'
            f'<geom type="sphere" size="{float(scene.radius[i])!r}" '
            f'mass="{float(scene.mass[i])!r}" condim="1" '
            f'solref="{-stiffness!r} {-float(body_damping[i])!r}"/></body>'
            for i in range(scene.n)
        ]
        memory = max(64, scene.n // 20)  # MB: contacts and constraints of a dense gas
        xml = (
            f'<mujoco model="{scene.name}"><size memory="{memory}M"/>'
            f'<option timestep="{DT!r}" gravity="{three(scene.gravity)}"/>'
            f"<worldbody>{''.join(geoms)}{''.join(bodies)}</worldbody></mujoco>"
        )
        self.model = model = mujoco.MjModel.from_xml_string(xml)
        self.data = data = mujoco.MjData(model)
        qvel = data.qvel.reshape(scene.n, 6)
        qvel[:, :dim] = scene.velocities  # a free joint's linear velocity is in world axes
        mujoco.mj_forward(model, data)
        self.dt = DT
        opt = model.opt
        self.settings: dict[str, Any] = {
            "dt_s": float(opt.timestep),
            "integrator": mujoco.mjtIntegrator(opt.integrator).name,
            "solver": mujoco.mjtSolver(opt.solver).name,
            "iterations": int(opt.iterations),
            "tolerance": float(opt.tolerance),
            "cone": mujoco.mjtCone(opt.cone).name,
            "noslip_iterations": int(opt.noslip_iterations),
            "condim": 1,
            "solref_body_first": model.geom_solref[2 * dim].tolist(),
            "solref_walls": model.geom_solref[: 2 * dim].tolist(),
            "solimp": model.geom_solimp[2 * dim].tolist(),
            "margin_m": float(model.geom_margin[2 * dim]),
            "stiffness_per_kg": stiffness,
            "restitution_combine": "walls: priority; bodies: solmix average of solref",
            "walls": "plane geoms, priority 1",
            "memory_MB": memory,
            "ccd": "none for sphere-sphere and sphere-plane (analytic contacts)",
        }
        self.notes = [
            "no restitution coefficient in MuJoCo: solref = (-stiffness, -damping) per its "
            "Modeling chapter (Restitution), damping from e = exp(-pi zeta / sqrt(1 - zeta^2))",
            f"stiffness 1 / (2 dt)^2 = {stiffness:g} 1/s^2: time constant two steps, the "
            f"stiffest MuJoCo advises",
            "condim = 1: frictionless contacts",
        ]

    def step(self) -> None:
        mujoco.mj_step(self.model, self.data)

    def state(self) -> tuple[np.ndarray, np.ndarray]:
        n, dim = self.model.nbody - 1, self.dim
        x = self.data.qpos.reshape(n, 7)[:, :dim].copy()
        v = self.data.qvel.reshape(n, 6)[:, :dim].copy()
        return x, v

    def close(self) -> None:
        pass


def start(scene: PeerScene) -> MujocoSimulation:
    return MujocoSimulation(scene)
