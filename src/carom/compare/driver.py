"""Run one scene in several engines and measure each the same way."""

from __future__ import annotations

import platform
import sys
import time
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from tqdm import tqdm

from carom.compare.closed_form import Expectation, expectation
from carom.compare.engines import ENGINES, EngineEntry, engine
from carom.compare.monitor import Monitor
from carom.compare.spec import PeerScene
from carom.errors import CaromError
from carom.scene import Scene, find_scene, load_scene

__all__ = ["Comparison", "compare", "peer_scene"]


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
            "machine": {"python": platform.python_version(), "processor": platform.machine()},
            "engines": {
                name: {k: v for k, v in run.items() if k != "series"}
                for name, run in self.engines.items()
            },
            "skipped": self.skipped,
        }


def peer_scene(
    scene: str | Path | Scene, until: float | None = None, name: str | None = None
) -> PeerScene:
    """The :class:`PeerScene` of a built-in scene name, a scene file or a :class:`Scene`."""
    if not isinstance(scene, Scene):
        path = find_scene(scene)
        name = name or path.stem
        scene = load_scene(path)
    name = name or Path(scene.source).stem
    run = scene.run
    return PeerScene.from_world(
        scene.build,
        name,
        until if until is not None else run["until"],
        run["frame_interval"],
        scene.scene.get("title") or name,
    )


def default_engines(dim: int) -> list[str]:
    """carom and every peer that simulates ``dim`` dimensions."""
    return [e.name for e in ENGINES.values() if dim in e.dims]


def compare(
    scene: str | Path | Scene | PeerScene,
    engines: Sequence[str] | None = None,
    *,
    until: float | None = None,
    progress: bool | None = False,
) -> Comparison:
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
    Comparison
        Per engine: its settings, wall time and measurements.

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
    spec = scene if isinstance(scene, PeerScene) else peer_scene(scene, until)
    asked = engines is not None
    names = list(engines) if engines is not None else default_engines(spec.dim)
    chosen: list[EngineEntry] = []
    skipped: dict[str, str] = {}
    for name in names:
        e = engine(name)
        problem = e.unable(spec.dim)
        if problem is not None:
            if asked:
                raise CaromError(problem)
            skipped[name] = problem
            continue
        chosen.append(e)
    expected = expectation(spec)
    runs = {}
    for e in chosen:
        runs[e.name] = run_engine(e, spec, expected, progress)
    return Comparison(spec, expected, runs, skipped)


def run_engine(
    e: EngineEntry, scene: PeerScene, expected: Expectation | None, progress: bool | None = False
) -> dict[str, Any]:
    """Set ``e`` up, step it to ``until`` with the monitor watching; time only the steps."""
    began = time.perf_counter()
    sim = e.start(scene)
    setup = time.perf_counter() - began
    try:
        steps = scene.steps(sim.dt)
        monitor = Monitor(scene, expected, sim.dt)
        monitor.observe(0.0, *sim.state())
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
                monitor.observe(k * sim.dt, *sim.state())
                bar.update()
    finally:
        sim.close()
    metrics = monitor.result()
    return {
        "version": e.version(),
        "dt_s": sim.dt,
        "settings": sim.settings,
        "notes": sim.notes,
        "setup_s": setup,
        "wall_s": wall,
        "simulated_s": steps * sim.dt,
        "steps": steps,
        "metrics": metrics,
        "series": monitor.series,
    }
