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
from carom.geometry.rotation import matrix_quaternion, rotation_matrices
from carom.laws.kinds import KIND_DYNAMIC, KIND_KINEMATIC

__all__ = ["damping_ratio", "start", "start_rigid"]

DT = 0.002


def _options(model: Any) -> dict[str, Any]:
    """The model's step, integrator, solver, iterations, tolerance and friction cone, by
    MuJoCo's names."""
    opt = model.opt
    return {
        "dt_s": float(opt.timestep),
        "integrator": mujoco.mjtIntegrator(opt.integrator).name,
        "solver": mujoco.mjtSolver(opt.solver).name,
        "iterations": int(opt.iterations),
        "tolerance": float(opt.tolerance),
        "cone": mujoco.mjtCone(opt.cone).name,
    }


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
        self.settings: dict[str, Any] = {
            **_options(model),
            "noslip_iterations": int(model.opt.noslip_iterations),
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


# --- 3D rigid bodies --------------------------------------------------------------------

#: the step on rigid scenes [s]: MuJoCo's default
RIGID_DT = DT


def _numbers(values: Any) -> str:
    return " ".join(repr(float(c)) for c in np.ravel(values))


def _model(xml: str, name: str) -> Any:
    """MuJoCo's model of ``xml``; a model MuJoCo refuses is a CaromError naming the scene."""
    try:
        return mujoco.MjModel.from_xml_string(xml)
    except ValueError as refused:
        raise CaromError(f"MuJoCo refused its model of scene {name!r}: {refused}") from None


def _contact_settings(scene: Any) -> tuple[np.ndarray, int, str, float, list[str]]:
    """How MuJoCo's contacts are set for a rigid scene: friction per material (MuJoCo takes
    the larger of two geoms'), ``condim`` (1 when nothing has friction), the ``solref``
    attribute of the Modeling chapter's restitution recipe (empty for e = 0), the
    restitution, and the notes; a scene with more than one restitution is refused."""
    from carom.compare.yardstick import shape_coefficients

    pairs = scene.needed_pairs()
    values = sorted({float(scene.restitution[a, b]) for a, b in pairs})
    if len(values) > 1:
        raise CaromError(
            f"MuJoCo: scene {scene.name!r} has pairs with different restitutions "
            f"{values}; MuJoCo's solref recipe gives one; give every pair one restitution"
        )
    e = values[0] if values else 0.0
    mu, notes = shape_coefficients(scene, scene.friction, "max", "MuJoCo", "friction")
    condim = 1 if not np.any(mu > 0.0) else 3
    stiffness = 1.0 / (2.0 * RIGID_DT) ** 2
    solref = ""
    if e > 0.0:
        damping = 2.0 * damping_ratio(e) * math.sqrt(stiffness)
        solref = f' solref="{-stiffness!r} {-damping!r}"'
    return mu, condim, solref, e, notes


class MujocoRigidSimulation:
    """A 3D rigid scene in MuJoCo, as its Modeling chapter builds bodies.

    * Each dynamic body a ``freejoint`` body with carom's mass and full inertia tensor
      (``<inertial fullinertia>``) and its pieces as geoms: ``box``, ``sphere``, ``capsule``
      (``fromto``), ``mesh`` (MuJoCo collides a mesh as its convex hull) and ``plane``;
      static bodies' geoms in the world body. A concave static mesh is refused: MuJoCo would
      fill it in.
    * Friction: MuJoCo takes the larger of the two geoms' (condim 3); per-material values
      reproduce the scene's pairs, else the scene is refused. condim 1 when nothing has
      friction.
    * Restitution: none in MuJoCo; for ``e > 0`` the Modeling chapter's recipe, ``solref``
      ``(-stiffness, -damping)`` with the damping of a damped oscillator that bounces back
      with ``e`` (one restitution for every pair). For ``e = 0`` MuJoCo's default ``solref``.
    * A kinematic body is a ``mocap`` body, set to its pose before every step (MuJoCo's way
      to move a body it does not simulate).
    * ``implicitfast``, which the changelog (2.3.3) recommends for all new models; the
      default 0.002 s step, solver and pyramidal cone.
    * Joints (:func:`_joint_tree`): a joint to the world is a joint of MuJoCo's tree (``ball``,
      ``hinge``, ``slide``; a weld: none), its limits the joint's ``range``, its motor a
      ``velocity`` actuator saturated at the motor's torque or force (:func:`_motor`); a weld
      between two bodies nests one in the other; the other joints between two bodies are
      ``connect`` equality constraints (:func:`_equality`). Joined pairs that may not touch
      are excluded from contact (``<contact><exclude>``).
    """

    def __init__(self, scene: Any) -> None:
        from carom.compare.rigid3d import primitives

        parts = [primitives(scene, i) for i in range(scene.bodies)]
        for i, own in enumerate(parts):
            if any(part.shape == "mesh" for part in own):
                raise CaromError(
                    f"MuJoCo: body {i} of scene {scene.name!r} is a static triangle mesh; "
                    f"MuJoCo collides a mesh as its convex hull, which would fill it in; "
                    f"leave MuJoCo out of this scene"
                )
        mu, condim, solref, e, notes = _contact_settings(scene)
        assets: list[str] = []
        world: list[str] = []
        self.n = scene.n
        self.scene = scene
        self.time = 0.0
        parent, loops = _joint_tree(scene)
        if any(spec.motor is not None for spec in loops):
            raise CaromError(
                f"MuJoCo: scene {scene.name!r} has a motor on a joint that closes a loop; "
                "MuJoCo drives the joints of its tree"
            )
        children: dict[int, list[int]] = {}
        for child, (up, _) in sorted(parent.items()):
            children.setdefault(up, []).append(child)
        geoms: list[str] = []
        for i in range(scene.bodies):
            m = int(scene.material[i])
            common = f' condim="{condim}" friction="{float(mu[m])!r} 0 0"{solref}'
            geoms.append(
                "".join(
                    self._geom(part, f"b{i}p{k}", common, assets) for k, part in enumerate(parts[i])
                )
            )
            if scene.kind[i] != KIND_DYNAMIC:
                mocap = ' mocap="true"' if scene.kind[i] == KIND_KINEMATIC else ""
                world.append(
                    f'<body pos="{_numbers(scene.position[i])}" '
                    f'quat="{_numbers(scene.orientation[i])}"{mocap}>{geoms[i]}</body>'
                )

        def body(i: int) -> str:
            """Body ``i`` and the bodies it carries, in its parent's frame."""
            up, spec = parent.get(i, (-1, None))
            r = rotation_matrices(scene.orientation[i])[0]
            if up >= 0:
                r_up = rotation_matrices(scene.orientation[up])[0]
                pos = r_up.T @ (scene.position[i] - scene.position[up])
                quat = matrix_quaternion(r_up.T @ r)
            else:
                pos, quat = scene.position[i], scene.orientation[i]
            joint = "<freejoint/>" if spec is None else _tree_joint(spec, i, r, scene)
            inertia = scene.inertia[i]
            full = [inertia[0, 0], inertia[1, 1], inertia[2, 2]]
            full += [inertia[0, 1], inertia[0, 2], inertia[1, 2]]
            inner = "".join(body(c) for c in children.get(i, []))
            return (
                f'<body name="b{i}" pos="{_numbers(pos)}" quat="{_numbers(quat)}">{joint}'
                f'<inertial pos="0 0 0" mass="{float(scene.mass[i])!r}" '
                f'fullinertia="{_numbers(full)}"/>{geoms[i]}{inner}</body>'
            )

        driven = [(child, spec) for child, (_, spec) in sorted(parent.items()) if spec.motor]
        motors = "".join(_motor(spec, child) for child, spec in driven)
        roots = [
            i for i in range(scene.bodies) if scene.kind[i] == KIND_DYNAMIC and i not in parent
        ]
        tops = [c for c in children.get(-1, [])] + roots
        bodies = [body(i) for i in sorted(tops)]
        equality = "".join(_equality(spec, scene) for spec in loops)
        xml = (
            f'<mujoco model="{scene.name}"><compiler angle="radian"/>'
            f'<option timestep="{RIGID_DT!r}" gravity="{_numbers(scene.gravity)}" '
            f'integrator="implicitfast"/>'
            f"<asset>{''.join(assets)}</asset>"
            f"<worldbody>{''.join(world)}{''.join(bodies)}</worldbody>"
            f"{f'<equality>{equality}</equality>' if equality else ''}"
            f"{_exclusions(scene)}"
            f"{f'<actuator>{motors}</actuator>' if motors else ''}</mujoco>"
        )
        self.model = model = _model(xml, scene.name)
        self.data = data = mujoco.MjData(model)
        _servo_gains(model)
        for k, (child, spec) in enumerate(driven):  # each servo's speed, as the joint turns
            data.ctrl[k] = spec.motor[0] if child == spec.b else -spec.motor[0]
        self._rows = np.nonzero(scene.kind[: scene.n] == KIND_DYNAMIC)[0]
        self._ids = np.array(
            [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"b{row}") for row in self._rows],
            dtype=np.int64,
        )
        # the mocap bodies in the order MuJoCo numbers them (the world body's children first)
        self._mocap = [int(row) for row in np.nonzero(scene.kind == KIND_KINEMATIC)[0]]
        for row in self._rows:
            moving = np.any(scene.velocity[row]) or np.any(scene.omega[row])
            if row in parent:
                if moving:
                    raise CaromError(
                        f"MuJoCo: body {row} of scene {scene.name!r} is jointed and starts "
                        "moving; carom compare starts MuJoCo's jointed bodies at rest"
                    )
                continue
            qv = int(model.jnt_dofadr[model.body_jntadr[self._ids[list(self._rows).index(row)]]])
            data.qvel[qv : qv + 3] = scene.velocity[row]  # world frame
            r = rotation_matrices(scene.orientation[row])[0]
            data.qvel[qv + 3 : qv + 6] = r.T @ scene.omega[row]  # a free joint: body frame
        mujoco.mj_forward(model, data)
        self._static_x = scene.position[: scene.n].copy()
        self._static_q = scene.orientation[: scene.n].copy()
        self.dt = RIGID_DT
        self.settings: dict[str, Any] = {
            **_options(model),
            "condim": condim,
            "friction_per_material": mu.tolist(),
            "solref": model.geom_solref[0].tolist() if model.ngeom else None,
            "solimp": model.geom_solimp[0].tolist() if model.ngeom else None,
            "restitution": e,
        }
        self.notes = [
            *notes,
            "implicitfast integrator (recommended for all new models since 2.3.3); MuJoCo's "
            "default step 0.002 s, solver and cone",
            "carom's mass and full inertia tensor for each body (<inertial fullinertia>)",
            (
                f"restitution {e:g} by solref = (-stiffness, -damping), the Modeling chapter's "
                f"recipe, stiffness 1 / (2 dt)^2"
                if e > 0.0
                else "restitution 0: MuJoCo's default solref (0.02 s, critical damping)"
            ),
        ]

    @staticmethod
    def _geom(part: Any, name: str, common: str, assets: list[str]) -> str:
        """One primitive as an MJCF geom (a hull's mesh goes into ``assets``)."""
        if part.shape == "box":
            return (
                f'<geom type="box" pos="{_numbers(part.centre)}" size="{_numbers(part.half)}"'
                f"{common}/>"
            )
        if part.shape == "sphere":
            return (
                f'<geom type="sphere" pos="{_numbers(part.centre)}" '
                f'size="{float(part.radius)!r}"{common}/>'
            )
        if part.shape == "capsule":
            return (
                f'<geom type="capsule" fromto="{_numbers(part.ends)}" '
                f'size="{float(part.radius)!r}"{common}/>'
            )
        if part.shape == "hull":
            assets.append(f'<mesh name="{name}" vertex="{_numbers(part.vertices)}"/>')
            return f'<geom type="mesh" mesh="{name}"{common}/>'
        return (
            f'<geom type="plane" size="0 0 1" pos="{_numbers(part.normal * part.offset)}" '
            f'zaxis="{_numbers(part.normal)}"{common}/>'
        )

    def step(self) -> None:
        self.time += self.dt
        for k, row in enumerate(self._mocap):
            x, q = self.scene.kinematic_pose(row, self.time)
            self.data.mocap_pos[k] = x
            self.data.mocap_quat[k] = q
        mujoco.mj_step(self.model, self.data)

    def state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        n = self.n
        x, q = self._static_x.copy(), self._static_q.copy()
        v, w = np.zeros((n, 3)), np.zeros((n, 3))
        for k, kin in enumerate(self._mocap):
            if kin < n:
                x[kin], q[kin] = self.data.mocap_pos[k], self.data.mocap_quat[k]
                v[kin], w[kin] = self.scene.velocity[kin], self.scene.omega[kin]
        data, twist = self.data, np.zeros(6)
        for row, body in zip(self._rows, self._ids, strict=True):
            x[row] = data.xpos[body]
            q[row] = data.xquat[body]
            # (angular, linear) at the body's centre of mass, in the world's axes
            mujoco.mj_objectVelocity(self.model, data, mujoco.mjtObj.mjOBJ_BODY, body, twist, 0)
            w[row], v[row] = twist[:3], twist[3:]
        return x, v, q, w

    def close(self) -> None:
        pass


