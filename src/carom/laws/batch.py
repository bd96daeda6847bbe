"""The two-sphere laws of :func:`carom.collide` as one Numba pass over a batch.

:func:`collide_rows` reads each pair's inputs once, checks them, applies the law and writes
every field of the :class:`~carom.laws.spheres.CollisionResult` in the same pass: no NumPy
temporaries, so a batch costs about what its inputs and outputs take to move through memory.
The arithmetic is that of the NumPy laws it replaced (commit d294db6) operation for operation
(same order, no fused multiply-adds): every field agreed to the bit when it replaced them.
Tests hold a pair alone to the same pair in a batch, on any number of threads.

Inputs are C-contiguous float64 arrays whose first axis has length ``n`` or 1; a length of 1
is broadcast (row stride 0). Vectors are ``(k, d)``, per-pair scalars ``(k,)``, spins
``(k, 1)`` in 2D and ``(k, 3)`` in 3D.

The check is deliberately the simple one: a pair is flagged when any input lies outside the
range :func:`carom.collide` accepts, when both masses are infinite, or when the centres
coincide. The caller then runs the full argument checks, which name what is wrong and where.

**Pairs side by side in vector instructions.** The pairs go through in blocks of
:data:`LANES`, in three loops: the block's inputs are copied into a scratch block on the
thread's stack, one row per component (broadcast inputs read with stride 0, absent ones as
zeros); the law runs over the block, row by row; the results are copied out. The middle
loop reads and writes only the two scratch blocks, which LLVM knows to overlap nothing, so it
vectorises it (the vector square roots and divisions are IEEE-exact like the scalar ones, and
nothing is reordered or fused: the same bits). Run over the caller's arrays, whose overlaps
only a check at run time could rule out, the same loop stayed scalar: LLVM gives up past a
few such checks, and there are about twenty arrays. The middle loop is written once
(:func:`law_block`) and inlined by LLVM. A batch of :data:`CASE_PAIRS` pairs or more runs
in a pass compiled for its case alone (2D or 3D; smooth without spins, smooth with, rough,
Walton's: :func:`case_of`), where the copy carries no branch on them; smaller batches run in
one pass for any case (case 0), which branches on each pair, so that single pairs and small
batches never compile more than it.
Measured at 10^6 pairs, two threads, with ``out=``: 1.15x (3D smooth) to 1.85x (2D Walton) the
pass before blocks, in the same run (benchmarks/RESULTS.md).

**Results past the caches.** A pair's results are 113 (2D smooth) to 201 bytes (3D Walton), and a
plain store first reads the line it writes into the cache: at 10^6 pairs the pass moved about 1.5
times the bytes it had to. When a batch's results are written over (``out=``) and reach
:data:`STREAM_BYTES` (:func:`streams`), a case's own pass writes them array by array in streaming
stores of two values (``movntpd``, :func:`stream_pair`), which write whole lines without reading
them, and ends each task with a fence (``sfence``) so that every store is seen before the threads
join. The same values are stored: the bits do not change. A fresh result is stored plainly: its new
pages are zeroed by the system as the pass first touches them, so they are in the cache then
(streamed, a fresh result on one thread ran at 0.86-0.91x). 3D Walton at 10^6 pairs with ``out=``
went from 4.3-4.4e7 to 5.5-5.7e7 pairs per second on two cores (benchmarks/RESULTS.md).
"""

from __future__ import annotations

import math
import platform
from collections.abc import Callable
from typing import Any, cast

import llvmlite.ir as llvm_ir  # type: ignore[import-untyped]
import numpy as np
from numba import config, njit, prange, types
from numba.core import cgutils
from numba.extending import intrinsic

from carom.jit import kernel_cache, kernel_only
from carom.laws.kernels import LAW_ROUGH, LAW_SMOOTH, LAW_WALTON

# carom.limits' bounds, repeated here because a kernel's constants must live in the kernel
# packages (their hash names the cache); a test holds the two equal
LARGEST = 1e100  # beyond it, products of three overflow
SMALLEST = 1e-100  # below it, a positive size underflows

BLOCK = 4096  # pairs per task of the threads
LANES = 32  # pairs per scratch block: 25 + 27 rows of 256 bytes, 13 kB, in the L1 cache

