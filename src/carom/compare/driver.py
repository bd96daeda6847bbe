"""Run one scene in several engines and measure each the same way."""

from __future__ import annotations

import platform
import sys
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from carom.compare.closed_form import Expectation, expectation
from carom.compare.engines import ENGINES, EngineEntry, engine
from carom.compare.jointed import JointGauge
from carom.compare.monitor import Monitor
from carom.compare.rigid import ImpactCheck, RigidMonitor, RigidScene, impact_expectation
from carom.compare.rigid3d import (
    ImpactCheck3D,
    RigidMonitor3D,
    RigidScene3D,
    impact_expectation3d,
)
from carom.compare.spec import PeerScene
from carom.errors import CaromError
from carom.scene import Scene, find_scene, load_scene

__all__ = ["Comparison", "RigidComparison", "compare", "peer_scene"]


@dataclass
class Comparison:
    """The outcome of :func:`compare`.

    Attributes
    ----------
    scene : PeerScene
        The scene every engine ran.
    expected : Expectation or None
        The closed form the engines were held to.
    engines : dict
        Per engine name: ``version``, ``dt_s``, ``settings``, ``notes``, ``setup_s``,
        ``wall_s`` (time inside its step calls), ``simulated_s`` and ``metrics``
        (:meth:`carom.compare.monitor.Monitor.result`), and ``series`` (time, energy,
        penetration) for the plot.
    skipped : dict
        Engines asked for but not run, with the reason.
    """

    scene: PeerScene
    expected: Expectation | None
    engines: dict[str, dict[str, Any]]
    skipped: dict[str, str]

    @property
    def title(self) -> str:
        """The scene's title."""
        return self.scene.title

    def to_json(self) -> dict[str, Any]:
        """Everything but the series, as JSON-ready data."""
        return {
            "scene": self.scene.name,
            "title": self.title,
            "dimension": self.scene.dim,
            "bodies": self.scene.n,
            "until_s": self.scene.until,
            "closed_form": None if self.expected is None else self.expected.source,
            "checks": []
            if self.expected is None
            else [
                {
                    "time_s": c.time,
                    "energy_J": c.energy,
                    "velocities_known": c.velocities is not None,
                }
                for c in self.expected.checks
            ],
            **_runs_json(self.engines, self.skipped),
        }


def _runs_json(engines: dict[str, dict[str, Any]], skipped: dict[str, str]) -> dict[str, Any]:
    """The machine, each engine's run but its series, and the engines skipped."""
    return {
        "machine": {"python": platform.python_version(), "processor": platform.machine()},
        "engines": {
            name: {k: v for k, v in run.items() if k not in ("series", "trace")}
            for name, run in engines.items()
        },
        "skipped": skipped,
    }


def peer_scene(
    scene: str | Path | Scene, until: float | None = None, name: str | None = None
) -> PeerScene | RigidScene | RigidScene3D:
    """The scene of a built-in scene name, a scene file or a :class:`Scene`, as the engines
    take it: a :class:`PeerScene` of spheres, or a :class:`RigidScene` (2D) or
    :class:`RigidScene3D` when the scene runs carom's rigid-body engine."""
    if not isinstance(scene, Scene):
        path = find_scene(scene)
        name = name or path.stem
        scene = load_scene(path)
    name = name or Path(scene.source).stem
    run = scene.run
    title = scene.scene.get("title") or name
    world = scene.build()
    if world.engine_name == "rigid":
        rigid = RigidScene3D if world.dim == 3 else RigidScene
        return rigid.from_world(
            lambda: world, name, until if until is not None else run["until"], title
        )
    return PeerScene.from_world(
        lambda: world,
        name,
        until if until is not None else run["until"],
        run["frame_interval"],
        title,
    )


@dataclass
class RigidComparison:
    """The outcome of :func:`compare` on a scene of rigid bodies.

    Attributes
    ----------
    scene : RigidScene or RigidScene3D
        The scene every engine ran.
    expected : ImpactCheck or ImpactCheck3D or None
        The closed form of a body landing on flat ground, when the scene is one.
    engines : dict
        Per engine name: ``version``, ``dt_s``, ``settings``, ``notes``, ``setup_s``,
        ``wall_s`` (time inside its step calls), ``ms_per_step``, ``simulated_s``,
        ``metrics`` (:meth:`carom.compare.rigid.RigidMonitor.result`) and ``series``.
    skipped : dict
        Engines asked for but not run, with the reason.
    """

    scene: RigidScene | RigidScene3D
    expected: ImpactCheck | ImpactCheck3D | None
    engines: dict[str, dict[str, Any]]
    skipped: dict[str, str]

    @property
    def title(self) -> str:
        """The scene's title."""
        return self.scene.title

    def to_json(self) -> dict[str, Any]:
        """Everything but the series, as JSON-ready data."""
        check = self.expected
        return {
            "scene": self.scene.name,
            "title": self.title,
            "dimension": self.scene.dim,
            "bodies": self.scene.n,
            "until_s": self.scene.until,
            "closed_form": None if check is None else check.source,
            "joint_closed_form": (
                JointGauge(self.scene).source if self.scene.joint_ints.shape[0] else None
            ),
            "checks": []
            if check is None
            else [
                {
                    "body": check.body,
                    "impact_time_s": check.impact_time,
                    "time_s": check.time,
                    "velocity_m_s": check.velocity.tolist(),
                    "omega_rad_s": np.asarray(check.omega).tolist(),
                }
            ],
            **_runs_json(self.engines, self.skipped),
        }