def _joint_tree(scene: Any) -> tuple[dict[int, tuple[int, Any]], list[Any]]:
    """MuJoCo's kinematic tree for the scene's joints: each body a joint carries, with its
    parent (-1: the world) and the joint. A joint to the world is a joint of the tree (a
    ball, hinge or slide joint; a weld: none, the body fixed in the world); a weld between
    two bodies fixes one in the other; the other joints between two bodies are equality
    constraints (``connect``), as MuJoCo closes loops: a chain of light bodies on ball joints
    in its tree (the rope's 30 balls of 0.4 g) goes unstable at its default step, and MuJoCo
    resets it, where free bodies held by ``connect`` run."""
    specs = list(scene.joints)
    for spec in specs:
        for end in (spec.a, spec.b):
            if end >= 0 and scene.kind[end] != KIND_DYNAMIC:
                raise CaromError(
                    f"MuJoCo: scene {scene.name!r} joins a static or kinematic body ({end}); "
                    "carom compare gives MuJoCo joints between dynamic bodies and the world"
                )
        if spec.kind not in ("spherical", "revolute", "prismatic", "weld"):
            raise CaromError(
                f"MuJoCo: scene {scene.name!r} has a {spec.kind} joint; carom compare gives "
                "MuJoCo spherical, revolute, prismatic and fixed joints"
            )
        if spec.spring is not None or spec.angular_spring is not None:
            raise CaromError(
                f"MuJoCo: scene {scene.name!r} has a joint with a spring; carom compare gives "
                "MuJoCo rigid joints (with limits and motors) only"
            )
    parent: dict[int, tuple[int, Any]] = {}
    used: set[int] = set()
    dynamic = [i for i in range(scene.bodies) if scene.kind[i] == KIND_DYNAMIC]
    for root in [-1, *dynamic]:
        if root >= 0 and root in parent:
            continue
        reached, frontier = {root}, [root]
        while frontier:
            here = frontier.pop(0)
            for k, spec in enumerate(specs):
                if k in used or here not in (spec.a, spec.b):
                    continue
                other = spec.b if spec.a == here else spec.a
                if here >= 0 and spec.kind != "weld":
                    continue
                if other < 0 or other in parent or other in reached or other == root:
                    continue
                parent[other] = (here, spec)
                used.add(k)
                reached.add(other)
                frontier.append(other)
        if root >= 0:
            parent.pop(root, None)
    return parent, [spec for k, spec in enumerate(specs) if k not in used]


