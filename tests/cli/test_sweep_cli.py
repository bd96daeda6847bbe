"""``carom sweep`` as a user runs it: a built-in sweep on two local workers, and every
mistake refused with exit code 2, one line and no traceback, before anything is written."""

from __future__ import annotations

import csv
from pathlib import Path

from tests.cli.helpers import carom
from tests.sweeps.helpers import write_sweep


def test_builtin_sweep_on_two_workers(tmp_path: Path) -> None:
    out = tmp_path / "rebound"
    done = carom("sweep", "rebound", "--out", out, "--workers", "2")
    assert done.returncode == 0, done.stderr
    assert "10 runs (10 points x 1 seed) on 2 workers" in done.stdout
    assert "0 failed" in done.stdout
    with (out / "results.csv").open() as handle:
        table = list(csv.DictReader(handle))
    assert [float(row["world.walls.2"]) for row in table] == [k / 10 for k in range(1, 11)]
    assert all(row["status"] == "ok" for row in table)
    assert (out / "plot-rebound_height.png").stat().st_size > 10_000
    # again into the same folder: refused, the results kept
    again = carom("sweep", "rebound", "--out", out)
    assert again.returncode == 2
    assert "already exists" in again.stderr
    assert (out / "results.csv").is_file()


def test_failed_points_exit_1_with_the_table_written(tmp_path: Path) -> None:
    path = write_sweep(tmp_path / "in", '"gas.count" = [15, 200]', head="seeds = [3]")
    done = carom("sweep", path, "--out", tmp_path / "out", "--workers", "1", "--no-plots")
    assert done.returncode == 1
    assert "2 runs (2 points x 1 seed) on 1 worker" in done.stdout
    assert "1 failed" in done.stdout
    lines = (tmp_path / "out" / "results.csv").read_text().splitlines()
    assert lines[1].split(",")[3] == "ok"
    assert lines[2].split(",")[3] == "failed"


def test_mistakes_exit_2_without_a_traceback(tmp_path: Path) -> None:
    good = write_sweep(tmp_path / "good", '"gas.count" = [15]')
    bad = write_sweep(tmp_path / "bad", '"gas.count" = [15]', head='observables = ["entropy"]')
    cases = [
        (["sweep", bad, "--out", tmp_path / "o1"], "'entropy' is not an observable"),
        (["sweep", "no-such-sweep", "--out", tmp_path / "o2"], "eos-3d"),
        (
            ["sweep", good, "--out", tmp_path / "o3", "--workers", "2", "--scheduler", "x:1"],
            "give one of them",
        ),
        (["sweep", good, "--out", tmp_path / "o4", "--resume"], "nothing to resume"),
        (["sweep", good, "--out", tmp_path / "o5", "--workers", "0"], "--workers must be"),
        (
            ["sweep", good, "--out", tmp_path / "o6", "--scheduler", "tcp://127.0.0.1:9"],
            "cannot reach the Dask scheduler",
        ),
    ]
    for args, words in cases:
        done = carom(*args)
        assert done.returncode == 2, (args, done.stderr)
        assert words in done.stderr
        assert "Traceback" not in done.stderr
        assert done.stderr.startswith("carom: error:")
    for k in (1, 2, 3, 5, 6):
        assert not (tmp_path / f"o{k}").exists()  # refused before anything was written
