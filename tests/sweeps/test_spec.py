"""Sweep files: parameters by dotted path, ranges, crossing and zipping, seeds, and every
mistake refused with the key and the fix (nothing runs)."""

from __future__ import annotations

from pathlib import Path

import pytest

from carom.sweeps import SweepError, builtin_sweeps, load_sweep
from tests.sweeps.helpers import write_sweep


def test_ranges_lists_and_crossing(tmp_path: Path) -> None:
    spec = load_sweep(
        write_sweep(
            tmp_path,
            '"gas.count" = {from = 10, to = 30, step = 10}\n'
            '"gas.temperature" = {from = 0.1, to = 10.0, steps = 3, log = true}\n'
            '"world.box" = [[5.0, 5.0, 5.0], [6.0, 6.0, 6.0]]\n',
        )
    )
    # one-entry arrays of tables are named with their index in the table
    assert spec.parameters == {
        "gas.0.count": [10, 20, 30],
        "gas.0.temperature": [0.1, 1.0, 10.0],
        "world.box": [[5.0, 5.0, 5.0], [6.0, 6.0, 6.0]],
    }
    grid = spec.grid()
    assert len(grid) == 3 * 3 * 2  # crossed: every combination, the first slowest
    assert grid[0] == {"gas.0.count": 10, "gas.0.temperature": 0.1, "world.box": [5.0] * 3}
    assert grid[1]["world.box"] == [6.0] * 3
    assert grid[-1] == {"gas.0.count": 30, "gas.0.temperature": 10.0, "world.box": [6.0] * 3}
    points = spec.check()
    assert len(points) == 18 * 2  # two seeds each
    last = points[-1]
    assert (last.index, last.seed) == (17, 2)
    assert last.scene["gas"][0]["count"] == 30
    assert last.scene["gas"][0]["seed"] == 2  # the seed goes where the scene has one
    assert last.scene["world"]["box"] == [6.0] * 3


def test_zip_and_linear_steps(tmp_path: Path) -> None:
    spec = load_sweep(
        write_sweep(
            tmp_path,
            '"gas.packing" = {from = 0.3, to = 0.4, steps = 3}\n"gas.count" = [20, 25, 30]\n',
            head='combine = "zip"\nseeds = [7]',
        )
    )
    # 0.3 + 0.05 k to 12 significant digits, as a reader of the table would write it
    assert spec.grid() == [
        {"gas.0.packing": 0.3, "gas.0.count": 20},
        {"gas.0.packing": 0.35, "gas.0.count": 25},
        {"gas.0.packing": 0.4, "gas.0.count": 30},
    ]
    assert [p.seed for p in spec.points()] == [7, 7, 7]


def test_several_seed_keys_get_their_own_streams(tmp_path: Path) -> None:
    two_gases = """
[world]
dimension = 2
box = [20.0, 20.0]
boundary = "periodic"
[[gas]]
count = 5
packing = 0.3
radius = 0.5
seed = 1
[[gas]]
count = 5
packing = 0.3
radius = 0.5
seed = 2
[run]
until = 1.0
"""
    spec = load_sweep(write_sweep(tmp_path, '"gas.0.count" = [5]', scene=two_gases))
    assert spec.seed_keys == ["gas.0.seed", "gas.1.seed"]
    seeds = [(p.scene["gas"][0]["seed"], p.scene["gas"][1]["seed"]) for p in spec.points()]
    # seed s: key k gets s * 2 + k, so no two generators share a stream
    assert seeds == [(2, 3), (4, 5)]


@pytest.mark.parametrize(
    ("parameters", "head", "words"),
    [
        ('"gas.colour" = [1]', "", "colour: is not a known key"),
        ('"plasma.count" = [1]', "", "the scene has no plasma"),
        ('"gas.count" = []', "", "the list of values is empty"),
        ('"gas.count" = {from = 1, to = 5}', "", "give steps = n"),
        ('"gas.temperature" = {from = 0, to = 5, steps = 3, log = true}', "", "from and to > 0"),
        ('"gas.count" = [10, 20]\n"gas.seed" = [1]', 'combine = "zip"', "as many values each"),
        ('"gas.radius" = [-1.0]', "", "point 0 (gas.0.radius = -1.0) is not a valid scene"),
        ('"gas.count" = [10]', 'observables = ["entropy"]', "'entropy' is not an observable"),
        ('"gas.count" = [10]', "warmup = 2.0\nuntil = 1.0", "must end before until"),
        ('"gas.count" = [10]', "seeds = [1, 1]", "lists a seed twice"),
        ('"gas.count" = [10]', 'scene = "no-such-scene"', "no such scene file"),
        ('"gas.count" = [10]', "speed = 3", "[sweep] speed is not a known key"),
    ],
)
def test_mistakes_are_refused_by_name(
    tmp_path: Path, parameters: str, head: str, words: str
) -> None:
    path = write_sweep(tmp_path, parameters, head=head)
    with pytest.raises(SweepError) as caught:
        load_sweep(path).check()
    assert words in str(caught.value)
    assert str(path) in str(caught.value)  # the file is named


def test_seeds_need_a_seed_key(tmp_path: Path) -> None:
    still = "[world]\ndimension = 2\nbox = [1.0, 1.0]\n[[bodies]]\npositions = [[0.5, 0.5]]\n"
    still += "radius = 0.1\n[run]\nuntil = 1.0\n"
    path = write_sweep(tmp_path, '"bodies.radius" = [0.1, 0.2]', scene=still)
    with pytest.raises(SweepError, match="no seed key to set"):
        load_sweep(path)


def test_builtin_sweeps_are_valid() -> None:
    names = set(builtin_sweeps())
    assert {"eos-3d", "eos-2d", "haff", "rebound"} <= names
    for name in names:
        points = load_sweep(name).check()
        assert points