def _tree_joint(spec: Any, child: int, turn: np.ndarray, scene: Any) -> str:
    """The MJCF joint that lets ``child`` move in its parent as ``spec`` says (``turn`` the
    child's rotation matrix at the start); empty for a weld."""
    if spec.kind == "weld":
        return ""
    forward = child == spec.b  # MuJoCo moves the child relative to its parent: B in A
    anchor = spec.anchor_b if forward else spec.anchor_a
    pos = turn.T @ (anchor - scene.position[child])
    if spec.kind == "spherical":
        return f'<joint name="j{child}" type="ball" pos="{_numbers(pos)}"/>'
    axis = turn.T @ (spec.axis if forward else -spec.axis)
    limits = ""
    if spec.limits is not None:
        low, high = spec.limits
        limits = f' limited="true" range="{low!r} {high!r}"'
    kind = "hinge" if spec.kind == "revolute" else "slide"
    return (
        f'<joint name="j{child}" type="{kind}" pos="{_numbers(pos)}" axis="{_numbers(axis)}"'
        f"{limits}/>"
    )


def _motor(spec: Any, child: int) -> str:
    """A joint's motor as MuJoCo's ``velocity`` actuator: a servo ``kv (speed - qvel)``
    clamped at the motor's largest torque or force. Its gain is set once the model is built
    (:func:`_servo_gains`)."""
    most = spec.motor[1]
    return (
        f'<velocity joint="j{child}" kv="1" forcelimited="true" forcerange="{-most!r} {most!r}"/>'
    )


