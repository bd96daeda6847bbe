"""The neighbour lists and cell grid (carom.engines.edmd.neighbours), tested directly against
brute force: body i lists body j exactly when their shells overlap,
|c_i - c_j| < a_i + a_j + 2 delta (nearest image when periodic), and static bodies list
nobody (Smallenburg 2022, as the module docstring states)."""

from __future__ import annotations

import numpy as np
import pytest

from carom.engines.edmd import threads
from carom.engines.edmd.neighbours import CELL_FULL, FITS, LIST_FULL, build_all, first_overlap


def _grid(
    dim: int,
    n: int,
    periodic: bool,
    seed: int,
    capacity: int = 64,
    cell_capacity: int = 64,
    delta: float = 0.3,
) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    box = np.full(dim, 10.0)
    radius = rng.uniform(0.1, 0.4, n)
    shell = np.zeros((n, 4))
    shell[:, :dim] = rng.uniform(0.0, 10.0, (n, dim))
    shell[:, 3] = radius
    ncell = np.maximum(1, np.floor(box / (2 * (radius.max() + delta)))).astype(np.int64)
    n_cells = int(np.prod(ncell))
    return {
        "shell": shell,
        "mobile": rng.random(n) < 0.8,
        "nbr": np.zeros((n, capacity), np.int32),
        "count": np.zeros(n, np.int64),
        "cell_count": np.zeros(n_cells, np.int64),
        "cell_body": np.zeros((n_cells, cell_capacity), np.int32),
        "slot": np.zeros(n, np.int64),
        "cell": np.zeros(n, np.int64),
        "box": box,
        "periodic": np.bool_(periodic),
        "delta": np.float64(delta),
        "cell_size": box / ncell,
        "ncell": ncell,
    }


def _build(g: dict[str, np.ndarray]) -> int:
    return int(build_all(*(g[k] for k in g)))


def _assert_lists_are_the_overlapping_shells(
    g: dict[str, np.ndarray], dim: int, periodic: bool
) -> None:
    c, a = g["shell"][:, :dim], g["shell"][:, 3]
    d = c[:, None, :] - c[None, :, :]
    if periodic:
        d -= g["box"] * np.floor(d / g["box"] + 0.5)
    reach = a[:, None] + a[None, :] + 2 * g["delta"]
    overlap = (np.sum(d * d, axis=2) < reach**2) & ~np.eye(len(a), dtype=bool)
    for i in range(len(a)):
        listed = set(g["nbr"][i, : g["count"][i]].tolist())
        expected = set(np.flatnonzero(overlap[i]).tolist()) if g["mobile"][i] else set()
        assert listed == expected, i


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize(
    ("periodic", "n", "delta"),
    [
        (False, 300, 0.3),
        (True, 300, 0.3),  # 7 cells a side: each pair's image is its cell's
        (True, 60, 1.8),  # 2 cells a side: both neighbouring cells are one, met once
    ],
)
def test_lists_are_exactly_the_overlapping_shells(
    dim: int, periodic: bool, n: int, delta: float
) -> None:
    g = _grid(dim, n, periodic, seed=dim, delta=delta)
    assert int(g["ncell"][0]) == (2 if delta > 1.0 else 7)
    assert _build(g) == FITS
    _assert_lists_are_the_overlapping_shells(g, dim, periodic)
    # every body sits in the cell of its centre, at its slot
    for i in range(len(g["shell"])):
        assert g["cell_body"][g["cell"][i], g["slot"][i]] == i


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("periodic", [False, True])
def test_cells_as_wide_as_a_shell_lose_no_pair(dim: int, periodic: bool) -> None:
    # A scan skips the cells farther from a shell's centre than its radius, twice the
    # thickness and the largest radius, bounded by half a cell. With spheres of one size in
    # cells exactly a shell diameter wide (0.5 + 0.5 m: 5 cells of 2 m) that bound is tight:
    # every pair nearly touching across a corner must still be listed.
    g = _grid(dim, 400 if dim == 3 else 150, periodic, seed=7 + dim, delta=0.5)
    g["shell"][:, 3] = 0.5
    g["ncell"][:] = 5
    g["cell_size"][:] = 2.0
    assert _build(g) == FITS
    _assert_lists_are_the_overlapping_shells(g, dim, periodic)


