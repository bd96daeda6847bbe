"""Throughput of ``carom.collide`` on a batch of pairs: pairs per second, 2D and 3D, per law.

Each configuration runs in a fresh process on the same seeded inputs (10^6 pairs by default),
best and median of ``--repeats`` calls after a warm-up call. Three ways are timed:

* ``fresh``: every call allocates its result, as a plain ``carom.collide(...)`` does;
* ``out``: every call writes over the previous result (``out=``), so no new memory is touched;
* ``1 thread``: ``fresh`` with Numba limited to one thread.

With ``--base SRC`` the same calls are timed on another carom source tree, in every way,
each cell right after this tree's, for the ratios: ``git worktree add /tmp/base REV`` then
``python benchmarks/collide.py --base /tmp/base/src``.

Run:  python benchmarks/collide.py [--pairs 1000000] [--repeats 7] [--base SRC] [--record]
"""

from __future__ import annotations

import argparse
import datetime as dt
import json
import os
import subprocess
import sys
from pathlib import Path

from edmd import commit, machine  # benchmarks/edmd.py, beside this file

HERE = Path(__file__).resolve().parent
SRC = HERE.parent / "src"
LAWS = ("smooth", "rough", "walton")

SNIPPET = """
import json, statistics, sys, time
import numpy as np
dim, law, mode = int(sys.argv[1]), sys.argv[2], sys.argv[5]
n, repeats = int(sys.argv[3]), int(sys.argv[4])
if mode == "1 thread":
    import numba
    numba.set_num_threads(1)
import carom
rng = np.random.default_rng(20261126)
normal = rng.normal(size=(n, dim))
normal /= np.linalg.norm(normal, axis=1)[:, None]
radius1, radius2 = rng.uniform(0.05, 1.0, n), rng.uniform(0.05, 1.0, n)
x2 = rng.normal(size=(n, dim))
args = dict(
    x1=x2 + (radius1 + radius2)[:, None] * normal, v1=rng.normal(size=(n, dim)),
    m1=rng.uniform(0.5, 2.0, n), x2=x2, v2=rng.normal(size=(n, dim)), m2=rng.uniform(0.5, 2.0, n),
    e=rng.uniform(0.5, 1.0, n),
)
if law == "rough":
    args.update(beta=rng.uniform(-1.0, 1.0, n), radius1=radius1, radius2=radius2)
if law == "walton":
    args.update(friction=rng.uniform(0.1, 0.5, n), beta0=0.4, radius1=radius1, radius2=radius2)
result = carom.collide(**args)  # warm-up: kernels loaded, memory touched once
times = []
for _ in range(repeats):
    start = time.perf_counter()
    if mode == "out":
        carom.collide(**args, out=result)
    else:
        carom.collide(**args)
    times.append(time.perf_counter() - start)
print(json.dumps({"best": n / min(times), "median": n / statistics.median(times)}))
"""


def _time(src: Path, dim: int, law: str, n: int, repeats: int, mode: str) -> dict[str, float]:
    env = {**os.environ, "PYTHONPATH": str(src)}
    out = subprocess.run(
        [sys.executable, "-c", SNIPPET, str(dim), law, str(n), str(repeats), mode],
        capture_output=True,
        text=True,
        env=env,
        check=True,
    )
    return json.loads(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--pairs", type=int, default=1_000_000)
    parser.add_argument("--repeats", type=int, default=7)
    parser.add_argument("--base", type=Path, help="another carom source tree, timed alongside")
    parser.add_argument("--record", action="store_true", help="append to benchmarks/RESULTS.md")
    a = parser.parse_args()
    modes = ["fresh", "out", "1 thread"]
    header = ["dim", "law"] + [f"{m} [pairs/s]" for m in modes]
    if a.base:
        header += [f"base {m} [pairs/s]" for m in modes] + [f"{m} / base" for m in modes]
    rows = []
    for dim in (2, 3):
        for law in LAWS:
            got, base = {}, {}
            for m in modes:
                got[m] = _time(SRC, dim, law, a.pairs, a.repeats, m)["median"]
                if a.base:
                    base[m] = _time(a.base, dim, law, a.pairs, a.repeats, m)["median"]
            row = [str(dim), law] + [f"{got[m]:.3g}" for m in modes]
            if a.base:
                row += [f"{base[m]:.3g}" for m in modes]
                row += [f"{got[m] / base[m]:.2f}" for m in modes]
            rows.append(row)
            print(" | ".join(row), flush=True)
    table = "\n".join(
        ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
        + ["| " + " | ".join(r) + " |" for r in rows]
    )
    print(table)
    if a.record:
        when = dt.datetime.now(dt.UTC).strftime("%Y-%m-%d %H:%M UTC")
        base = f" --base {a.base}" if a.base else ""
        text = (
            f"\n## carom.collide on a batch: pairs per second, {when}\n\n"
            f"- machine: {machine()}\n- commit: {commit()}\n"
            f"- command: `python benchmarks/collide.py --pairs {a.pairs} --repeats {a.repeats}"
            f"{base} --record`\n"
            f"- {a.pairs:,} pairs, median of {a.repeats} calls in a fresh process per cell; "
            f"fresh: a new result each call; out: written over the last one (out=); "
            f"1 thread: fresh with Numba on one thread\n\n{table}\n"
        )
        with open(HERE / "RESULTS.md", "a") as fh:
            fh.write(text)


if __name__ == "__main__":
    main()