def _servo_gains(model: Any) -> None:
    """Each velocity servo's gain ``kv = M / dt``, M the joint's own inertia (MuJoCo's
    ``dof_M0``): it would reach its speed in one explicit step, and ``implicitfast``, which
    counts the servo's damping in the step, keeps it stable. A much larger gain would make
    that damping swamp the clamped force (the joint all but stops accelerating)."""
    for k in range(model.nu):
        dof = int(model.jnt_dofadr[model.actuator_trnid[k, 0]])
        kv = float(model.dof_M0[dof]) / float(model.opt.timestep)
        model.actuator_gainprm[k, 0] = kv
        model.actuator_biasprm[k, 2] = -kv


def _equality(spec: Any, scene: Any) -> str:
    """A joint that closes a loop as MuJoCo's equality constraints: a ``connect`` at a
    spherical joint's anchor, two along a hinge's axis, a ``weld`` (its pose at the start);
    a slider in a loop is refused."""

    def local(body: int, point: np.ndarray) -> np.ndarray:
        r = rotation_matrices(scene.orientation[body])[0]
        turned: np.ndarray = r.T @ (point - scene.position[body])
        return turned

    a, b = (spec.a, spec.b) if spec.a >= 0 else (spec.b, spec.a)
    other = f' body2="b{b}"' if b >= 0 else ""
    anchor = spec.anchor_a if a == spec.a else spec.anchor_b
    if spec.kind == "weld":
        return f'<weld body1="b{a}"{other}/>'
    if spec.kind == "spherical":
        return f'<connect body1="b{a}"{other} anchor="{_numbers(local(a, anchor))}"/>'
    if spec.kind == "revolute":
        reach = max(float(scene.model.reach[a]), 0.05)
        return "".join(
            f'<connect body1="b{a}"{other} anchor="{_numbers(local(a, anchor + t * spec.axis))}"/>'
            for t in (-reach, reach)
        )
    raise CaromError(
        f"MuJoCo: scene {scene.name!r} closes a loop with a prismatic joint, which MuJoCo has "
        "no equality constraint for"
    )


