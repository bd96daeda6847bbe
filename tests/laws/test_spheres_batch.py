"""A batch gives, pair by pair, exactly (bit for bit) what single calls give."""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

import carom
from carom.studies import hecker

RNG_SEED = 20261121


def _batch(dim: int, n: int = 64) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(RNG_SEED + dim)
    normal = rng.normal(size=(n, dim))
    normal /= np.linalg.norm(normal, axis=1)[:, None]
    a1, a2 = rng.uniform(0.05, 1.0, n), rng.uniform(0.05, 1.0, n)
    x2 = rng.normal(size=(n, dim))
    spin_shape = (n,) if dim == 2 else (n, 3)
    m2 = 10.0 ** rng.uniform(-3, 3, n)
    m2[::7] = math.inf  # some static partners
    return {
        "x1": x2 + (a1 + a2)[:, None] * normal,
        "v1": rng.normal(size=(n, dim)),
        "m1": 10.0 ** rng.uniform(-3, 3, n),
        "x2": x2,
        "v2": rng.normal(size=(n, dim)),
        "m2": m2,
        "e": rng.uniform(0, 1, n),
        "w1": rng.normal(size=spin_shape) * 10,
        "w2": rng.normal(size=spin_shape) * 10,
        "radius1": a1,
        "radius2": a2,
    }


LAWS = {
    "smooth": lambda: {},
    "rough": lambda: {"beta": 0.3},
    "walton": lambda: {"friction": 0.4, "beta0": 0.2},
}


def _fields(result: carom.CollisionResult) -> dict[str, object]:
    return {k: getattr(result, k) for k in result.__dataclass_fields__}


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("law", list(LAWS))
@pytest.mark.parametrize("n", [64, 131])
@pytest.mark.parametrize("case", ["any", "own", "own, streaming"])
def test_batch_equals_single_pairs_exactly(
    dim: int, law: str, n: int, case: str, monkeypatch: pytest.MonkeyPatch
) -> None:
    # the compiled pass works through scratch blocks of carom.laws.batch.LANES = 32 pairs:
    # 131 pairs end in a block of 3, and each pair sits in another lane than when alone.
    # Large batches run in a pass compiled for their own case (dimension, law, spins), with
    # the law vectorised; "own" sends this small batch there too, against single pairs in
    # the pass for any case. There, results of STREAM_BYTES or more written over (out=) are
    # stored two values at a time, in streaming stores ("streaming" sends these there too):
    # 131 pairs end in an odd row, which is stored plainly
    from carom.laws import batch as batch_pass
    from carom.laws import spheres

    b = _batch(dim, n)
    if case != "any":
        monkeypatch.setattr(spheres, "CASE_PAIRS", 2)
    out = None
    if case == "own, streaming":  # written over: out=
        monkeypatch.setattr(batch_pass, "STREAM_BYTES", 0)
        out = carom.collide(**{**b, "v1": b["v1"][::-1].copy()}, **LAWS[law]())
    chosen: list[bool] = []
    decide = spheres.streams
    monkeypatch.setattr(
        spheres, "streams", lambda outputs: chosen.append(decide(outputs)) or chosen[-1]
    )
    batch = carom.collide(**b, **LAWS[law](), out=out)
    # whether the pass streamed: asked only in a case's own pass
    assert chosen == ([True] if case == "own, streaming" else [])
    monkeypatch.undo()
    for i in range(len(b["m1"])):
        single = carom.collide(**{k: v[i] for k, v in b.items()}, **LAWS[law]())
        for name, value in _fields(single).items():
            if value is None:
                assert getattr(batch, name) is None
                continue
            np.testing.assert_array_equal(getattr(batch, name)[i], value, err_msg=name)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("reading", ["contact", "head-on"])
