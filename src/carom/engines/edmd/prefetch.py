"""Software prefetch of one row of a 2-D array, or one element of a 1-D array (LLVM
``llvm.prefetch``).

The event loop reads, for each neighbour of a body, one record in an order no hardware
prefetcher can guess; at large N each is a trip to main memory. Asking for all of them
before using any lets the misses overlap. A no-op in plain Python (``NUMBA_DISABLE_JIT=1``).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, cast

import llvmlite.ir as llvm_ir  # type: ignore[import-untyped]
from numba import config, types
from numba.core import cgutils
from numba.extending import intrinsic


def _prefetch_element(context: Any, builder: Any, signature: Any, args: Any) -> Any:
    """The code of a prefetch of ``args[0][args[1:]]``, missing trailing indices 0."""
    array_type, *index_types = signature.args
    ary = context.make_array(array_type)(context, builder, args[0])
    indices = [
        context.cast(builder, value, kind, types.intp)
        for value, kind in zip(args[1:], index_types, strict=True)
    ]
    indices += [context.get_constant(types.intp, 0)] * (array_type.ndim - len(indices))
    ptr = cgutils.get_item_pointer(  # type: ignore[no-untyped-call]
        context, builder, array_type, ary, indices, wraparound=False
    )
    i8p = llvm_ir.IntType(8).as_pointer()
    i32 = llvm_ir.IntType(32)
    fnty = llvm_ir.FunctionType(llvm_ir.VoidType(), [i8p, i32, i32, i32])
    fn = cgutils.get_or_insert_function(  # type: ignore[no-untyped-call]
        builder.module, fnty, "llvm.prefetch.p0"
    )
    # a read (0), to be kept in every cache level (3), of data (1)
    builder.call(fn, [builder.bitcast(ptr, i8p), i32(0), i32(3), i32(1)])
    return context.get_dummy_value()


@intrinsic
def _prefetch_row(typingctx: Any, array: Any, row: Any) -> Any:
    if not isinstance(array, types.Array) or array.ndim not in (1, 2):
        return None
    return types.void(array, row), _prefetch_element


@intrinsic
def _prefetch_item(typingctx: Any, array: Any, row: Any, column: Any) -> Any:
    if not isinstance(array, types.Array) or array.ndim != 2:
        return None
    return types.void(array, row, column), _prefetch_element


def _no_prefetch(array: Any, row: int) -> None:
    """Nothing to do without the JIT."""


def _no_prefetch_item(array: Any, row: int, column: int) -> None:
    """Nothing to do without the JIT."""


prefetch_row: Callable[[Any, int], None] = (
    _no_prefetch
    if config.DISABLE_JIT  # type: ignore[attr-defined]
    else cast(Callable[[Any, int], None], _prefetch_row)
)
#: ``prefetch_item(array, row, column)``: the cache line of one element of a 2-D array (the
#: rest of a row longer than a line, as neighbour lists are)
prefetch_item: Callable[[Any, int, int], None] = (
    _no_prefetch_item
    if config.DISABLE_JIT  # type: ignore[attr-defined]
    else cast(Callable[[Any, int, int], None], _prefetch_item)
)