def default_engines(dim: int, kind: str = "spheres", joints: bool = False) -> list[str]:
    """carom and every peer that simulates ``dim`` dimensions of ``kind`` bodies, and with
    ``joints`` the peers that take such a scene with joints (the others are then skipped,
    with the reason)."""
    return [
        e.name
        for e in ENGINES.values()
        if e.takes(dim, kind) or (joints and e.takes(dim, kind, joints))
    ]


def compare(
    scene: str | Path | Scene | PeerScene | RigidScene | RigidScene3D,
    engines: Sequence[str] | None = None,
    *,
    until: float | None = None,
    progress: bool | None = False,
) -> Comparison | RigidComparison:
    """Run ``scene`` in each engine and measure them against the closed form.

    Parameters
    ----------
    scene : str, Path, Scene or PeerScene
        A built-in scene name, a scene file, or a scene.
    engines : sequence of str, optional
        Engine names (``carom``, ``pymunk``, ``pybullet``, ``mujoco``); default: every
        engine for the scene's dimension. Peers that are not installed are skipped (and
        named in :attr:`Comparison.skipped`) unless asked for by name.
    until : float, optional
        Simulated time [s]; default the scene's ``[run] until``.
    progress : bool or None, default False
        A progress bar per engine on standard error (tqdm); None shows it only when standard
        error is a terminal.

    Returns
    -------
    Comparison or RigidComparison
        Per engine: its settings, wall time and measurements (a :class:`RigidComparison`
        when the scene runs carom's rigid-body engine: the closed form of a body landing on
        flat ground, whether a stack stands, ms per step).

    Raises
    ------
    CaromError
        Unknown engine; a named engine that is not installed or cannot simulate the scene;
        a scene no peer can represent (periodic box, static bodies, friction).

    Examples
    --------
    >>> result = compare("case-1", ["carom"])  # head-on, equal masses, e = 1
    >>> result.engines["carom"]["metrics"]["velocity_error"]
    0.0
    >>> result.expected.checks[0].velocities.tolist()  # the spheres swap velocities [m/s]
    [[-1.0, 0.0], [1.0, 0.0]]
    """
    spec = (
        scene
        if isinstance(scene, PeerScene | RigidScene | RigidScene3D)
        else peer_scene(scene, until)
    )
    kind = "rigid" if isinstance(spec, RigidScene | RigidScene3D) else "spheres"
    asked = engines is not None
    jointed = isinstance(spec, RigidScene | RigidScene3D) and spec.joint_ints.shape[0] > 0
    names = list(engines) if engines is not None else default_engines(spec.dim, kind, jointed)
    chosen: list[EngineEntry] = []
    skipped: dict[str, str] = {}
    for name in names:
        e = engine(name)
        problem = e.unable(spec.dim, kind, jointed)
        if problem is not None:
            if asked:
                raise CaromError(problem)
            skipped[name] = problem
            continue
        chosen.append(e)
    if isinstance(spec, RigidScene | RigidScene3D):
        if isinstance(spec, RigidScene):
            check: ImpactCheck | ImpactCheck3D | None = impact_expectation(spec, spec.dt)
        else:  # the peers step at their own documented rates; the check waits for the slowest
            check = impact_expectation3d(spec, max([spec.dt, *(e.rigid_dt(spec) for e in chosen)]))
        rigid = {}
        for e in chosen:
            try:
                rigid[e.name] = run_rigid(e, spec, check, progress)
            except CaromError as refused:  # a peer that cannot build this scene
                if asked or e.name == "carom":
                    raise
                skipped[e.name] = str(refused)
        if REFERENCE in rigid:
            against_reference(rigid)
        return RigidComparison(spec, check, rigid, skipped)
    expected = expectation(spec)
    runs = {}
    for e in chosen:
        runs[e.name] = run_engine(e, spec, expected, progress)
    return Comparison(spec, expected, runs, skipped)


def run_engine(
    e: EngineEntry, scene: PeerScene, expected: Expectation | None, progress: bool | None = False
) -> dict[str, Any]:
    """Set ``e`` up, step it to ``until`` with the monitor watching; time only the steps."""
    return _run(e, scene, lambda dt: Monitor(scene, expected, dt), 1, progress)