def test_full_lists_and_full_cells_are_reported() -> None:
    # (the engine then doubles the room and builds again: cramped worlds in
    # tests/engines/edmd/test_closed_forms.py)
    assert _build(_grid(3, 300, False, seed=1, capacity=1)) == LIST_FULL
    assert _build(_grid(3, 300, False, seed=1, cell_capacity=1)) == CELL_FULL


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("periodic", [False, True])
def test_the_first_overlap_is_the_first_by_brute_force(dim: int, periodic: bool) -> None:
    # Random spheres (radii 0.1-0.4 m in a 10 m box) overlap here and there. first_overlap
    # walks the moving bodies in order and measures a pair of moving bodies once, from the
    # first of the two: the pair it returns must overlap, by the amount it says, and no
    # overlapping pair may be met earlier: none whose first moving body comes before.
    g = _grid(dim, 300, periodic, seed=10 + dim)
    assert _build(g) == FITS
    c, a, mobile = g["shell"][:, :dim], g["shell"][:, 3], g["mobile"]
    kin = np.zeros((len(a), 8))
    kin[:, :dim] = c
    tol = 1e-12
    d = c[:, None, :] - c[None, :, :]
    if periodic:
        d -= g["box"] * np.floor(d / g["box"] + 0.5)
    reach = a[:, None] + a[None, :]
    depth = reach - np.sqrt(np.sum(d * d, axis=2))
    over = (depth > tol * reach) & ~np.eye(len(a), dtype=bool)
    over &= mobile[:, None] | mobile[None, :]  # two static bodies may overlap
    i_all, j_all = np.nonzero(np.triu(over))
    assert len(i_all) > 1  # the case is not empty
    pairs = zip(i_all.tolist(), j_all.tolist(), strict=True)
    first = min(min(i, j) if mobile[i] and mobile[j] else (i if mobile[i] else j) for i, j in pairs)
    i, j, amount = first_overlap(
        0, len(a), kin, g["nbr"], g["count"], mobile, a, g["box"], periodic, tol
    )
    assert i == first
    assert over[i, j]
    # the same sum, in the kernel's order: equal to the last bit or two
    assert amount == pytest.approx(depth[i, j], rel=0, abs=4 * np.finfo(float).eps * reach[i, j])
    # radii shrunk below half the closest distance (the lists, built for larger shells, still
    # hold every pair that could touch): nothing overlaps
    apart = np.sqrt(np.sum(d * d, axis=2))[~np.eye(len(a), dtype=bool)].min()
    small = np.full(len(a), 0.45 * apart)
    found = first_overlap(
        0, len(a), kin, g["nbr"], g["count"], mobile, small, g["box"], periodic, tol
    )
    assert found == (-1, -1, 0.0)


def _lists(g: dict[str, np.ndarray]) -> list[list[int]]:
    return [g["nbr"][i, : g["count"][i]].tolist() for i in range(len(g["count"]))]


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("periodic", [False, True])
def test_lists_in_the_order_of_filing_the_bodies_one_by_one(dim: int, periodic: bool) -> None:
    # build_all gives the lists of filing the bodies in the order of their numbers, each
    # linked with those already filed: a moving body lists first its neighbours numbered
    # below it (in the order of the scan of the grid), then those above it, each appended
    # when it was filed, so in increasing numbers
    g = _grid(dim, 400, periodic, seed=20 + dim)
    assert _build(g) == FITS
    above_seen = 0
    for i, listed in enumerate(_lists(g)):
        below = [j for j in listed if j < i]
        above = [j for j in listed if j > i]
        assert listed == below + above, i
        assert above == sorted(above), i
        above_seen += len(above)
    assert above_seen > 100  # (the case is not empty)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("periodic", [False, True])
@pytest.mark.parametrize("ranges", [2, 3, 7])
def test_the_same_bits_on_any_number_of_ranges(
    dim: int, periodic: bool, ranges: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    # the scans run over ranges of bodies on threads (carom.engines.edmd.threads); every
    # array the build writes, scratch left in the rows included, is the same with one range
    # as with several
    one = _grid(dim, 400, periodic, seed=30 + dim)
    assert _build(one) == FITS
    monkeypatch.setattr(threads, "range_count", lambda n: min(ranges, n))
    many = _grid(dim, 400, periodic, seed=30 + dim)
    assert _build(many) == FITS
    for name in ("nbr", "count", "cell_count", "cell_body", "slot", "cell"):
        np.testing.assert_array_equal(many[name], one[name], err_msg=name)
    # and a list that overflows is reported from any range
    assert _build(_grid(3, 300, False, seed=1, capacity=1)) == LIST_FULL
