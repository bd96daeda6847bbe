"""How the event loop's kernels are compiled: without reference counting, and inlined by LLVM.

**Without reference counting.** Nothing is allocated per event, so the functions the loop
calls are compiled without Numba's reference counting (:data:`carom.jit.NO_REFCOUNTING`, an
internal Numba flag; the remedy Numba's developers give in numba#2345; the rigid engines' leaf
kernels take it too, :func:`carom.jit.leaf`): each call would otherwise increment and decrement
an atomic counter per array argument, and each such locked instruction stalls the loads
around it (measured: the event loop 1.4x faster without them). The loop itself counts only
where it reads the engine's handle, once a call (:mod:`carom.engines.edmd.loop`). A kernel
that allocated would fail to compile, loudly. A function compiled so must not return an
array either (its caller, if counted, would release a reference it never took): the few
helpers that return views stay in Numba's own inliner (``inline="always"``).

**Inlined by LLVM, not by Numba.** The loop's helpers are inlined into it, because a call
that is not inlined passes every array as about nine machine words and copies any tuple whole
(measured: the event loop 10 to 20% slower). Numba's ``inline="always"`` does it on Numba's
IR, copying the callee's IR block by block with its whole scope, and types it again at every
site: it was 35 s of a 55 s cold start. ``forceinline=True`` compiles each helper once and
asks LLVM to inline it (``alwaysinline``): the same machine code, the same bits, compiled in a
fraction of the time (issue 16, item 4).

**No entry points from Python.** A helper that only runs inlined into the loop needs no
wrapper for calls from Python or C: the helpers are compiled without them
(:func:`carom.jit.kernel_only`), and a call from Python is refused with a ``TypeError``.
"""

from __future__ import annotations

from carom.jit import NO_REFCOUNTING, kernel_only

#: a function the event loop calls, not inlined: compiled once, cached, without reference
#: counting, with no entry point from Python (:func:`carom.jit.kernel_only`)
njit_without_refcounting = kernel_only(error_model="numpy", **NO_REFCOUNTING)

#: a helper of the event loop: as :data:`njit_without_refcounting`, inlined by LLVM into every
#: caller, and with no entry point from Python (:func:`carom.jit.kernel_only`)
njit_inlined = kernel_only(error_model="numpy", forceinline=True, **NO_REFCOUNTING)
