"""Sweeps on a local Dask cluster of two workers: every row is the point run alone, a failing
point is recorded and the others go on, the table is the same bit for bit whatever the number
of workers, and a crash, a killed worker or Ctrl-C loses nothing done."""

from __future__ import annotations

import csv
import os
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from carom.errors import CaromError
from carom.sweeps import SweepReport, load_sweep, sweep
from carom.sweeps.observe import run_point
from tests.processes import from_a_terminal
from tests.sweeps.helpers import GAS, write_sweep

# 20 spheres of radius 0.5 in a 5 m box fit up to packing 0.3; 200 do not: that point fails
# when its scene is built (a run-time failure, not a bad file)
PARAMETERS = '"gas.count" = [15, 20, 25, 200]'


def rows(folder: Path) -> list[dict[str, str]]:
    with (folder / "results.csv").open(newline="") as handle:
        return list(csv.DictReader(handle))


@pytest.fixture(scope="module")
def reference(tmp_path_factory: pytest.TempPathFactory) -> tuple[Path, Path, SweepReport]:
    """The sweep run once on two workers: its file, its folder and its report."""
    folder = tmp_path_factory.mktemp("reference")
    path = write_sweep(folder / "in", PARAMETERS)
    report = sweep(path, folder / "out", workers=2, plots=False)
    return path, folder / "out", report


def test_every_row_is_its_point_run_alone(reference: tuple[Path, Path, SweepReport]) -> None:
    path, out, report = reference
    assert (report.runs, report.ran, report.failed, report.workers) == (8, 8, 2, 2)
    spec = load_sweep(path)
    table = rows(out)
    assert [(r["point"], r["seed"]) for r in table] == [
        (str(p.index), str(p.seed)) for p in spec.points()
    ]  # one row per point and seed, in order
    for point, row in zip(spec.points(), table, strict=True):
        alone = run_point(spec.task(point))
        assert row["status"] == alone["status"]
        for name in spec.observables:
            value = alone["values"].get(name)
            assert row[name] == ("" if value is None else repr(value))  # to the bit
        theory = alone["theory"].get("compressibility")
        assert row["compressibility_theory"] == ("" if theory is None else repr(theory))


def test_a_failing_point_is_recorded_and_the_others_run(
    reference: tuple[Path, Path, SweepReport],
) -> None:
    _, out, _ = reference
    table = rows(out)
    failed = [r for r in table if r["status"] == "failed"]
    assert [r["gas.0.count"] for r in failed] == ["200", "200"]
    assert all("packing" in r["message"] and r["compressibility"] == "" for r in failed)
    ok = [r for r in table if r["status"] == "ok"]
    assert len(ok) == 6
    assert all(float(r["compressibility"]) > 1.0 and r["message"] == "" for r in ok)
    with (out / "tasks.csv").open() as handle:
        timings = list(csv.DictReader(handle))
    assert len(timings) == 8  # every task ran once
    assert len({t["worker"] for t in timings}) == 2  # on both workers


@pytest.mark.needs_jit
def test_workers_reuse_their_kernels(reference: tuple[Path, Path, SweepReport]) -> None:
    # Each worker loads the kernels once, before the runs: no run compiles or loads any
    _, out, _ = reference
    with (out / "tasks.csv").open() as handle:
        loaded = [row["kernels_loaded"] for row in csv.DictReader(handle)]
    assert loaded == ["0"] * 8
    # the count is real: a fresh process loads kernels for its first run, none for its second
    code = (
        "from carom.sweeps import load_sweep\n"
        "from carom.sweeps.observe import run_point\n"
        f"spec = load_sweep({str(reference[0])!r})\n"
        "p = spec.points()[0]\n"
        "t = dict(index=0, seed=1, scene=p.scene, source=str(spec.scene_path), until=1.0,\n"
        "         warmup=0.0, observables=['temperature'])\n"
        "print(run_point(t)['kernels_loaded'], run_point(t)['kernels_loaded'])\n"
    )
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=300
    )
    first, second = map(int, done.stdout.split())
    assert first > 0
    assert second == 0


