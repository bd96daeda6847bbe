"""Timing time-stepped engines against each other honestly: bare steps, interleaved rounds.

What the rigid benchmarks (rigid2d.py, rigid3d.py) share:

* :func:`bare_ms` times an engine of ``carom compare`` stepping a scene with nothing else
  between its steps: no monitor reads the state (a monitor between timed steps measurably
  slowed some peers' next step, x1.05-1.30 for Rapier, issue 46), only the step calls are
  inside the timed window;
* :class:`Box2DV3` builds Box2D v3 (C) from a source tree in its default (SSE2) build and, on a
  processor that has it, its ``BOX2D_AVX2=ON`` build, and runs carom's harness
  (benchmarks/box2d_v3/pyramid.c) on Box2D's benchmark pyramids with 1 or more workers;
* :func:`interleave` runs every engine once a round, the order rotating round by round, with
  a garbage collection and a pause before each run so that nothing of carom's runs inside or
  just before a peer's timed window;
* :func:`monitored` runs the engines once more under ``carom compare``'s monitor, for the
  accuracy columns;
* :func:`ratios` gives carom / peer round by round, and :func:`spread` their median and
  spread (least, greatest).
"""

from __future__ import annotations

import gc
import os
import shutil
import statistics
import subprocess
import sys
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

from carom.compare import compare, peer_scene
from carom.compare.engines import ENGINES
from carom.compare.report import format_table

HARNESSES = Path(__file__).resolve().parent / "box2d_v3"
#: a pause before each timed run [s], so that one engine's tail does not fall in the next's
SETTLE_S = 0.3


def one_core() -> int:
    """Pin this process (and the processes it starts) to one core; return which."""
    core = min(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {core})
    return core


def bare_ms(name: str, scene: Any) -> float:
    """ms per step of engine ``name`` stepping ``scene`` to its end, only its step calls
    timed and nothing run between them."""
    sim = ENGINES[name].start(scene)
    try:
        steps = scene.steps(sim.dt)
        step = sim.step
        wall = 0.0
        clock = time.perf_counter
        for _ in range(steps):
            began = clock()
            step()
            wall += clock() - began
        return 1e3 * wall / steps
    finally:
        sim.close()


def has_avx2() -> bool:
    """Whether this processor has AVX2 (Linux: /proc/cpuinfo)."""
    try:
        return " avx2" in Path("/proc/cpuinfo").read_text()
    except OSError:
        return False


class Box2DV3:
    """Box2D v3 built from ``source`` into ``build``: its default build (``"sse2"``) and, if
    the processor has AVX2, its ``BOX2D_AVX2=ON`` build (``"avx2"``), both Release, each
    linked to carom's harness ``benchmarks/box2d_v3/<harness>.c``."""

    def __init__(self, source: Path, build: Path, harness: str = "pyramid") -> None:
        if shutil.which("cmake") is None or shutil.which("cc") is None:
            sys.exit("--box2d-v3 needs cmake and a C compiler")
        self.source = source.expanduser()
        self.builds = ["sse2", "avx2"] if has_avx2() else ["sse2"]
        self.programs = {b: self._build(b, build / b, harness) for b in self.builds}
        head = subprocess.run(
            ["git", "-C", str(self.source), "log", "-1", "--format=%h %cs"],
            capture_output=True,
            text=True,
        )
        self.version = head.stdout.strip() or "unknown commit"

    def _build(self, kind: str, build: Path, harness: str) -> Path:
        quiet = {"check": True, "stdout": subprocess.DEVNULL}
        subprocess.run(
            ["cmake", "-S", str(self.source), "-B", str(build), "-DCMAKE_BUILD_TYPE=Release",
             "-DBOX2D_SAMPLES=OFF", "-DBOX2D_UNIT_TESTS=OFF", "-DBOX2D_BENCHMARKS=ON",
             f"-DBOX2D_AVX2={'ON' if kind == 'avx2' else 'OFF'}"],
            **quiet,
        )  # fmt: skip
        subprocess.run(
            ["cmake", "--build", str(build), "-j2", "--target", "box2d", "shared"], **quiet
        )
        program = build / harness
        subprocess.run(
            ["cc", "-O2", "-std=c17", "-I", str(self.source / "include"),
             "-I", str(self.source / "shared"), str(HARNESSES / f"{harness}.c"),
             str(next(build.rglob("libshared.a"))), str(next(build.rglob("libbox2d.a"))),
             "-lm", "-lpthread", "-o", str(program)],
            check=True,
        )  # fmt: skip
        return program

    def run(self, kind: str, *args: str) -> dict[str, float]:
        """Run the ``kind`` build's harness with ``args``; its last line's ``name value``
        pairs."""
        out = subprocess.run(
            [str(self.programs[kind]), *args], check=True, capture_output=True, text=True
        )
        words = out.stdout.splitlines()[-1].split()
        return {k: float(v) for k, v in zip(words[::2], words[1::2], strict=True)}

    def trace(self, kind: str, *args: str) -> list[list[float]]:
        """The harness's per-step lines (``trace`` mode) as rows of numbers."""
        out = subprocess.run(
            [str(self.programs[kind]), *args, "trace"], check=True, capture_output=True, text=True
        )
        return [[float(w) for w in line.split()] for line in out.stdout.splitlines()[:-1]]


def interleave(runs: dict[str, Callable[[], float]], rounds: int) -> dict[str, list[float]]:
    """Each of ``runs`` (name: a timed run returning ms per step) once a round for ``rounds``
    rounds, round k starting at the k-th name (so each runs first, last and between the
    others in turn); the ms per step of each, round by round."""
    names = list(runs)
    times: dict[str, list[float]] = {name: [] for name in names}
    for k in range(rounds):
        order = names[k % len(names) :] + names[: k % len(names)]
        for name in order:
            gc.collect()
            time.sleep(SETTLE_S)
            times[name].append(runs[name]())
        line = ", ".join(f"{n} {times[n][-1]:.3g}" for n in names)
        print(f"round {k + 1}/{rounds}: ms per step: {line}", flush=True)
    return times


def ratios(times: dict[str, list[float]], ours: str = "carom") -> dict[str, list[float]]:
    """For each engine of ``times``: carom's ms / its ms, round by round (carom's own: 1)."""
    return {
        name: [a / b for a, b in zip(times[ours], each, strict=True)]
        for name, each in times.items()
    }


def spread(values: list[float]) -> str:
    """``median (least-greatest)`` to 3 figures."""
    return f"{statistics.median(values):.3g} ({min(values):.3g}-{max(values):.3g})"


def monitored(
    name: str, engines: list[str], until: float | None, fields: list[str]
) -> tuple[list[str], dict[str, dict[str, Any]]]:
    """One run of ``engines`` on scene ``name`` under ``carom compare``'s monitor (untimed
    here): a table row per engine (scene, engine and version, then the metrics ``fields``) and
    the runs."""
    result = compare(peer_scene(name, until), engines)
    print(format_table(result) + "\n", flush=True)
    rows = []
    for engine, run in result.engines.items():
        values = " | ".join(
            f"{v:.3g}" if isinstance(v, float) else str(v)
            for v in (run["metrics"][f] for f in fields)
        )
        rows.append(f"| {name} | {engine} {run['version']} | {values} |")
    return rows, result.engines