#: a scene of more bodies than this is looked at ten times a simulated second, not every step
DENSE_BODIES = 1000
#: the engine the others are held to, state by state, when it runs: pooltool, event-based,
#: whose billiards model carom's cloth shares (:mod:`carom.compare.engines.pooltool_engine`)
REFERENCE = "pooltool"
#: the states of a scene of at most this many bodies are kept for that
TRACED_BODIES = 64


def against_reference(runs: dict[str, dict[str, Any]]) -> None:
    """Add to each engine's metrics how far its states are from the reference's
    (:data:`REFERENCE`) at the times both observed, up to the reference's first event that
    the others model otherwise (pooltool: a ball meeting a cushion): ``reference`` with the
    largest difference of any body's position [m], velocity [m/s] and angular velocity
    [rad/s], and the time compared to [s]."""
    ref = runs[REFERENCE]
    times = {round(t, 9): k for k, t in enumerate(ref["trace"]["time"])}
    until = ref.get("reference_until_s")
    for run in runs.values():
        trace = run.get("trace")
        if trace is None:
            continue
        worst = [0.0, 0.0, 0.0]
        last = 0.0
        for k, t in enumerate(trace["time"]):
            j = times.get(round(t, 9))
            if j is None or (until is not None and t > until):
                continue
            last = max(last, t)
            for c, key in enumerate(("x", "v", "w")):
                gap = np.abs(trace[key][k] - ref["trace"][key][j]).max(initial=0.0)
                worst[c] = max(worst[c], float(gap))
        run["metrics"]["reference"] = {
            "engine": REFERENCE,
            "position_m": worst[0],
            "velocity_m_s": worst[1],
            "omega_rad_s": worst[2],
            "until_s": last,
        }


def run_rigid(
    e: EngineEntry,
    scene: RigidScene | RigidScene3D,
    expected: ImpactCheck | ImpactCheck3D | None,
    progress: bool | None,
) -> dict[str, Any]:
    """Set ``e`` up for a rigid scene, step it to ``until``; time only the steps."""
    dense = scene.n > DENSE_BODIES

    def watch(dt: float) -> RigidMonitor | RigidMonitor3D:
        if isinstance(scene, RigidScene3D):
            assert expected is None or isinstance(expected, ImpactCheck3D)
            return RigidMonitor3D(scene, expected, dt)
        assert expected is None or isinstance(expected, ImpactCheck)
        return RigidMonitor(scene, expected, dt)

    return _run(
        e,
        scene,
        watch,
        max(1, round(0.1 * scene.settings.rate)) if dense else 1,
        progress,
    )


def _run(
    e: EngineEntry,
    scene: PeerScene | RigidScene | RigidScene3D,
    watch: Callable[[float], Monitor | RigidMonitor | RigidMonitor3D],
    stride: int,
    progress: bool | None,
) -> dict[str, Any]:
    """Step ``e`` to ``until``, showing its state to the monitor ``watch(interval)`` every
    ``stride`` steps (and after the last); time only the step calls."""
    began = time.perf_counter()
    sim = e.start(scene)
    setup = time.perf_counter() - began
    traced = isinstance(scene, RigidScene | RigidScene3D) and scene.n <= TRACED_BODIES
    trace: dict[str, list[Any]] = {"time": [], "x": [], "v": [], "w": []}

    def look(t: float) -> None:
        state = sim.state()
        monitor.observe(t, *state)
        if traced:
            trace["time"].append(t)
            trace["x"].append(np.array(state[0], float))
            trace["v"].append(np.array(state[1], float))
            trace["w"].append(np.array(state[3], float))

    try:
        steps = scene.steps(sim.dt)
        monitor = watch(sim.dt * stride)
        look(0.0)
        wall = 0.0
        bar = tqdm(
            total=steps,
            disable=None if progress is None else not progress,
            file=sys.stderr,
            desc=f"{e.name:<9}",
            unit="step",
            leave=True,
        )
        with bar:
            for k in range(1, steps + 1):
                began = time.perf_counter()
                sim.step()
                wall += time.perf_counter() - began
                if k % stride == 0 or k == steps:
                    look(k * sim.dt)
                bar.update()
    finally:
        sim.close()
    # an engine that solved the whole run as it started (pooltool, in its own process) says
    # how long its own solving took: its steps only read the answer
    wall = float(getattr(sim, "solved_in", wall))
    extra: dict[str, Any] = {"trace": trace} if traced else {}
    if getattr(sim, "cushion_s", None) is not None:
        extra["reference_until_s"] = float(sim.cushion_s)
    return {
        **extra,
        "version": e.version(),
        "dt_s": sim.dt,
        "settings": sim.settings,
        "notes": sim.notes,
        "setup_s": setup,
        "wall_s": wall,
        "ms_per_step": 1e3 * wall / steps,
        "ms_per_simulated_s": 1e3 * wall / (steps * sim.dt),
        "simulated_s": steps * sim.dt,
        "steps": steps,
        "metrics": monitor.result(),
        "series": monitor.series,
    }