# rows of the scratch block of inputs: x1, x2, v1, v2, w1, w2 three each (2D: z zero, spin
# in the first), then masses, restitution, radii, beta (or beta0) and friction
IN_X1, IN_X2, IN_V1, IN_V2, IN_W1, IN_W2 = 0, 3, 6, 9, 12, 15
IN_M1, IN_M2, IN_E, IN_R1, IN_R2, IN_BETA, IN_FRICTION = 18, 19, 20, 21, 22, 23, 24
IN_ROWS = 25
# rows of the scratch block of results, in the order of CollisionResult's fields; applied
# and refused as 1.0 or 0.0
OUT_V1, OUT_V2, OUT_J, OUT_N, OUT_W1, OUT_W2 = 0, 3, 6, 9, 12, 15
OUT_APPROACH, OUT_SEPARATION, OUT_RELATIVE, OUT_KE_BEFORE, OUT_KE_AFTER = 18, 19, 20, 21, 22
OUT_KE_LOST, OUT_BETA, OUT_APPLIED, OUT_REFUSED = 23, 24, 25, 26
OUT_ROWS = 27


@intrinsic
def _stack_block(typingctx: Any, rows: Any, cols: Any) -> Any:
    """A (rows, cols) float64 C array on the calling function's stack, uninitialised; rows
    and cols literal. Its memory is allocated once per call of that function (in its entry
    block), so a call inside a loop reuses it; the array must not outlive the function."""
    if not isinstance(rows, types.IntegerLiteral) or not isinstance(cols, types.IntegerLiteral):
        return None
    n_rows, n_cols = rows.literal_value, cols.literal_value
    array_type = types.Array(types.float64, 2, "C")

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        def intp(value: int) -> Any:
            return context.get_constant(types.intp, value)

        data = cgutils.alloca_once(  # type: ignore[no-untyped-call]
            builder, llvm_ir.DoubleType(), size=intp(n_rows * n_cols)
        )
        array = context.make_array(array_type)(context, builder)
        context.populate_array(
            array,
            data=data,
            shape=cgutils.pack_array(builder, [intp(n_rows), intp(n_cols)]),  # type: ignore[no-untyped-call]
            strides=cgutils.pack_array(builder, [intp(8 * n_cols), intp(8)]),  # type: ignore[no-untyped-call]
            itemsize=intp(8),
            meminfo=None,
        )
        return array._getvalue()

    return array_type(rows, cols), codegen


#: x86-64 has streaming stores (``movntpd``) and the fence that orders them (``sfence``); on
#: other machines :func:`stream_pair` is a plain store and :func:`stream_fence` does nothing
STREAMING = platform.machine().lower() in ("x86_64", "amd64")


def _flat_float64(array: Any, flat: Any) -> bool:
    """Whether an intrinsic's first two arguments are a C-contiguous float64 array and an
    integer (a flat index into it)."""
    return (
        isinstance(array, types.Array)
        and array.dtype == types.float64
        and array.layout == "C"
        and isinstance(flat, types.Integer)
    )


def _element(context: Any, builder: Any, signature: Any, args: Any) -> Any:
    """The address of the element at the flat index ``args[1]`` of the array ``args[0]``."""
    data = context.make_array(signature.args[0])(context, builder, args[0]).data
    index = context.cast(builder, args[1], signature.args[1], types.intp)
    return builder.gep(data, [index])


@intrinsic
def _stream_pair(typingctx: Any, array: Any, flat: Any, a: Any, b: Any) -> Any:
    """Store ``a, b`` at the flat indices ``flat, flat + 1`` of a C-contiguous float64
    ``array``, past the caches (a streaming store: no read of the line it writes). The
    address of ``flat`` must be a multiple of 16 bytes."""
    if not _flat_float64(array, flat):
        return None

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        pair_type = llvm_ir.VectorType(llvm_ir.DoubleType(), 2)
        pair = llvm_ir.Constant(pair_type, None)
        for lane, value in enumerate(args[2:]):
            pair = builder.insert_element(pair, value, llvm_ir.Constant(llvm_ir.IntType(32), lane))
        address = builder.bitcast(
            _element(context, builder, signature, args), pair_type.as_pointer()
        )
        store = builder.store(pair, address, align=16)
        if STREAMING:
            one = llvm_ir.Constant(llvm_ir.IntType(32), 1)
            store.set_metadata("nontemporal", builder.module.add_metadata([one]))
        return context.get_dummy_value()

    return types.void(array, flat, types.float64, types.float64), codegen