def test_hecker_batch_equals_single_pairs_exactly(dim: int, reading: str) -> None:
    b = _batch(dim)
    batch = hecker.collide(**b, reading=reading)  # type: ignore[arg-type]
    for i in range(len(b["m1"])):
        single = hecker.collide(**{k: v[i] for k, v in b.items()}, reading=reading)  # type: ignore[arg-type]
        np.testing.assert_array_equal(batch.v1[i], single.v1)
        np.testing.assert_array_equal(batch.v2[i], single.v2)
        assert batch.w1 is not None
        assert single.w1 is not None
        np.testing.assert_array_equal(batch.w1[i], single.w1)


def test_scalars_broadcast_against_a_batch() -> None:
    # one moving sphere against three targets of different mass: scalars broadcast
    r = carom.collide(
        [[-0.2, 0.0]] * 3, [1.0, 0.0], 1.0, [0.0, 0.0], [0.0, 0.0], [1.0, 3.0, math.inf], e=1.0
    )
    assert r.v1.shape == (3, 2)
    # textbook: v1' = (m1 - m2)/(m1 + m2) v1 -> 0, -1/2, -1
    np.testing.assert_allclose(r.v1[:, 0], [0.0, -0.5, -1.0], atol=1e-15)
    assert r.applied.tolist() == [True, True, True]


def test_single_pair_returns_unbatched_shapes() -> None:
    r = carom.collide(
        [0, 0, 0], [1, 0, 0], 1, [0.2, 0, 0], [0, 0, 0], 1, w1=[0, 0, 1], radius1=0.1, radius2=0.1
    )
    assert r.v1.shape == (3,)
    assert r.w1 is not None
    assert r.w1.shape == (3,)
    assert np.ndim(r.ke_lost) == 0
    assert isinstance(r.applied, bool)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("law", list(LAWS))
def test_out_is_written_over_with_the_bits_of_a_fresh_call(dim: int, law: str) -> None:
    b = _batch(dim)
    fresh = carom.collide(**b, **LAWS[law]())
    other = _batch(dim, n=64)
    other["v1"] = other["v1"][::-1].copy()  # a different batch of the same shape
    out = carom.collide(**other, **LAWS[law]())
    again = carom.collide(**b, **LAWS[law](), out=out)
    assert again is out
    for name, value in _fields(fresh).items():
        if value is None:
            assert getattr(out, name) is None
        else:
            np.testing.assert_array_equal(getattr(out, name), value, err_msg=name)


