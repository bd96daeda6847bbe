"""Hypothesis strategies for two-body impacts: masses 1e-3 to 1e3 kg, speeds to 10 m/s."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from hypothesis import strategies as st

EPS = float(np.finfo(np.float64).eps)

masses = st.floats(min_value=-3.0, max_value=3.0).map(lambda p: float(10.0**p))
restitutions = st.floats(min_value=0.0, max_value=1.0)
betas = st.floats(min_value=-1.0, max_value=1.0)
radii = st.floats(min_value=1e-2, max_value=1.0)


def vectors(dim: int, bound: float = 10.0) -> st.SearchStrategy[np.ndarray]:
    comp = st.floats(min_value=-bound, max_value=bound, allow_subnormal=False)
    return st.lists(comp, min_size=dim, max_size=dim).map(np.array)


def unit_vectors(dim: int) -> st.SearchStrategy[np.ndarray]:
    return (
        vectors(dim, 1.0)
        .filter(lambda v: np.hypot.reduce(v) > 0.1)
        .map(lambda v: v / np.sqrt(v @ v))
    )


@dataclass
class Pair:
    """Two bodies at the instant of contact (|x1 - x2| = a1 + a2)."""

    x1: np.ndarray
    v1: np.ndarray
    m1: float
    x2: np.ndarray
    v2: np.ndarray
    m2: float
    a1: float
    a2: float

    @property
    def n(self) -> np.ndarray:
        r = self.x1 - self.x2
        return r / np.sqrt(r @ r)

    @property
    def args(self) -> tuple[np.ndarray, np.ndarray, float, np.ndarray, np.ndarray, float]:
        return self.x1, self.v1, self.m1, self.x2, self.v2, self.m2


@st.composite
def pairs(draw: st.DrawFn, dim: int) -> Pair:
    n = draw(unit_vectors(dim))
    a1, a2 = draw(radii), draw(radii)
    x2 = draw(vectors(dim, 5.0))
    return Pair(
        x1=x2 + (a1 + a2) * n,
        v1=draw(vectors(dim)),
        m1=draw(masses),
        x2=x2,
        v2=draw(vectors(dim)),
        m2=draw(masses),
        a1=a1,
        a2=a2,
    )


def spins(dim: int) -> st.SearchStrategy[np.ndarray | float]:
    if dim == 2:
        return st.floats(min_value=-50.0, max_value=50.0)
    return vectors(3, 50.0)


def random_rotation(dim: int, seed: int) -> np.ndarray:
    """A proper rotation matrix (det +1) drawn from a seeded generator."""
    rng = np.random.default_rng(seed)
    q, r = np.linalg.qr(rng.normal(size=(dim, dim)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q