@intrinsic
def _stream_fence(typingctx: Any) -> Any:
    """Order the streaming stores made so far before every later store (``sfence``)."""

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        if STREAMING:
            fence_type = llvm_ir.FunctionType(llvm_ir.VoidType(), [])
            fence = cgutils.get_or_insert_function(  # type: ignore[no-untyped-call]
                builder.module, fence_type, "llvm.x86.sse.sfence"
            )
            builder.call(fence, [])
        return context.get_dummy_value()

    return types.void(), codegen


@intrinsic
def _put_flat(typingctx: Any, array: Any, flat: Any, value: Any) -> Any:
    """Store ``value`` at the flat index ``flat`` of a C-contiguous float64 ``array``."""
    if not _flat_float64(array, flat):
        return None

    def codegen(context: Any, builder: Any, signature: Any, args: Any) -> Any:
        builder.store(args[2], _element(context, builder, signature, args))
        return context.get_dummy_value()

    return types.void(array, flat, types.float64), codegen


def _heap_stream_pair(array: np.ndarray, flat: int, a: float, b: float) -> None:
    """Without the JIT: two plain stores."""
    array.reshape(-1)[flat : flat + 2] = a, b


def _heap_put_flat(array: np.ndarray, flat: int, value: float) -> None:
    """Without the JIT: a plain store."""
    array.reshape(-1)[flat] = value


def _no_fence() -> None:
    """Without the JIT: nothing to order."""


_jit = not config.DISABLE_JIT  # type: ignore[attr-defined]
stream_pair: Callable[[np.ndarray, int, float, float], None] = (
    cast(Callable[[np.ndarray, int, float, float], None], _stream_pair)
    if _jit
    else _heap_stream_pair
)
put_flat: Callable[[np.ndarray, int, float], None] = (
    cast(Callable[[np.ndarray, int, float], None], _put_flat) if _jit else _heap_put_flat
)
stream_fence: Callable[[], None] = cast(Callable[[], None], _stream_fence) if _jit else _no_fence


def _heap_block(rows: int, cols: int) -> np.ndarray:
    """Without the JIT: the same block, on the heap."""
    return np.empty((rows, cols))


#: a scratch block: on the stack when compiled, on the heap without the JIT
stack_block: Callable[[int, int], np.ndarray] = (
    _heap_block
    if config.DISABLE_JIT  # type: ignore[attr-defined]
    else cast(Callable[[int, int], np.ndarray], _stack_block)
)


@kernel_only(error_model="numpy", forceinline=True)
def _dot(a0: float, a1: float, a2: float, b0: float, b1: float, b2: float, d3: bool) -> float:
    """``a . b`` summed in the order of :func:`carom._inputs.dot`."""
    s = a0 * b0 + a1 * b1
    if d3:
        s = s + a2 * b2
    return s


@kernel_only(error_model="numpy", forceinline=True)
def _kinetic(
    m: float,
    v0: float,
    v1: float,
    v2: float,
    w0: float,
    w1: float,
    w2: float,
    radius: float,
    q: float,
    d3: bool,
    spins: bool,
) -> float:
    """``1/2 m |v|^2 (+ 1/2 q m a^2 |w|^2)`` in the order of ``spheres.kinetic_energy``."""
    m_f = m if math.isfinite(m) else 0.0
    ke = 0.5 * m_f * _dot(v0, v1, v2, v0, v1, v2, d3)
    if spins:
        w_squared = _dot(w0, w1, w2, w0, w1, w2, True) if d3 else w0 * w0
        ke = ke + 0.5 * q * m_f * radius * radius * w_squared
    return ke


@kernel_only(error_model="numpy", forceinline=True)
def _spin_cross(
    s: float, w0: float, w1: float, w2: float, n0: float, n1: float, n2: float, d3: bool
) -> tuple[float, float, float]:
    """``(s w) x n``: in 2D ``w0`` is the spin about z and the result lies in the plane."""
    if d3:
        a0, a1, a2 = s * w0, s * w1, s * w2
        return a1 * n2 - a2 * n1, a2 * n0 - a0 * n2, a0 * n1 - a1 * n0
    a = s * w0
    return -a * n1, a * n0, 0.0