def test_parquet_holds_the_same_table(reference: tuple[Path, Path, SweepReport]) -> None:
    pq = pytest.importorskip("pyarrow.parquet")
    _, out, _ = reference
    table = pq.read_table(out / "results.parquet").to_pylist()
    expected = rows(out)
    assert len(table) == len(expected)
    for got, row in zip(table, expected, strict=True):
        assert got["point"] == int(row["point"])
        assert got["status"] == row["status"]
        for name in ("compressibility", "collision_rate", "compressibility_theory"):
            assert got[name] == (None if row[name] == "" else float(row[name]))


def test_the_same_table_whatever_the_number_of_workers(
    reference: tuple[Path, Path, SweepReport], tmp_path: Path
) -> None:
    path, out, _ = reference
    report = sweep(path, tmp_path / "one", workers=1, plots=False)
    assert report.workers == 1
    assert (tmp_path / "one" / "results.csv").read_bytes() == (out / "results.csv").read_bytes()


def test_resume_after_a_crash_runs_only_what_is_missing(
    reference: tuple[Path, Path, SweepReport], tmp_path: Path
) -> None:
    path, out, _ = reference
    crashed = tmp_path / "crashed"
    shutil.copytree(out, crashed)
    lines = (out / "results.csv").read_text().splitlines(keepends=True)
    # a crash after three rows, in the middle of writing the fourth
    (crashed / "results.csv").write_text("".join(lines[:4]) + lines[4][:9])
    report = sweep(path, crashed, resume=True, workers=2, plots=False)
    assert report.ran == 8 - 3
    assert (crashed / "results.csv").read_bytes() == (out / "results.csv").read_bytes()
    # nothing left to do: no cluster, the same table
    again = sweep(path, crashed, resume=True, plots=False)
    assert (again.ran, again.workers) == (2, 2)  # the failed point's two seeds are retried
    assert (crashed / "results.csv").read_bytes() == (out / "results.csv").read_bytes()


def test_resume_refuses_another_sweep(
    reference: tuple[Path, Path, SweepReport], tmp_path: Path
) -> None:
    _, out, _ = reference
    other = write_sweep(tmp_path / "in", '"gas.count" = [15, 20]')
    with pytest.raises(CaromError, match="holds another sweep"):
        sweep(other, out, resume=True, plots=False)
    with pytest.raises(CaromError, match="nothing to resume"):
        sweep(other, tmp_path / "empty", resume=True, plots=False)
    with pytest.raises(CaromError, match="already exists and is not empty"):
        sweep(other, out, plots=False)
    with pytest.raises(CaromError, match="give one of them"):
        sweep(other, tmp_path / "x", workers=2, scheduler="tcp://127.0.0.1:1", plots=False)


# -- interruptions: tasks of about a second, so that a kill lands mid-task ------------------

SLOW_GAS = GAS.replace("count = 20", "count = 600").replace("[5.0, 5.0, 5.0]", "[11.0, 11.0, 11.0]")
SLOW = '"gas.temperature" = [1.0, 1.5, 2.0, 2.5, 3.0, 3.5]'
SLOW_HEAD = "until = 12.0\nwarmup = 0.0\nseeds = [1]"


