"""Write the built-in scenes with joints (issue 43): pendulums, a chain bridge, a ragdoll
pile, a car on wheel joints over bumpy ground, Newton's cradle on strings.

Bodies and joints are laid out here, in Python, and written out as plain TOML (each body its
own ``[[bodies]]`` table, in order, so that a joint's ``bodies = [a, b]`` are the indices the
scene gives them). tests/scenarios/test_builtin_scenes.py runs every built-in scene. Run from
the repository root:

    python scripts/make_joint_scenes.py
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

FOLDER = Path(__file__).resolve().parent.parent / "src" / "carom" / "scenarios"


def number(x: float) -> str:
    return repr(round(float(x), 9))


def value(v: Any) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, str):
        return f'"{v}"'
    if isinstance(v, list | tuple):
        return "[" + ", ".join(value(x) for x in v) + "]"
    if isinstance(v, int):
        return str(v)
    return number(v)


class Scene:
    """Bodies and joints in the order they are added, written as TOML."""

    def __init__(self, title: str, description: str, world: dict[str, Any]) -> None:
        self.head = {"scene": {"title": title, "description": description}, "world": world}
        self.extra: list[tuple[str, dict[str, Any]]] = []
        self.bodies: list[dict[str, Any]] = []
        self.joints: list[dict[str, Any]] = []
        self.tail: dict[str, dict[str, Any]] = {}

    def body(self, **keys: Any) -> int:
        self.bodies.append(keys)
        return len(self.bodies) - 1

    def joint(self, **keys: Any) -> None:
        self.joints.append(keys)

    def write(self, name: str) -> None:
        lines: list[str] = []
        for table, keys in self.head.items():
            lines.append(f"[{table}]")
            lines += [f"{k} = {value(v)}" for k, v in keys.items()]
            lines.append("")
        for table, keys in self.extra:
            lines.append(f"[[{table}]]" if table == "materials" else f"[{table}]")
            lines += [f"{k} = {value(v)}" for k, v in keys.items()]
            lines.append("")
        for index, keys in enumerate(self.bodies):
            lines.append(f"[[bodies]]  # {index}")
            lines += [f"{k} = {value(v)}" for k, v in keys.items()]
            lines.append("")
        for keys in self.joints:
            lines.append("[[joints]]")
            lines += [f"{k} = {value(v)}" for k, v in keys.items()]
            lines.append("")
        for table, keys in self.tail.items():
            lines.append(f"[{table}]")
            lines += [f"{k} = {value(v)}" for k, v in keys.items()]
            lines.append("")
        (FOLDER / f"{name}.toml").write_text("\n".join(lines).rstrip() + "\n")


def pendulums() -> None:
    s = Scene(
        "Pendulums",
        "Three pendulums from one bar, let go at 60 degrees: a bob on a 1 m rod (a distance "
        "joint: its period is 4 sqrt(L/g) K(sin 30 deg) = 2.153 s, 7.3% longer than a small "
        "swing's), a 1 m bar pinned at its end (a revolute joint: a physical pendulum, L = 2/3 "
        "m) and a double pendulum of two 0.5 m bars (chaotic).",
        {"dimension": 2, "box": [6.0, 4.0], "boundary": "open", "gravity": [0.0, -9.81]},
    )
    s.tail = {"run": {"until": 10.0, "frame_interval": 1 / 30}}
    theta = math.pi / 3
    c, si = math.cos(theta), math.sin(theta)
    pivot = (1.0, 3.5)
    bob = s.body(shape="circle", radius=0.05, positions=[[pivot[0] + si, pivot[1] - c]])
    s.joint(type="distance", bodies=[-1, bob], anchors=[list(pivot), [pivot[0] + si, pivot[1] - c]])
    pivot = (3.0, 3.5)
    bar = s.body(
        shape="box", size=[0.04, 1.0], positions=[[pivot[0] + 0.5 * si, pivot[1] - 0.5 * c]],
        angles=theta,
    )  # fmt: skip
    s.joint(type="revolute", bodies=[-1, bar], anchor=list(pivot))
    pivot = (5.0, 3.5)
    upper = s.body(
        shape="box", size=[0.04, 0.5], positions=[[pivot[0] + 0.25 * si, pivot[1] - 0.25 * c]],
        angles=theta,
    )  # fmt: skip
    elbow = [pivot[0] + 0.5 * si, pivot[1] - 0.5 * c]
    lower = s.body(
        shape="box", size=[0.04, 0.5], positions=[[elbow[0] + 0.25, elbow[1]]],
        angles=math.pi / 2,
    )  # fmt: skip
    s.joint(type="revolute", bodies=[-1, upper], anchor=list(pivot))
    s.joint(type="revolute", bodies=[upper, lower], anchor=elbow)
    s.write("pendulums")


def chain_bridge() -> None:
    links, width, span = 40, 0.5, 18.0
    s = Scene(
        "Chain bridge",
        f"A bridge of {links} planks 0.5 m long pinned end to end (revolute joints) between "
        f"two pins {span:g} m apart, hung as a V; boxes and a ball fall on it.",
        {"dimension": 2, "box": [24.0, 12.0], "boundary": "open", "gravity": [0.0, -9.81]},
    )
    s.extra.append(("materials", {"name": "wood", "restitution": 0.1, "friction": 0.6}))
    s.tail = {"run": {"until": 8.0, "frame_interval": 1 / 30}}
    half = links // 2
    drop = math.sqrt((width * half) ** 2 - (span / 2) ** 2)
    slope = math.atan2(-drop, span / 2)
    x0, y0 = 3.0, 10.0
    ends = [(x0, y0)]
    for k in range(links):
        turn = slope if k < half else -slope
        ends.append((ends[-1][0] + width * math.cos(turn), ends[-1][1] + width * math.sin(turn)))
    planks = [
        s.body(
            shape="box",
            size=[width, 0.1],
            positions=[[(ends[k][0] + ends[k + 1][0]) / 2, (ends[k][1] + ends[k + 1][1]) / 2]],
            angles=slope if k < half else -slope,
            material="wood",
        )
        for k in range(links)
    ]
    for k, x in enumerate((8.0, 10.5, 14.0)):
        s.body(shape="box", size=[0.6, 0.6], positions=[[x, 9.0 + k]], material="wood")
    s.body(shape="circle", radius=0.4, positions=[[16.0, 10.0]], material="wood")
    pairs = [[-1, planks[0]]] + [[planks[k], planks[k + 1]] for k in range(links - 1)]
    pairs.append([planks[-1], -1])
    s.joint(type="revolute", bodies=pairs, anchor=[list(e) for e in ends])
    s.write("chain-bridge")


def ragdoll(s: Scene, x: float, y: float, material: str) -> None:
    """A ragdoll standing with its feet at (x, y): torso, head, arms and legs in two parts,
    joined by revolute joints with limits (elbows and knees bend one way)."""
    cap = math.pi / 2
    torso = s.body(shape="box", size=[0.3, 0.6], positions=[[x, y + 1.2]], material=material)
    head = s.body(shape="circle", radius=0.12, positions=[[x, y + 1.65]], material=material)
    s.joint(type="revolute", bodies=[torso, head], anchor=[x, y + 1.52], limits=[-0.5, 0.5])
    for side in (-1.0, 1.0):
        upper = s.body(
            shape="capsule", size=0.25, radius=0.05, positions=[[x + side * 0.3, y + 1.45]],
            material=material,
        )  # fmt: skip
        lower = s.body(
            shape="capsule", size=0.25, radius=0.05, positions=[[x + side * 0.6, y + 1.45]],
            material=material,
        )  # fmt: skip
        s.joint(
            type="revolute", bodies=[torso, upper], anchor=[x + side * 0.15, y + 1.45],
            limits=[-cap, cap],
        )  # fmt: skip
        s.joint(
            type="revolute", bodies=[upper, lower], anchor=[x + side * 0.45, y + 1.45],
            limits=[0.0, 2.5] if side > 0 else [-2.5, 0.0],
        )  # fmt: skip
        thigh = s.body(
            shape="capsule", size=0.3, radius=0.07, positions=[[x + side * 0.08, y + 0.7]],
            angles=cap, material=material,
        )  # fmt: skip
        shin = s.body(
            shape="capsule", size=0.3, radius=0.06, positions=[[x + side * 0.08, y + 0.25]],
            angles=cap, material=material,
        )  # fmt: skip
        s.joint(
            type="revolute", bodies=[torso, thigh], anchor=[x + side * 0.08, y + 0.9],
            limits=[-1.0, 1.0],
        )  # fmt: skip
        s.joint(
            type="revolute", bodies=[thigh, shin], anchor=[x + side * 0.08, y + 0.48],
            limits=[-2.5, 0.0],
        )  # fmt: skip


def ragdoll_pile() -> None:
    s = Scene(
        "Ragdoll pile",
        "Twelve ragdolls (ten bodies and nine limited revolute joints each) dropped in turn "
        "into a pit; they tumble, fold at the elbows and knees and pile up.",
        {"dimension": 2, "box": [8.0, 16.0], "boundary": "open", "gravity": [0.0, -9.81]},
    )
    s.extra.append(("materials", {"name": "cloth", "restitution": 0.0, "friction": 0.6}))
    s.tail = {"run": {"until": 8.0, "frame_interval": 1 / 30}}
    s.body(shape="box", size=[8.0, 0.5], positions=[[4.0, 0.25]], kind="static", material="cloth")
    for x in (0.25, 7.75):
        s.body(shape="box", size=[0.5, 6.0], positions=[[x, 3.5]], kind="static", material="cloth")
    for k in range(12):
        ragdoll(
            s, 2.2 + 1.8 * (k % 3) + 0.1 * (k % 2), 1.0 + 2.2 * (k // 3) + 0.3 * (k % 3), "cloth"
        )
    s.write("ragdoll-pile")


def car() -> None:
    s = Scene(
        "Car on wheel joints",
        "A car (a chassis and two wheels on wheel joints: springs of 4 Hz along the suspension "
        "and motors of 8 N m driving the wheels) drives over bumpy ground.",
        {"dimension": 2, "box": [40.0, 10.0], "boundary": "open", "gravity": [0.0, -9.81]},
    )
    s.extra.append(("materials", {"name": "rubber", "restitution": 0.0, "friction": 0.9}))
    s.tail = {"run": {"until": 10.0, "frame_interval": 1 / 30}}
    ground = [[0.0, 2.0], [6.0, 2.0]]
    for k in range(1, 14):
        x = 6.0 + 2.0 * k
        ground.append([x, 2.0 + 0.25 * math.sin(1.3 * k) + (0.6 if k in (5, 10) else 0.0)])
    ground.append([40.0, 2.0])
    s.body(shape="chain", vertices=ground, positions=[[0.0, 0.0]], kind="static", material="rubber")
    chassis = s.body(shape="box", size=[2.4, 0.5], positions=[[3.0, 3.3]], density=2.0)
    for x in (2.1, 3.9):
        wheel = s.body(shape="circle", radius=0.4, positions=[[x, 2.45]], material="rubber")
        s.joint(
            type="wheel", bodies=[chassis, wheel], anchor=[x, 2.45], axis=[0.0, 1.0],
            spring=[4.0, 0.7], motor=[-12.0, 8.0],
        )  # fmt: skip
    s.write("car")


def cradle_on_strings() -> None:
    s = Scene(
        "Newton's cradle on strings",
        "Five balls of 5 cm hung on 0.5 m strings (distance joints), touching in a row; the "
        "first is let go from 0.4 rad. It strikes at 0.88 m/s and the last ball leaves at "
        "99.98% of that speed, the others staying within 1e-4 of it: the impacts are taken "
        "pair by pair, at their times within the substep, where a soft step alone would share "
        "the blow among all five.",
        {"dimension": 2, "box": [2.0, 1.2], "boundary": "open", "gravity": [0.0, -9.81]},
    )
    s.extra.append(("materials", {"name": "steel", "restitution": 1.0, "friction": 0.0}))
    s.tail = {"run": {"until": 6.0, "frame_interval": 1 / 60}}
    radius, length, theta = 0.05, 0.5, 0.4
    for k in range(5):
        pivot = [0.8 + 2 * radius * k, 1.0]
        if k == 0:
            at = [pivot[0] - length * math.sin(theta), pivot[1] - length * math.cos(theta)]
        else:
            at = [pivot[0], pivot[1] - length]
        ball = s.body(shape="circle", radius=radius, positions=[at], material="steel")
        s.joint(type="distance", bodies=[-1, ball], anchors=[pivot, at])
    s.write("cradle-on-strings")


def rope_3d() -> None:
    s = Scene(
        "Rope in 3D",
        "A rope of 30 balls on spherical joints hung from one end and let go sideways; a "
        "hinged door swings beside it on a revolute joint about z, and a ball on a fixed "
        "joint rides a bar that slides on a prismatic joint (3D joints).",
        {"dimension": 3, "box": [6.0, 4.0, 5.0], "boundary": "open", "gravity": [0.0, 0.0, -9.81]},
    )
    s.tail = {"run": {"until": 6.0, "frame_interval": 1 / 30}}
    links, step = 30, 0.1
    balls = [
        s.body(shape="ball", radius=0.045, positions=[[1.0 + step * (k + 1), 2.0, 4.5]])
        for k in range(links)
    ]
    s.joint(type="spherical", bodies=[-1, balls[0]], anchor=[1.0 + step / 2, 2.0, 4.5])
    for k in range(links - 1):
        s.joint(
            type="spherical", bodies=[balls[k], balls[k + 1]],
            anchor=[1.0 + step * (k + 1.5), 2.0, 4.5],
        )  # fmt: skip
    door = s.body(shape="box", size=[1.0, 0.05, 1.6], positions=[[4.6, 1.0, 1.0]])
    s.joint(
        type="revolute", bodies=[-1, door], anchor=[4.1, 1.0, 1.0], axis=[0.0, 0.0, 1.0],
        motor=[1.5, 20.0], limits=[-2.0, 2.0],
    )  # fmt: skip
    bar = s.body(shape="box", size=[0.6, 0.1, 0.1], positions=[[3.0, 3.0, 2.0]])
    s.joint(
        type="prismatic", bodies=[-1, bar], anchor=[3.0, 3.0, 2.0], axis=[1.0, 0.0, 0.0],
        limits=[-1.5, 1.5], motor=[0.8, 10.0],
    )  # fmt: skip
    ball = s.body(shape="ball", radius=0.15, positions=[[3.0, 3.0, 2.25]])
    s.joint(type="fixed", bodies=[bar, ball], anchor=[3.0, 3.0, 2.1])
    s.write("rope-3d")


if __name__ == "__main__":
    pendulums()
    chain_bridge()
    ragdoll_pile()
    car()
    cradle_on_strings()
    rope_3d()
