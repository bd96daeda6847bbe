"""Branch hints for the event loop (LLVM ``llvm.expect``).

``if unlikely(c):`` tells LLVM that ``c`` is almost always false, so it lays the branch's code
out of line and gives the other path the registers. The event loop's rough-and-frictional
branch (spins, orientations: trigonometry and a quaternion product) is taken in no collision
of a smooth gas, yet inlined it adds about 300 instructions to the loop's machine code
(``inspect_asm``). Whether the hint changes the loop's speed could not be measured on the
noisy machine it was written on (benchmarks/RESULTS.md, 2026-11-23). The identity in plain
Python (``NUMBA_DISABLE_JIT=1``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, cast

import llvmlite.ir as llvm_ir  # type: ignore[import-untyped]
from numba import config, types
from numba.core import cgutils
from numba.extending import intrinsic


@intrinsic
def _unlikely(typingctx: Any, condition: Any) -> Any:
    if not isinstance(condition, types.Boolean):
        return None

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        i1 = llvm_ir.IntType(1)
        fnty = llvm_ir.FunctionType(i1, [i1, i1])
        fn = cgutils.get_or_insert_function(  # type: ignore[no-untyped-call]
            builder.module, fnty, "llvm.expect.i1"
        )
        return builder.call(fn, [args[0], i1(0)])

    return types.boolean(condition), codegen


def _identity(condition: bool) -> bool:
    """Nothing to hint without the JIT."""
    return condition


unlikely: Callable[[bool], bool] = (
    _identity
    if config.DISABLE_JIT  # type: ignore[attr-defined]
    else cast(Callable[[bool], bool], _unlikely)
)