def _exclusions(scene: Any) -> str:
    """MuJoCo's ``<contact><exclude>`` for the joined pairs that may not touch (it leaves a
    parent and its child apart already; a joint to the world needs nothing)."""
    pairs = sorted(
        {
            (min(s.a, s.b), max(s.a, s.b))
            for s in scene.joints
            if not s.collide and min(s.a, s.b) >= 0
        }
    )
    if not pairs:
        return ""
    return (
        "<contact>"
        + "".join(f'<exclude body1="b{a}" body2="b{b}"/>' for a, b in pairs)
        + "</contact>"
    )


def start_rigid(scene: Any) -> MujocoRigidSimulation | MujocoPlanarSimulation:
    if scene.dim == 2:
        return MujocoPlanarSimulation(scene)
    return MujocoRigidSimulation(scene)


class MujocoPlanarSimulation:
    """A 2D rigid scene with joints in MuJoCo: its bodies in the plane z = 0.

    * Each dynamic body a ``body`` with two ``slide`` joints (x, y) and a ``hinge`` about z,
      carom's mass and moment about z; a circle a ``sphere``, a capsule a ``capsule``, a
      polygon a prism (a ``mesh``: its corners at z = +-H), H the largest reach in the scene,
      so that every pair meets across the same depth; static bodies' geoms in the world body.
      Rounded polygons, static segments and kinematic bodies are refused.
    * The joints as equality constraints, the way MuJoCo closes loops (its tree has only
      the plane's joints): a revolute joint a ``connect`` at the pin, a weld a ``weld``, a
      distance joint a spatial tendon between two sites, held at its length by a ``tendon``
      equality (a rod), limited to its range (a rope), or with the tendon's ``stiffness`` and
      ``damping`` (a spring: ``k = m w^2``, ``c = 2 m zeta w`` with the reduced mass). Limits,
      motors and springs on the other joints, and sliders and wheels, are refused.
    * Contacts, step and integrator as :class:`MujocoRigidSimulation`.
    """

    def __init__(self, scene: Any) -> None:
        mu, condim, solref, e, notes = _contact_settings(scene)
        kinds = np.asarray(scene.kind)
        if np.any(kinds == KIND_KINEMATIC):
            raise CaromError(
                f"MuJoCo: scene {scene.name!r} has a kinematic body; carom compare gives MuJoCo "
                "2D scenes of dynamic and static bodies"
            )
        depth = max(
            float(np.max(np.linalg.norm(piece.vertices, axis=1))) + piece.radius
            for pieces in scene.pieces[: scene.n]
            for piece in pieces
        )
        assets: list[str] = []
        world: list[str] = []
        bodies: list[str] = []
        sites: dict[int, list[str]] = {}
        tendons: list[str] = []
        equality: list[str] = []
        for k, spec in enumerate(scene.joints):
            problem = _planar_joint(spec, k, scene, sites, tendons, equality)
            if problem:
                raise CaromError(
                    f"MuJoCo: scene {scene.name!r} has {problem}; carom compare gives MuJoCo's "
                    "2D scenes revolute joints, welds and distance joints (rods, ropes, "
                    "springs), without limits or motors"
                )
        for i in range(scene.bodies):
            m = int(scene.material[i])
            common = f' condim="{condim}" friction="{float(mu[m])!r} 0 0"{solref}'
            # the body's frame keeps the world's axes (its slide joints move along x and y);
            # its pieces are turned by its angle at the start instead
            turn = float(scene.angle[i])
            c, s = math.cos(turn), math.sin(turn)
            geoms = "".join(
                _planar_geom(
                    piece.vertices @ np.array([[c, s], [-s, c]]), float(piece.radius),
                    f"b{i}p{k}", depth, common, assets, scene.name, i,
                )
                for k, piece in enumerate(scene.pieces[i])
            )  # fmt: skip
            where = f"{float(scene.position[i, 0])!r} {float(scene.position[i, 1])!r} 0"
            quat = "1 0 0 0"
            own = "".join(sites.get(i, []))
            if kinds[i] == KIND_DYNAMIC:
                moment = float(scene.inertia[i])
                bodies.append(
                    f'<body name="b{i}" pos="{where}" quat="{quat}">'
                    f'<joint type="slide" axis="1 0 0"/><joint type="slide" axis="0 1 0"/>'
                    f'<joint type="hinge" axis="0 0 1"/>'
                    f'<inertial pos="0 0 0" mass="{float(scene.mass[i])!r}" '
                    f'diaginertia="{moment!r} {moment!r} {moment!r}"/>{geoms}{own}</body>'
                )
            else:
                world.append(f'<body name="b{i}" pos="{where}" quat="{quat}">{geoms}{own}</body>')
        gravity = f"{float(scene.gravity[0])!r} {float(scene.gravity[1])!r} 0"
        xml = (
            f'<mujoco model="{scene.name}"><compiler angle="radian"/>'
            f'<option timestep="{RIGID_DT!r}" gravity="{gravity}" integrator="implicitfast"/>'
            f"<asset>{''.join(assets)}</asset>"
            f"<worldbody>{''.join(sites.get(-1, []))}{''.join(world)}{''.join(bodies)}"
            "</worldbody>"
            f"{f'<tendon>{chr(10).join(tendons)}</tendon>' if tendons else ''}"
            f"{f'<equality>{chr(10).join(equality)}</equality>' if equality else ''}"
            f"{_exclusions(scene)}</mujoco>"
        )
        self.model = model = _model(xml, scene.name)
        self.data = data = mujoco.MjData(model)
        self.n = scene.n
        self._rows = np.nonzero(kinds[: scene.n] == KIND_DYNAMIC)[0]
        ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_BODY, f"b{r}") for r in self._rows]
        self._qpos = np.array([model.jnt_qposadr[model.body_jntadr[b]] for b in ids], np.int64)
        self._qvel = np.array([model.jnt_dofadr[model.body_jntadr[b]] for b in ids], np.int64)
        for row, qv in zip(self._rows, self._qvel, strict=True):
            data.qvel[qv : qv + 2] = scene.velocity[row]
            data.qvel[qv + 2] = scene.omega[row]
        mujoco.mj_forward(model, data)
        self._x0 = np.asarray(scene.position[: scene.n], np.float64).copy()
        self._angle0 = np.asarray(scene.angle[: scene.n], np.float64).copy()
        self.dt = RIGID_DT
        self.settings: dict[str, Any] = {
            **_options(model),
            "condim": condim,
            "friction_per_material": mu.tolist(),
            "restitution": e,
            "plane": "slide x, slide y, hinge z per body; prisms H deep",
            "depth_m": depth,
        }
        self.notes = [
            *notes,
            "2D: each body on two slide joints and a hinge in the plane z = 0 (MuJoCo's "
            "planar bodies); circles as spheres, polygons as prisms",
            "joints as equality constraints (connect, weld) and spatial tendons (distance "
            "joints), the way MuJoCo closes loops",
            "implicitfast integrator; MuJoCo's default step 0.002 s, solver and cone",
        ]

    def step(self) -> None:
        mujoco.mj_step(self.model, self.data)

    def state(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        x, angle = self._x0.copy(), self._angle0.copy()
        v, w = np.zeros((self.n, 2)), np.zeros(self.n)
        qpos, qvel = self.data.qpos, self.data.qvel
        for row, qp, qv in zip(self._rows, self._qpos, self._qvel, strict=True):
            x[row] += qpos[qp : qp + 2]  # a slide joint counts from the body's start
            angle[row] += qpos[qp + 2]
            v[row] = qvel[qv : qv + 2]
            w[row] = qvel[qv + 2]
        return x, v, angle, w

    def close(self) -> None:
        pass


def _planar_geom(
    corners: np.ndarray,
    radius: float,
    name: str,
    depth: float,
    common: str,
    assets: list[str],
    scene: str,
    body: int,
) -> str:
    """One 2D piece, its ``corners`` (k, 2) [m] in its body's frame (turned to the world's
    axes) and rounding ``radius`` [m], as a MuJoCo geom in the plane z = 0 (a prism ``depth``
    deep each way)."""
    if corners.shape[0] == 1:
        centre = f"{float(corners[0, 0])!r} {float(corners[0, 1])!r} 0"
        return f'<geom type="sphere" pos="{centre}" size="{radius!r}"{common}/>'
    if corners.shape[0] == 2 and radius > 0.0:
        ends = " ".join(f"{float(c)!r}" for c in (*corners[0], 0.0, *corners[1], 0.0))
        return f'<geom type="capsule" fromto="{ends}" size="{radius!r}"{common}/>'
    if radius > 0.0 or corners.shape[0] < 3:
        raise CaromError(
            f"MuJoCo: body {body} of scene {scene!r} has a rounded polygon or a bare segment; "
            "carom compare gives MuJoCo circles, capsules and polygons in 2D"
        )
    prism = [(*c, z) for z in (-depth, depth) for c in corners.tolist()]
    assets.append(f'<mesh name="{name}" vertex="{_numbers(prism)}"/>')
    return f'<geom type="mesh" mesh="{name}"{common}/>'


def _planar_joint(
    spec: Any,
    k: int,
    scene: Any,
    sites: dict[int, list[str]],
    tendons: list[str],
    equality: list[str],
) -> str | None:
    """Joint ``k`` as MuJoCo equality constraints (and a tendon between two sites), appended
    to ``sites`` (per body, -1 the world), ``tendons`` and ``equality``; what cannot be
    given, in words, else None."""

    def local(body: int, point: np.ndarray) -> str:
        """A world point in ``body``'s frame (its axes the world's: see the builder)."""
        at = point if body < 0 else point - scene.position[body]
        return f"{float(at[0])!r} {float(at[1])!r} 0"

    if spec.motor is not None or spec.angular_spring is not None:
        return f"a {spec.kind} joint with a motor or an angular spring"
    a, b = (spec.a, spec.b) if spec.a >= 0 else (spec.b, spec.a)
    anchor_a = spec.anchor_a if a == spec.a else spec.anchor_b
    other = f' body2="b{b}"' if b >= 0 else ""
    if spec.kind == "revolute":
        if spec.limits is not None or spec.spring is not None:
            return "a revolute joint with limits or a spring"
        equality.append(f'<connect body1="b{a}"{other} anchor="{local(a, anchor_a)}"/>')
        return None
    if spec.kind == "weld":
        if spec.spring is not None:
            return "a soft weld"
        equality.append(f'<weld body1="b{a}"{other}/>')
        return None
    if spec.kind != "distance":
        return f"a {spec.kind} joint"
    for end, body, point in (("a", spec.a, spec.anchor_a), ("b", spec.b, spec.anchor_b)):
        sites.setdefault(body, []).append(
            f'<site name="j{k}{end}" pos="{local(body, point)}" size="0.001"/>'
        )
    path = f'<site site="j{k}a"/><site site="j{k}b"/>'
    if spec.spring is not None:
        hertz, ratio = spec.spring
        mass = 1.0 / sum(1.0 / float(scene.mass[i]) for i in (spec.a, spec.b) if i >= 0)
        omega = 2.0 * math.pi * hertz
        stiff, damp = mass * omega * omega, 2.0 * mass * ratio * omega
        tendons.append(
            f'<spatial name="t{k}" stiffness="{stiff!r}" damping="{damp!r}" '
            f'springlength="{spec.length!r}">{path}</spatial>'
        )
    elif spec.limits is not None:
        low, high = spec.limits
        tendons.append(
            f'<spatial name="t{k}" limited="true" range="{low!r} {high!r}">{path}</spatial>'
        )
    else:
        tendons.append(f'<spatial name="t{k}">{path}</spatial>')
        # the tendon's length held at its length at the start (qpos0)
        equality.append(f'<tendon tendon1="t{k}" polycoef="0 0 0 0 0"/>')
    return None
