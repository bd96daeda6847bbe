"""The event loop's helpers are compiled without entry points from Python
(carom.jit.kernel_only): they run in compiled code, and a call from Python is refused with a
TypeError rather than jumping to a wrapper that was never made."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from carom.engines.edmd import calendar, collide, loop, neighbours, predict
from carom.geometry import toi
from carom.jit import KernelOnly
from carom.laws import kernels
from tests.conftest import JIT_DISABLED
from tests.engines.edmd.test_calendar import calendar_top as jitted_top
from tests.engines.edmd.test_calendar import empty_calendar
from tests.processes import fresh_python

needs_dispatchers = pytest.mark.skipif(
    JIT_DISABLED, reason="without the JIT the helpers are plain Python functions"
)


@needs_dispatchers
@pytest.mark.parametrize(
    "helper",
    [
        calendar.calendar_top,
        calendar.calendar_update,
        collide.collide_pair,
        collide.collide_face,
        neighbours.rebuild_shell,
        predict.predict,
        loop.write_frame,
        toi._first_fall,
        toi._quadratic_roots,
        kernels.impulse_spheres,
    ],
)
def test_helpers_of_the_loop_have_no_python_entry(helper: object) -> None:
    assert isinstance(helper, KernelOnly)
    with pytest.raises(TypeError, match=r"runs only inside compiled kernels.*py_func"):
        helper()  # type: ignore[operator]


@needs_dispatchers
def test_a_helper_compiles_without_wrappers_and_runs_from_compiled_code() -> None:
    keys = np.array([3.0, 1.0, 2.0])
    cal = empty_calendar(keys.size)
    calendar.calendar_build(keys, cal)
    assert jitted_top(keys, cal) == 1  # the earliest event, through a jitted caller
    with pytest.raises(TypeError, match=r"calendar\.calendar_top"):
        calendar.calendar_top(keys, cal)
    # what was compiled (or loaded from the cache) has no Python wrapper and no C wrapper:
    # neither symbol is defined in its machine code
    assert calendar.calendar_top.overloads
    for compiled in calendar.calendar_top.overloads.values():
        library, fndesc = compiled.library, compiled.fndesc
        assert library.get_pointer_to_function(fndesc.llvm_cpython_wrapper_name) == 0
        assert library.get_pointer_to_function(fndesc.llvm_cfunc_wrapper_name) == 0
        assert library.get_pointer_to_function(fndesc.mangled_name) != 0


COMPILED_FOR = """
import json, sys
from numba.core import event
compiled = set()

class Compiles(event.Listener):
    def on_start(self, e): pass
    def on_end(self, e): compiled.add(e.data["dispatcher"].py_func.__qualname__)

event.register("numba:compile", Compiles())
import carom
from tests.worlds import gas
world = gas(3, 2, 0.3, seed=1, e=0.9, boundary="walls")
if sys.argv[1:] == ["gravity and spins"]:
    world.gravity[:] = (0.0, 0.0, -1.0)
    world.add_material(carom.Material(restitution=0.9, beta=0.3))  # a rough law: spins
world.run(until=world.time + 0.01)
print(json.dumps(sorted(compiled)))
"""


@pytest.mark.slow  # (a fresh process compiles the loop twice)
@needs_dispatchers
@pytest.mark.parametrize("both", [False, True], ids=["neither", "gravity and spins"])
def test_a_scene_without_gravity_or_spins_compiles_no_parabolas_supports_or_turns(
    both: bool, tmp_path: Path
) -> None:
    # Model.gravity is None without gravity, and Model.q when no body can spin: the kernels'
    # branches on them are pruned before typing, so the quartic time of impact, the support
    # rules and the spin's contact velocity are never compiled; under gravity, with a rough
    # law, they are. From an empty cache, in a fresh process (this one has compiled both).
    code = COMPILED_FOR.replace("sys.argv[1:]", repr(["gravity and spins"] if both else []))
    compiled = set(fresh_python(code, NUMBA_CACHE_DIR=str(tmp_path)))
    assert {"predict", "collide_pair", "collide_face", "run_frames"} <= compiled
    gravity = {"first_root_quartic", "set_support", "support_reaction", "held_cosine"}
    spins = {"contact_velocity"}
    assert (gravity | spins <= compiled) if both else not ((gravity | spins) & compiled)