@pytest.mark.slow  # (a Dask cluster of two workers, one killed)
@pytest.mark.needs_jit
def test_a_worker_killed_mid_sweep_loses_nothing(tmp_path: Path) -> None:
    from distributed import Client, LocalCluster

    path = write_sweep(tmp_path / "in", SLOW, head=SLOW_HEAD, scene=SLOW_GAS)
    expected = sweep(path, tmp_path / "expected", workers=2, plots=False)
    assert expected.failed == 0
    with (
        LocalCluster(n_workers=2, threads_per_worker=1, dashboard_address=":0") as cluster,
        Client(cluster) as client,
    ):
        done: list[SweepReport] = []
        runner = threading.Thread(
            target=lambda: done.append(
                sweep(path, tmp_path / "out", scheduler=cluster.scheduler_address, plots=False)
            )
        )
        runner.start()
        results = tmp_path / "out" / "results.csv"
        deadline = time.monotonic() + 120
        while time.monotonic() < deadline and len(_lines(results)) < 2:
            time.sleep(0.05)  # the first row is in: both workers are busy with the next
        busy = {w: keys for w, keys in client.processing().items() if keys}
        assert busy, "no worker was running a point when the kill came"
        victim = sorted(busy)[0]
        pid = client.run(os.getpid, workers=[victim])[victim]
        os.kill(pid, signal.SIGKILL)  # its point goes back to the scheduler
        runner.join(timeout=300)
        assert done, "the sweep did not finish"
    report = done[0]
    assert (report.ran, report.failed) == (6, 0)
    got = (tmp_path / "out" / "results.csv").read_bytes()
    assert got == (tmp_path / "expected" / "results.csv").read_bytes()  # nothing lost or twice


def _lines(path: Path) -> list[str]:
    return path.read_text().splitlines() if path.exists() else []


@pytest.mark.slow  # (a Dask cluster of two workers, stopped and resumed)
@pytest.mark.needs_jit
@pytest.mark.parametrize(
    ("how", "code"),
    [
        ("ctrl-c", 130),  # SIGINT to the whole process group, as a terminal sends it
        ("sigterm", 143),  # SIGTERM to the command alone, as timeout sends it
    ],
)
def test_a_stop_keeps_what_finished_and_resume_completes_it(
    tmp_path: Path, how: str, code: int
) -> None:
    path = write_sweep(tmp_path / "in", SLOW, head=SLOW_HEAD, scene=SLOW_GAS)
    expected = sweep(path, tmp_path / "expected", workers=2, plots=False)
    command = [sys.executable, "-m", "carom", "sweep", str(path), "--out", str(tmp_path / "out")]
    command += ["--workers", "2", "--no-plots"]
    process = subprocess.Popen(
        from_a_terminal(command),
        stdin=subprocess.DEVNULL,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        start_new_session=True,
    )
    results = tmp_path / "out" / "results.csv"
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline and len(_lines(results)) < 3:
        time.sleep(0.05)
    if how == "ctrl-c":
        os.killpg(process.pid, signal.SIGINT)  # the workers get it too, and ignore it
    else:
        process.send_signal(signal.SIGTERM)
    _, err = process.communicate(timeout=120)
    assert process.returncode == code, err
    assert "--resume" in err
    assert "Traceback" not in err
    assert "ERROR" not in err  # (no worker died noisily of the same signal)
    kept = len(_lines(results)) - 1
    assert 2 <= kept < 6  # what finished is kept; the rest is not
    report = sweep(path, tmp_path / "out", resume=True, workers=2, plots=False)
    assert report.ran == 6 - kept
    assert results.read_bytes() == (tmp_path / "expected" / "results.csv").read_bytes()
    assert expected.failed == 0


def test_no_more_local_workers_than_runs(tmp_path: Path) -> None:
    path = write_sweep(tmp_path / "in", '"gas.count" = [15]', head="seeds = [4]")
    report = sweep(path, tmp_path / "out", workers=2, plots=False)
    assert (report.runs, report.workers) == (1, 1)


def test_a_sweep_runs_beside_a_cluster_already_on_the_dashboard_port(tmp_path: Path) -> None:
    # regression: the local cluster's HTTP server took Dask's default port 8787; with it taken
    # (a dashboard, a second sweep, a parallel test run) Dask warned and, warnings being
    # errors here, the cluster failed to start (seen under make test on two workers)
    import socket

    taken = socket.socket()
    try:
        taken.bind(("", 8787))
        taken.listen()
    except OSError:
        pass  # already taken by someone else: the case itself
    try:
        path = write_sweep(tmp_path / "in", '"gas.count" = [15]', head="seeds = [4]")
        report = sweep(path, tmp_path / "out", workers=1, plots=False)
    finally:
        taken.close()
    assert (report.runs, report.failed) == (1, 0)