@kernel_only(error_model="numpy", forceinline=True)
def _out(x: float, low: float, high: float) -> bool:
    """True unless ``low <= x <= high`` (NaN is out of every range); no branch."""
    return not ((x >= low) & (x <= high))


@kernel_only(error_model="numpy", forceinline=True)
def _huge(x0: float, x1: float, x2: float) -> bool:
    """True if a component is not a number or beyond ``LARGEST`` in size."""
    return _out(x0, -LARGEST, LARGEST) | _out(x1, -LARGEST, LARGEST) | _out(x2, -LARGEST, LARGEST)


@kernel_only(error_model="numpy", forceinline=True)
def law_block(
    s: np.ndarray, o: np.ndarray, m: int, d3: bool, law: int, spins: bool, q1: float, q2: float
) -> None:
    """The law on the first ``m`` pairs of the scratch block ``s`` (``IN_*`` rows), into
    ``o`` (``OUT_*`` rows); the arithmetic of the pass before blocks, operation for operation.
    In a case's own pass ``d3``, ``law`` and ``spins`` are constants where LLVM inlines it."""
    for k in range(m):
        a0, a1, a2 = s[IN_X1, k], s[IN_X1 + 1, k], s[IN_X1 + 2, k]
        b0, b1, b2 = s[IN_X2, k], s[IN_X2 + 1, k], s[IN_X2 + 2, k]
        p0, p1, p2 = s[IN_V1, k], s[IN_V1 + 1, k], s[IN_V1 + 2, k]
        s0, s1, s2 = s[IN_V2, k], s[IN_V2 + 1, k], s[IN_V2 + 2, k]
        mass1, mass2, ei = s[IN_M1, k], s[IN_M2, k], s[IN_E, k]
        refused = (
            _huge(a0, a1, a2)
            | _huge(b0, b1, b2)
            | _huge(p0, p1, p2)
            | _huge(s0, s1, s2)
            | ((mass1 != math.inf) & _out(mass1, SMALLEST, LARGEST))
            | ((mass2 != math.inf) & _out(mass2, SMALLEST, LARGEST))
            | ((mass1 == math.inf) & (mass2 == math.inf))
            | _out(ei, 0.0, 1.0)
        )

        r0, r1, r2 = a0 - b0, a1 - b1, a2 - b2
        dist2 = _dot(r0, r1, r2, r0, r1, r2, d3)
        refused = refused | (dist2 == 0.0)
        # a refused pair (centres together, both masses infinite) must not divide by zero:
        # in plain Python (NUMBA_DISABLE_JIT) that raises; an accepted pair is untouched
        root = math.sqrt(dist2) if dist2 > 0.0 else 1.0
        n0, n1, n2 = r0 / root, r1 / root, r2 / root
        inv_m1 = 0.0 if math.isinf(mass1) else 1.0 / mass1
        inv_m2 = 0.0 if math.isinf(mass2) else 1.0 / mass2
        inv_sum = inv_m1 + inv_m2
        mu = 1.0 / inv_sum if inv_sum > 0.0 else 0.0
        g0, g1, g2 = p0 - s0, p1 - s1, p2 - s2  # v1 - v2
        u = _dot(g0, g1, g2, n0, n1, n2, d3)
        applied = u < 0.0
        u_in = u if applied else 0.0
        jn = -(1.0 + ei) * mu * u_in
        j0, j1, j2 = jn * n0, jn * n1, jn * n2
        ke_lost = 0.5 * mu * (1.0 - ei * ei) * u_in * u_in

        w10 = w11 = w12 = w20 = w21 = w22 = rad1 = rad2 = 0.0
        if spins:
            w10, w11, w12 = s[IN_W1, k], s[IN_W1 + 1, k], s[IN_W1 + 2, k]
            w20, w21, w22 = s[IN_W2, k], s[IN_W2 + 1, k], s[IN_W2 + 2, k]
            rad1, rad2 = s[IN_R1, k], s[IN_R2, k]
            refused = (
                refused
                | _huge(w10, w11, w12)
                | _huge(w20, w21, w22)
                | _out(rad1, SMALLEST, LARGEST)
                | _out(rad2, SMALLEST, LARGEST)
            )

        beta_used = 0.0
        if law != LAW_SMOOTH:
            bi = s[IN_BETA, k]
            refused = refused | _out(bi, -1.0, 1.0)
            c10, c11, c12 = _spin_cross(rad1, w10, w11, w12, n0, n1, n2, d3)
            c20, c21, c22 = _spin_cross(rad2, w20, w21, w22, n0, n1, n2, d3)
            h0, h1, h2 = g0 - c10 - c20, g1 - c11 - c21, g2 - c12 - c22
            gn = _dot(h0, h1, h2, n0, n1, n2, d3)
            t0, t1, t2 = h0 - gn * n0, h1 - gn * n1, h2 - gn * n2
            g_t2 = _dot(t0, t1, t2, t0, t1, t2, d3)
            g_t = math.sqrt(g_t2)
            inv_mu_t = inv_m1 * (1.0 + 1.0 / q1) + inv_m2 * (1.0 + 1.0 / q2)
            mu_t = 1.0 / inv_mu_t if inv_mu_t > 0.0 else 1.0
            # Work with 1 + beta and 1 - beta, never beta itself: in a sliding contact
            # with |g_t| >> |g_n| the Coulomb cap puts beta within a hair of -1, and
            # forming -1 + x then 1 + beta would cancel most of x's digits (seen: 2.6e-12
            # relative excess over mu_f |J_n|); near beta = +1, 1 + beta rounds to 2 and
            # 1 - beta^2 would vanish.
            one_plus_beta, one_minus_beta, beta_used = 1.0 + bi, 1.0 - bi, bi
            if law == LAW_WALTON:
                fi = s[IN_FRICTION, k]
                refused = refused | _out(fi, 0.0, LARGEST)
                # Coulomb: |J_t| = (1 + beta) mu_t |g_t| <= mu_f (1 + e) mu |g_n|
                cap = fi * (1.0 + ei) * (mu / mu_t) * (-u_in) / g_t
                capped = (g_t > 0.0) & (cap < one_plus_beta)
                one_plus_beta = cap if capped else one_plus_beta
                one_minus_beta = 2.0 - cap if capped else one_minus_beta
                beta_used = cap - 1.0 if capped else beta_used
            one_plus_beta = one_plus_beta if applied else 0.0
            kt = one_plus_beta * mu_t
            j0, j1, j2 = j0 - kt * t0, j1 - kt * t1, j2 - kt * t2
            ke_lost = ke_lost + 0.5 * mu_t * one_plus_beta * one_minus_beta * g_t2

        y0, y1, y2 = p0 + j0 * inv_m1, p1 + j1 * inv_m1, p2 + j2 * inv_m1  # v1 after
        z0, z1, z2 = s0 - j0 * inv_m2, s1 - j1 * inv_m2, s2 - j2 * inv_m2  # v2 after
        o10 = o11 = o12 = o20 = o21 = o22 = 0.0  # spins after
        if spins:
            if d3:
                k0, k1, k2 = n1 * j2 - n2 * j1, n2 * j0 - n0 * j2, n0 * j1 - n1 * j0
            else:
                k0, k1, k2 = n0 * j1 - n1 * j0, 0.0, 0.0
            f1 = inv_m1 / (q1 * rad1)
            f2 = inv_m2 / (q2 * rad2)
            o10, o11, o12 = w10 - f1 * k0, w11 - f1 * k1, w12 - f1 * k2
            o20, o21, o22 = w20 - f2 * k0, w21 - f2 * k1, w22 - f2 * k2

        c0, c1, c2 = y0 - z0, y1 - z1, y2 - z2  # relative velocity after
        o[OUT_V1, k], o[OUT_V1 + 1, k], o[OUT_V1 + 2, k] = y0, y1, y2
        o[OUT_V2, k], o[OUT_V2 + 1, k], o[OUT_V2 + 2, k] = z0, z1, z2
        o[OUT_J, k], o[OUT_J + 1, k], o[OUT_J + 2, k] = j0, j1, j2
        o[OUT_N, k], o[OUT_N + 1, k], o[OUT_N + 2, k] = n0, n1, n2
        o[OUT_W1, k], o[OUT_W1 + 1, k], o[OUT_W1 + 2, k] = o10, o11, o12
        o[OUT_W2, k], o[OUT_W2 + 1, k], o[OUT_W2 + 2, k] = o20, o21, o22
        o[OUT_APPROACH, k] = -u
        o[OUT_SEPARATION, k] = _dot(c0, c1, c2, n0, n1, n2, d3)
        o[OUT_RELATIVE, k] = math.sqrt(_dot(c0, c1, c2, c0, c1, c2, d3))
        o[OUT_KE_BEFORE, k] = _kinetic(
            mass1, p0, p1, p2, w10, w11, w12, rad1, q1, d3, spins
        ) + _kinetic(mass2, s0, s1, s2, w20, w21, w22, rad2, q2, d3, spins)
        o[OUT_KE_AFTER, k] = _kinetic(
            mass1, y0, y1, y2, o10, o11, o12, rad1, q1, d3, spins
        ) + _kinetic(mass2, z0, z1, z2, o20, o21, o22, rad2, q2, d3, spins)
        o[OUT_KE_LOST, k] = ke_lost
        o[OUT_BETA, k] = beta_used
        o[OUT_APPLIED, k] = 1.0 if applied else 0.0
        o[OUT_REFUSED, k] = 1.0 if refused else 0.0


