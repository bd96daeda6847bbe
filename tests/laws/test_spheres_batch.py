"""A batch gives, pair by pair, exactly (bit for bit) what single calls give."""

from __future__ import annotations

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
def test_batch_equals_single_pairs_exactly(dim: int, law: str) -> None:
    b = _batch(dim)
    batch = carom.collide(**b, **LAWS[law]())
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
