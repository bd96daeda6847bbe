"""A cold start compiles on two cores: the engine's build kernels in a helper process, the event
loop here.

Compiling is one thread's work in a process (Numba holds a lock), and a cold start has two
independent halves of about the same size: the kernels that build an engine (``initialise``,
the neighbour lists, the calendar, the handle, sampling) and the event loop
(:func:`carom.engines.edmd.loop.run_frames`). When the kernel cache is cold, a fresh engine
starts :func:`start`: a second Python process (``python -m carom.engines.edmd.helper``) builds a
two-sphere engine of the same kind (with gravity or without, spinning or not: the kernels
differ) and samples it, which compiles the first half into the shared cache, while this
process compiles the loop for its own model and state (:func:`compile_beside`). It then waits
for the helper and loads the first half from the cache. Machine code is the same whichever
process compiled it: the cache only moves it.

Nothing depends on the helper: if it cannot start, fails or outlives :data:`WAIT_SECONDS`, this
process compiles what is missing itself. It is not started on one CPU, without the JIT, when
the loop is compiled already (in this process or the cache), or from a helper.
"""

from __future__ import annotations

import os
import subprocess
import sys
from collections.abc import Callable
from typing import Any, cast

import numpy as np
from numba import config, types
from numba import typeof as _typeof

from carom.bodies import Bodies
from carom.engines.base import FrameArrays
from carom.engines.edmd import loop
from carom.engines.edmd.handle import handle_type
from carom.engines.edmd.model import Environment, Model
from carom.engines.edmd.state import State
from carom.jit import kernels_cached, usable_cpus
from carom.materials import pair_table

typeof = cast(Callable[[Any], Any], _typeof)

#: set in the helper's environment, so that its own engine starts no helper
HELPER_FLAG = "CAROM_COMPILE_HELPER"
#: how long a fresh engine waits for the helper before compiling the rest itself [s]
WAIT_SECONDS = 600.0


def start(gravity: bool, spins: bool) -> subprocess.Popen[bytes] | None:
    """Start the helper process if the kernel cache is cold and a second CPU can run it; its
    engine has ``gravity`` and ``spins`` when the caller's has (:func:`two_spheres`)."""
    if config.DISABLE_JIT or os.environ.get(HELPER_FLAG) or loop_ready():  # type: ignore[attr-defined]
        return None
    if usable_cpus() < 2:
        return None
    try:
        flags = [flag for flag, on in (("--gravity", gravity), ("--spins", spins)) if on]
        return subprocess.Popen(
            [sys.executable, "-m", "carom.engines.edmd.helper", *flags],
            stdin=subprocess.DEVNULL,
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
            env={**os.environ, HELPER_FLAG: "1"},
        )
    except OSError:
        return None


def loop_ready() -> bool:
    """Whether the event loop is compiled already: in this process (then the disk is not
    asked again), or in the kernel cache."""
    return bool(getattr(loop.run_frames, "overloads", None)) or kernels_cached()


def finish(helper: subprocess.Popen[bytes]) -> None:
    """Wait for the helper (at most :data:`WAIT_SECONDS`; then it is stopped): whatever it
    compiled is in the cache, and whatever it did not, the caller compiles."""
    try:
        helper.wait(timeout=WAIT_SECONDS)
    except subprocess.TimeoutExpired:
        helper.kill()
        helper.wait()


def loop_signature(model: Model, state: State, order: np.ndarray) -> tuple[Any, ...]:
    """The argument types of :func:`carom.engines.edmd.loop.run_frames` as the engine calls
    it (``EdmdEngine._drive``): the handle, the frame times, the event budget, the log and
    sample switches, the frame counter and the five frame arrays."""
    frames = FrameArrays.empty(1, 1, 3)
    return (
        handle_type(typeof(model), typeof(state), typeof(order)),
        typeof(np.zeros(1)),
        types.int64,
        types.boolean,
        types.boolean,
        typeof(np.zeros(1, np.int64)),
        *(typeof(a) for a in frames),
    )


def compile_beside(
    helper: subprocess.Popen[bytes] | None, model: Model, state: State, order: np.ndarray
) -> None:
    """With a ``helper`` running (:func:`start`), compile (or load) the event loop for this
    model and state here, then wait for the helper (:func:`finish`); if compiling fails or is
    interrupted, stop the helper before passing the error on. Without one, nothing."""
    if helper is None:
        return
    try:
        signature = loop_signature(model, state, order)
        loop.run_frames.compile(signature)
    except BaseException:
        helper.kill()
        helper.wait()
        raise
    finish(helper)


def two_spheres(gravity: bool = False, spins: bool = False) -> tuple[Bodies, Environment]:
    """The helper's engine inputs: two spheres in a walled 3D box, under gravity or not, one
    spinning or neither. Every scene the event-driven engine runs has the kernel argument
    types of one of the four (the tests hold this): a model without gravity has none
    (``Model.gravity`` is None), and its kernels are compiled without the code for parabolas
    and supports; one whose bodies never spin has no inertia factors (``Model.q`` is None),
    and its kernels are compiled without the code that turns them."""

    bodies = Bodies(3)
    bodies.append_spheres(
        np.array([[0.3, 0.5, 0.5], [0.7, 0.5, 0.5]]),
        np.array([[1.0, 0.0, 0.0], [-1.0, 0.0, 0.0]]),
        np.array([[0.0, 0.0, 1.0 if spins else 0.0], [0.0, 0.0, 0.0]]),
        np.full(2, 0.1),
        np.ones(2),
        0.4,
        0,
    )
    env = Environment(
        box=np.ones(3),
        periodic=False,
        gravity=np.array([0.0, 0.0, -9.81]) if gravity else np.zeros(3),
        pairs=pair_table([], "mean"),
        face_e=np.ones(6),
        plane_point=np.zeros((0, 3)),
        plane_normal=np.zeros((0, 3)),
    )
    return bodies, env