@kernel_only(error_model="numpy", forceinline=True)
def _stream_rows(dst: np.ndarray, o: np.ndarray, row: int, lo: int, m: int, width: int) -> None:
    """Rows ``lo .. lo + m - 1`` of ``dst`` (C order, ``width`` values a row: 1, 2 or 3) from
    the scratch rows ``row .. row + width - 1`` of ``o``, two values per streaming store.
    ``dst``'s data must start on 16 bytes and ``lo`` be even; an odd last row of a width of
    1 or 3 is stored plainly."""
    f = lo * width
    even = m - m % 2
    if width == 2:
        for k in range(m):
            stream_pair(dst, f + 2 * k, o[row, k], o[row + 1, k])
        even = m
    elif width == 1:
        for k in range(0, even, 2):
            stream_pair(dst, f + k, o[row, k], o[row, k + 1])
    else:
        for k in range(0, even, 2):
            g = f + 3 * k
            stream_pair(dst, g, o[row, k], o[row + 1, k])
            stream_pair(dst, g + 2, o[row + 2, k], o[row, k + 1])
            stream_pair(dst, g + 4, o[row + 1, k + 1], o[row + 2, k + 1])
    for k in range(even, m):
        for c in range(width):
            put_flat(dst, f + width * k + c, o[row + c, k])


