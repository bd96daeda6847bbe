"""A cold start compiles on two cores (carom.engines.edmd.aside): the helper's two-sphere engine
has the kernel argument types of every kind of scene, so what it compiles is what a scene
loads; the loop compiled ahead has the signature the engine calls it with; and from a cold
cache the helper's kernels are loaded, not compiled again, with the same bits."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from numba import typeof

import carom
from carom.engines.edmd import aside, loop
from carom.engines.edmd.driver import EdmdEngine
from carom.engines.edmd.settings import EdmdSettings
from carom.scene import find_scene, load_scene
from tests.worlds import gas


def _kinds() -> dict[str, carom.World]:
    """One world of each kind the event-driven engine runs."""
    planes = load_scene(find_scene("galton-board"))  # gravity, static spheres, planes
    rough = carom.World(dim=3, box=(1.0, 1.0, 1.0))
    steel = rough.add_material(carom.Material(restitution=0.8, beta=0.5))
    rough.add_spheres([[0.3, 0.5, 0.5], [0.7, 0.5, 0.5]], radius=0.1, material=steel)
    rough_falling = carom.World(dim=2, box=(1.0, 1.0), gravity=(0.0, -9.81))
    steel = rough_falling.add_material(carom.Material(restitution=0.8, beta=0.5))
    rough_falling.add_spheres([[0.3, 0.5], [0.7, 0.5]], radius=0.1, material=steel)
    spinning = gas(3, 4, 0.3, seed=1)  # smooth, but one sphere spins
    spinning.add_spheres([[0.0, 0.0, 0.0]], angular_velocities=[[0.0, 0.0, 2.0]], radius=0.01)
    return {
        "3D periodic gas": gas(3, 4, 0.3, seed=1),
        "2D walled gas": gas(2, 6, 0.4, seed=1, boundary="walls"),
        "gravity and planes": planes.build(),
        "rough spheres": rough,
        "rough spheres falling": rough_falling,
        "a smooth gas with one spin": spinning,
    }


def _kind(world: carom.World) -> tuple[bool, bool]:
    """(gravity, spins) of a world: whether gravity acts, and whether a body may spin."""
    rough = any(m.law != "smooth" for m in world.materials)
    spins = rough or bool(np.any(world.angular_velocities != 0.0))
    return bool(np.any(world.gravity != 0.0)), spins


def _types(engine: EdmdEngine) -> tuple[object, ...]:
    return (typeof(engine.model), typeof(engine.state), *aside.loop_signature(
        engine.model, engine.state, engine.order
    ))  # fmt: skip


@pytest.mark.needs_jit
def test_every_kind_of_scene_has_the_helpers_kernel_types() -> None:
    # four helpers, with gravity and without, spinning and not: a model without gravity types
    # it as None, so that its kernels are compiled without parabolas and supports, and one
    # whose bodies never spin its inertia factors; within each kind, one set of types
    kinds = [(gravity, spins) for gravity in (False, True) for spins in (False, True)]
    helpers = {
        kind: _types(EdmdEngine(*aside.two_spheres(*kind), EdmdSettings(), 0.0)) for kind in kinds
    }
    assert len(set(helpers.values())) == 4
    seen = set()
    for name, world in _kinds().items():
        engine = world.build()
        assert isinstance(engine, EdmdEngine), name
        kind = _kind(world)
        assert (engine.model.gravity is not None, engine.model.q is not None) == kind, name
        assert _types(engine) == helpers[kind], name
        seen.add(kind)
    assert seen == set(kinds)


@pytest.mark.needs_jit
def test_the_loop_compiled_ahead_is_the_one_the_engine_calls() -> None:
    world = gas(3, 4, 0.3, seed=1)
    world.run(until=world.time + 0.1)
    engine = world.build()
    assert isinstance(engine, EdmdEngine)
    signature = aside.loop_signature(engine.model, engine.state, engine.order)
    assert signature in loop.run_frames.overloads


def test_no_helper_when_the_loop_is_compiled_or_from_a_helper(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(aside, "loop_ready", lambda: True)
    assert aside.start(False, False) is None
    monkeypatch.setattr(aside, "loop_ready", lambda: False)
    monkeypatch.setenv(aside.HELPER_FLAG, "1")
    assert aside.start(False, False) is None


@pytest.mark.needs_jit
def test_a_loop_loaded_in_this_process_is_ready_whatever_the_disk_says(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # (an unwritable cache would otherwise start a helper at every engine build)
    gas(2, 4, 0.4, seed=1).run(until=0.1)
    monkeypatch.setattr(aside, "kernels_cached", lambda: False)
    assert aside.loop_ready()


def test_cpus_are_counted_where_the_system_has_no_affinity(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # macOS and Windows have no os.sched_getaffinity: every CPU counts there
    monkeypatch.delattr(os, "sched_getaffinity", raising=False)
    monkeypatch.setattr(os, "cpu_count", lambda: 3)
    assert aside.usable_cpus() == 3
    monkeypatch.setattr(os, "cpu_count", lambda: None)
    assert aside.usable_cpus() == 1


def test_no_helper_on_one_cpu(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    monkeypatch.setattr(aside, "loop_ready", lambda: False)
    monkeypatch.delenv(aside.HELPER_FLAG, raising=False)
    monkeypatch.setattr(aside, "usable_cpus", lambda: 1)
    assert aside.start(False, False) is None


def test_a_failed_compile_stops_the_helper(monkeypatch) -> None:  # type: ignore[no-untyped-def]
    # an error (or Ctrl-C) while the loop compiles leaves no helper process behind
    helper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])

    def broken(*args: object) -> None:
        raise RuntimeError("compiling failed")

    monkeypatch.setattr(aside, "loop_signature", broken)
    with pytest.raises(RuntimeError, match="compiling failed"):
        aside.compile_beside(helper, None, None, None)  # type: ignore[arg-type]
    assert helper.poll() is not None  # stopped and waited for


COLD_RUN = """
import json, sys
import numpy as np
from carom.engines.edmd import loop
from tests.worlds import gas
world = gas(3, 4, 0.3, seed=1, e=0.9)
world.run(until=2.0)
print(json.dumps({
    "positions": world.positions.tolist(),
    "velocities": world.velocities.tolist(),
    "initialise_loaded": sum(loop.initialise.stats.cache_hits.values()),
    "initialise_compiled": sum(loop.initialise.stats.cache_misses.values()),
    "loop_compiled": sum(loop.run_frames.stats.cache_misses.values()),
}))
"""


@pytest.mark.slow  # (two fresh processes compile from a cold cache)
@pytest.mark.needs_jit
@pytest.mark.skipif(aside.usable_cpus() < 2, reason="the helper needs a second CPU")
def test_a_cold_start_loads_what_the_helper_compiled_with_the_same_bits(tmp_path: Path) -> None:
    root = Path(__file__).resolve().parents[3]
    done = subprocess.run(
        [sys.executable, "-c", COLD_RUN],
        capture_output=True,
        text=True,
        cwd=root,
        env={**os.environ, "NUMBA_CACHE_DIR": str(tmp_path), "PYTHONPATH": str(root / "src")},
        stdin=subprocess.DEVNULL,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    cold = json.loads(done.stdout)
    # the helper compiled the build kernels into the (empty) cache; this process loaded them
    # and compiled the loop
    assert cold["initialise_loaded"] == 1
    assert cold["initialise_compiled"] == 0
    assert cold["loop_compiled"] == 1
    warm = gas(3, 4, 0.3, seed=1, e=0.9)
    warm.run(until=2.0)
    np.testing.assert_array_equal(np.array(cold["positions"]), warm.positions)
    np.testing.assert_array_equal(np.array(cold["velocities"]), warm.velocities)
