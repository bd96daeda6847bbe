"""One compiled handle on an engine's model and state, and the call that runs frames through it.

Numba unboxes a named tuple of arrays argument by argument on every call from Python: the
engine's model and state (about 60 arrays) cost 7 to 10 us a call, more than all the events of
a frame of a small scene. An engine handle is a Numba structure holding the two named tuples
and the body order; passing it costs one pointer (under 1 us a call). It is made once, and made
again whenever the state's arrays are replaced (the lists grow, a checkpoint is restored). It
refers to the same arrays, so what a kernel writes through it is what the driver reads.

:func:`carom.engines.edmd.loop.run_frames` takes the handle: it is the one call that runs a
stretch of frames, the events up to each frame's time in turn, and every body's state at that
time written into the caller's arrays, in the caller's numbering. A frame a call
(``World.frames``) and many frames a call (``World.record``) are the same kernel.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np
from numba import njit, types
from numba.experimental import structref
from numba.extending import overload

from carom.engines.edmd.loop import write_frame, write_motion


@structref.register
class EngineHandleType(types.StructRef):
    """The Numba type of an engine handle: fields ``model``, ``state`` and ``order``."""

    def preprocess_fields(self, fields: Any) -> Any:
        return tuple((name, types.unliteral(typ)) for name, typ in fields)  # type: ignore[no-untyped-call]


class EngineHandle(structref.StructRefProxy):
    """An engine handle seen from Python (made by :func:`new_handle`)."""


structref.define_boxing(EngineHandleType, EngineHandle)  # type: ignore[no-untyped-call]


class _PlainHandle(NamedTuple):
    """The handle under ``NUMBA_DISABLE_JIT``, where the kernels run as Python."""

    model: Any
    state: Any
    order: Any


def _make(model, state, order):  # type: ignore[no-untyped-def]
    """A handle on ``model``, ``state`` and ``order`` (compiled: an :class:`EngineHandle`)."""
    return _PlainHandle(model, state, order)


def handle_type(model: Any, state: Any, order: Any) -> EngineHandleType:
    """The Numba type of a handle on a model, state and order of these Numba types."""
    return EngineHandleType([("model", model), ("state", state), ("order", order)])  # type: ignore[no-untyped-call]


@overload(_make)
def _make_typed(model, state, order):  # type: ignore[no-untyped-def]
    typ = handle_type(model, state, order)

    def make(model, state, order):  # type: ignore[no-untyped-def]
        h = structref.new(typ)  # type: ignore[call-arg, var-annotated]
        h.model = model  # type: ignore[unreachable]
        h.state = state
        h.order = order
        return h

    return make


@njit(cache=True)
def new_handle(model, state, order):  # type: ignore[no-untyped-def]
    """The handle on an engine's ``model``, ``state`` and ``order`` (``order[i]`` is the
    caller's number of engine row ``i``)."""
    return _make(model, state, order)  # type: ignore[no-untyped-call]


@njit(cache=True, error_model="numpy")
def sample_now(h, t_out, x_out, v_out, orient_out, w_out) -> None:  # type: ignore[no-untyped-def]
    """Frame 0 of the outputs: every body at the engine's clock, events pending or not."""
    m, s = h.model, h.state
    frame = np.int64(0)  # typed, not a literal: the loop's compiled write_frame serves
    write_frame(
        s.kin, s.acc, s.orient, s.orient_t, s.w, m.box, m.periodic, h.order, s.clock[0], frame,
        t_out, x_out, v_out, orient_out, w_out,
    )  # fmt: skip


@njit(cache=True, error_model="numpy")
def sample_motion_now(h, t_out, x_out, v_out) -> None:  # type: ignore[no-untyped-def]
    """Frame 0 of ``x_out`` and ``v_out``: every body's position and velocity at the engine's
    clock, as :func:`sample_now` writes them, and no orientation or spin."""
    m, s = h.model, h.state
    frame = np.int64(0)
    write_motion(s.kin, s.acc, m.box, m.periodic, h.order, s.clock[0], frame, t_out, x_out, v_out)