#: from this many bytes of results on (all fields of a batch), they are written past the
#: caches. Measured here (2 cores, 4 MB of L2 each), a call with ``out=`` and a sum over two
#: fields of its result after it: with streaming stores 3D Walton at 2^19 pairs (105 MB) went
#: from 4.2-4.3e7 to 5.2e7 pairs/s; below about 64 MB plain stores win (2D smooth at 2^18
#: pairs, 30 MB: 8.7e7 against 7.1-7.4e7)
STREAM_BYTES = 1 << 26


def streams(outputs: list[np.ndarray]) -> bool:
    """Whether the pass is to write ``outputs`` (C-contiguous) past the caches, in
    streaming stores: when they hold :data:`STREAM_BYTES` or more and each float64 one starts
    on 16 bytes, as NumPy's own allocations do."""
    return sum(a.nbytes for a in outputs) >= STREAM_BYTES and all(
        a.ctypes.data % 16 == 0 for a in outputs if a.dtype == np.float64
    )


#: the passes compiled so far, by case (:func:`case_of`; 0: any case)
_PASSES: dict[int, Any] = {}

#: from this many pairs on, a batch runs in the pass of its own case (below, in case 0's)
CASE_PAIRS = 65536

#: the cases a pass is compiled for, with its own copy of the law: case k has the flags
#: ``(3D, law, spins)`` of ``CASES[k - 1]``
CASES = tuple(
    (d3, law, law != LAW_SMOOTH or spins)
    for d3 in (False, True)
    for law, spins in (
        (LAW_SMOOTH, False),
        (LAW_SMOOTH, True),
        (LAW_ROUGH, True),
        (LAW_WALTON, True),
    )
)


def case_of(dim: int, law: int, spins: bool) -> int:
    """The case of a batch in ``dim`` dimensions under ``law``, with or without spins (the
    rough laws always have them): its index in :data:`CASES`, plus 1."""
    return 1 + CASES.index((dim == 3, law, law != LAW_SMOOTH or spins))