def test_streaming_stores_need_large_results_that_start_on_16_bytes(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from carom.laws import batch as batch_pass
    from carom.laws import spheres

    n = 64
    aligned = np.empty(n)
    assert aligned.ctypes.data % 16 == 0  # NumPy's allocations start on 16 bytes (or more)
    # 8 bytes further on: a C-contiguous float64 array a streaming store cannot write two at
    # a time
    shifted = np.empty(3 * n + 1)[1:].reshape(n, 3)
    assert not batch_pass.streams([aligned])  # 512 bytes, far below STREAM_BYTES
    assert batch_pass.streams([np.empty(batch_pass.STREAM_BYTES // 8)])
    monkeypatch.setattr(batch_pass, "STREAM_BYTES", 0)
    monkeypatch.setattr(spheres, "CASE_PAIRS", 2)
    assert batch_pass.streams([aligned, np.empty(n, dtype=bool)])
    assert not batch_pass.streams([aligned, shifted])

    # an out= whose arrays start 8 bytes off is written plainly, with the same bits
    b = _batch(3, n)
    fresh = carom.collide(**b, friction=0.4, beta0=0.2)
    parts = {}
    for name, value in _fields(fresh).items():
        if isinstance(value, np.ndarray) and value.dtype == np.float64:
            flat = np.empty(value.size + 1)[1:]
            parts[name] = flat.reshape(value.shape)
            parts[name][...] = np.nan
    out = dataclasses.replace(fresh, **parts)
    assert carom.collide(**b, friction=0.4, beta0=0.2, out=out) is out
    for name, value in _fields(fresh).items():
        np.testing.assert_array_equal(getattr(out, name), value, err_msg=name)


def test_an_out_that_does_not_fit_is_refused_by_name() -> None:
    b = _batch(3)
    smooth = carom.collide(**{k: b[k] for k in ("x1", "v1", "m1", "x2", "v2", "m2", "e")})
    with pytest.raises(carom.CaromError, match=r"out\.w1 does not fit .* shape \(64, 3\)"):
        carom.collide(**b, beta=0.3, out=smooth)  # a rough call needs the spins' arrays
    short = carom.collide(**{k: v[:10] for k, v in b.items()})
    with pytest.raises(
        carom.CaromError, match=r"out\.v1 does not fit .* shape \(64, 3\), got shape \(10, 3\)"
    ):
        carom.collide(**b, out=short)
    with pytest.raises(carom.CaromError, match="out must be the CollisionResult"):
        carom.collide(**b, out=np.zeros((64, 3)))  # type: ignore[arg-type]
    with pytest.raises(carom.CaromError, match="a single pair returns scalars"):
        carom.collide(**{k: v[0] for k, v in b.items()}, out=smooth)
    result = carom.collide(**b)
    with pytest.raises(carom.CaromError, match=r"out\.v1 shares memory with v1"):
        carom.collide(**{**b, "v1": result.v1}, out=result)


@pytest.mark.parametrize("dim", [2, 3])
def test_the_first_bad_pair_of_a_large_batch_is_named(dim: int) -> None:
    # 20,000 pairs run in several blocks of the compiled pass (carom.laws.batch.BLOCK = 4096);
    # the bad pairs lie in different blocks, and the first in index order is named
    rng = np.random.default_rng(RNG_SEED)
    n = 20_000
    x2 = rng.normal(size=(n, dim))
    args = {
        "x1": x2 + 1.0,
        "v1": rng.normal(size=(n, dim)),
        "m1": np.ones(n),
        "x2": x2,
        "v2": rng.normal(size=(n, dim)),
        "m2": np.ones(n),
    }
    args["m1"][[15_001, 9_002]] = -1.0, -2.0
    with pytest.raises(carom.CaromError, match=r"m1\[9002\] = -2\.0"):
        carom.collide(**args)
    args["m1"][:] = 1.0
    args["x2"][[19_999, 4_100]] = args["x1"][[19_999, 4_100]]
    with pytest.raises(carom.CaromError, match=r"x1 and x2 coincide at index 4100"):
        carom.collide(**args)
    args["v2"][12_000, -1] = math.inf
    with pytest.raises(carom.CaromError, match=r"v2 must be finite \[m/s\]; got v2\[12000\]"):
        carom.collide(**args)  # argument checks come before the pair checks, as ever


@pytest.mark.needs_jit
def test_the_bits_do_not_depend_on_the_number_of_threads() -> None:
    import numba

    b = _batch(3, n=70_000)  # 18 blocks of the compiled pass, in the pass for its own case
    before = numba.get_num_threads()
    try:
        numba.set_num_threads(1)
        one = carom.collide(**b, friction=0.3, beta0=0.1)
        numba.set_num_threads(numba.config.NUMBA_NUM_THREADS)
        many = carom.collide(**b, friction=0.3, beta0=0.1)
    finally:
        numba.set_num_threads(before)
    for name, value in _fields(one).items():
        np.testing.assert_array_equal(getattr(many, name), value, err_msg=name)


def test_the_compiled_pass_refuses_what_the_limits_refuse() -> None:
    from carom import limits
    from carom.laws import batch

    # the kernel keeps its own copies of carom.limits' bounds (kernel constants live in the
    # kernel packages, whose hash names the cache); they must be the same numbers
    assert (batch.LARGEST, batch.SMALLEST) == (limits.LARGEST, limits.SMALLEST)