def collide_rows(case: int, *args: Any) -> int:
    """:func:`_make_pass`'s pass for ``case`` on ``args`` (made on first use, compiled or
    loaded from the cache on its first call): the index of the first refused pair, or -1."""
    rows = _PASSES.get(case)
    if rows is None:
        rows = _PASSES.setdefault(case, _make_pass(case))
    first: int = rows(*args)
    return first


def _make_pass(case: int) -> Any:
    """The compiled pass over a batch, for one case (:func:`case_of`) or, with 0, for any.

    Each case is its own function (a closure over ``case``, cached on disk by its value), so
    that a program compiles only the cases it uses, about 3 s each, and small batches,
    which all run in case 0, only that one.
    """

    with kernel_cache():  # decorated here, long after the package's import: cache it with it
        return _compile_pass(case)


def _compile_pass(case: int) -> Any:
    """:func:`_make_pass`'s work, decorated inside :func:`carom.jit.kernel_cache`."""

    @njit(cache=True, error_model="numpy", parallel=True)
    def case_pass(
        x1: np.ndarray,
        v1: np.ndarray,
        m1: np.ndarray,
        x2: np.ndarray,
        v2: np.ndarray,
        m2: np.ndarray,
        e: np.ndarray,
        w1: np.ndarray,
        w2: np.ndarray,
        radius1: np.ndarray,
        radius2: np.ndarray,
        beta: np.ndarray,
        friction: np.ndarray,
        law: int,
        spins: bool,
        q1: float,
        q2: float,
        stream: bool,
        out_v1: np.ndarray,
        out_v2: np.ndarray,
        out_w1: np.ndarray,
        out_w2: np.ndarray,
        out_impulse: np.ndarray,
        out_normal: np.ndarray,
        out_approach: np.ndarray,
        out_separation: np.ndarray,
        out_relative: np.ndarray,
        out_ke_before: np.ndarray,
        out_ke_after: np.ndarray,
        out_ke_lost: np.ndarray,
        out_beta: np.ndarray,
        out_applied: np.ndarray,
    ) -> int:
        """Apply the law to every pair; return the index of the first refused pair, or -1.

        ``beta`` holds the constant tangential restitution (``LAW_ROUGH``) or Walton's ``beta0``
        (``LAW_WALTON``). The outputs are the fields of a ``CollisionResult``. ``out_w1``,
        ``out_w2`` are written only with ``spins`` and ``out_beta`` only for the rough laws.
        After a refused pair the outputs are meaningless. Blocks of pairs run on Numba's
        threads; each pair is computed alone, so the bits do not depend on the thread count.
        """
        n = out_v1.shape[0]
        d3 = x1.shape[1] == 3
        dim = x1.shape[1]
        rough = law != LAW_SMOOTH
        # an input of one row is broadcast: its row is i * 0
        sx1, sv1, sx2, sv2 = x1.shape[0] > 1, v1.shape[0] > 1, x2.shape[0] > 1, v2.shape[0] > 1
        sm1, sm2, se = m1.shape[0] > 1, m2.shape[0] > 1, e.shape[0] > 1
        sw1, sw2 = w1.shape[0] > 1, w2.shape[0] > 1
        sr1, sr2 = radius1.shape[0] > 1, radius2.shape[0] > 1
        sb, sf = beta.shape[0] > 1, friction.shape[0] > 1
        blocks = (n + BLOCK - 1) // BLOCK
        first = np.empty(blocks, dtype=np.int64)  # the first refused pair of each block, or n
        for block in prange(blocks):
            s = stack_block(IN_ROWS, LANES)
            o = stack_block(OUT_ROWS, LANES)
            bad = n
            end = min(n, (block + 1) * BLOCK)
            for lo in range(block * BLOCK, end, LANES):
                m = min(LANES, end - lo)
                for k in range(m):  # in: the block's inputs, one row per component
                    i = lo + k
                    for c in range(3):
                        s[IN_X1 + c, k] = x1[i * sx1, c] if c < dim else 0.0
                        s[IN_X2 + c, k] = x2[i * sx2, c] if c < dim else 0.0
                        s[IN_V1 + c, k] = v1[i * sv1, c] if c < dim else 0.0
                        s[IN_V2 + c, k] = v2[i * sv2, c] if c < dim else 0.0
                        s[IN_W1 + c, k] = w1[i * sw1, c] if spins and c < w1.shape[1] else 0.0
                        s[IN_W2 + c, k] = w2[i * sw2, c] if spins and c < w2.shape[1] else 0.0
                    s[IN_M1, k], s[IN_M2, k], s[IN_E, k] = m1[i * sm1], m2[i * sm2], e[i * se]
                    s[IN_R1, k] = radius1[i * sr1] if spins else 0.0
                    s[IN_R2, k] = radius2[i * sr2] if spins else 0.0
                    s[IN_BETA, k] = beta[i * sb] if rough else 0.0
                    s[IN_FRICTION, k] = friction[i * sf] if law == LAW_WALTON else 0.0
                # the law, inlined by LLVM: for a case, with its flags as constants (computed here,
                # inside the threads' loop, from the closure's constant), so that the copy has no
                # branch on them; for case 0, with the arguments'
                if case == 0:
                    law_block(s, o, m, d3, law, spins, q1, q2)
                else:
                    case_d3, case_law, case_spins = CASES[case - 1]
                    law_block(s, o, m, case_d3, case_law, case_spins, q1, q2)
                # out: past the caches, array by array, in a case's own pass (case 0 has no such
                # code: its batches are far smaller than STREAM_BYTES)
                if case != 0 and stream:
                    _stream_rows(out_v1, o, OUT_V1, lo, m, dim)
                    _stream_rows(out_v2, o, OUT_V2, lo, m, dim)
                    _stream_rows(out_impulse, o, OUT_J, lo, m, dim)
                    _stream_rows(out_normal, o, OUT_N, lo, m, dim)
                    if spins:
                        _stream_rows(out_w1, o, OUT_W1, lo, m, out_w1.shape[1])
                        _stream_rows(out_w2, o, OUT_W2, lo, m, out_w2.shape[1])
                    if rough:
                        _stream_rows(out_beta, o, OUT_BETA, lo, m, 1)
                    _stream_rows(out_approach, o, OUT_APPROACH, lo, m, 1)
                    _stream_rows(out_separation, o, OUT_SEPARATION, lo, m, 1)
                    _stream_rows(out_relative, o, OUT_RELATIVE, lo, m, 1)
                    _stream_rows(out_ke_before, o, OUT_KE_BEFORE, lo, m, 1)
                    _stream_rows(out_ke_after, o, OUT_KE_AFTER, lo, m, 1)
                    _stream_rows(out_ke_lost, o, OUT_KE_LOST, lo, m, 1)
                    for k in range(m):
                        i = lo + k
                        out_applied[i] = o[OUT_APPLIED, k] != 0.0
                        bad = min(bad, i if o[OUT_REFUSED, k] != 0.0 else n)
                else:  # out: the results, in the caller's layout
                    for k in range(m):
                        i = lo + k
                        for c in range(dim):
                            out_v1[i, c] = o[OUT_V1 + c, k]
                            out_v2[i, c] = o[OUT_V2 + c, k]
                            out_impulse[i, c] = o[OUT_J + c, k]
                            out_normal[i, c] = o[OUT_N + c, k]
                        if spins:
                            for c in range(out_w1.shape[1]):
                                out_w1[i, c] = o[OUT_W1 + c, k]
                                out_w2[i, c] = o[OUT_W2 + c, k]
                        if rough:
                            out_beta[i] = o[OUT_BETA, k]
                        out_approach[i] = o[OUT_APPROACH, k]
                        out_separation[i] = o[OUT_SEPARATION, k]
                        out_relative[i] = o[OUT_RELATIVE, k]
                        out_ke_before[i] = o[OUT_KE_BEFORE, k]
                        out_ke_after[i] = o[OUT_KE_AFTER, k]
                        out_ke_lost[i] = o[OUT_KE_LOST, k]
                        out_applied[i] = o[OUT_APPLIED, k] != 0.0
                        bad = min(bad, i if o[OUT_REFUSED, k] != 0.0 else n)
            if case != 0 and stream:
                stream_fence()
            first[block] = bad
        bad = n
        for block in range(blocks):
            bad = min(bad, first[block])
        return -1 if bad == n else bad

    return case_pass
