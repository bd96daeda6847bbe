"""A cold start: how long the first run on a fresh install spends compiling the event-driven
engine's kernels (issue 16, item 4: under 15 s).

Each trial runs ``carom run case-1`` (or ``--scene``) in a fresh process with an empty kernel
cache (its own ``NUMBA_CACHE_DIR``), and reads the seconds the command itself reports for
compiling or loading the kernels before the run ("kernels compiled or loaded in ... s"), and the
command's wall time (imports, the run and its outputs too; animation off). With ``--base``,
another carom source tree takes the same trials, alternating with this one, so that both see the
same minutes of a noisy machine; trials with the helper process off (``--one-core``: the command
pinned to one CPU) show what compiling costs without a second core.

Run:  python benchmarks/cold_start.py [--trials 3] [--base /tmp/base/src] [--one-core]
          [--scene bouncing-ball]

A scene without gravity compiles less than one with it (no parabolas or supports:
``Model.gravity``); case-1 has none, bouncing-ball has it.
"""

from __future__ import annotations

import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))

from edmd import record

HERE = Path(__file__).resolve().parent
SRC = HERE.parent / "src"
REPORTED = re.compile(r"kernels compiled or loaded in ([0-9.]+) s")


def trial(src: Path, one_core: bool, scene: str = "case-1") -> tuple[float, float]:
    """One cold ``carom run scene`` with the tree at ``src``: the compile seconds it reports,
    and its wall time [s]."""
    with tempfile.TemporaryDirectory() as cache, tempfile.TemporaryDirectory() as out:
        pin = ["taskset", "-c", "0"] if one_core else []
        command = [*pin, sys.executable, "-m", "carom", "run", scene, "--out", out]
        env = {**os.environ, "NUMBA_CACHE_DIR": cache, "PYTHONPATH": str(src)}
        began = time.perf_counter()
        done = subprocess.run(
            [*command, "--force", "--animation", "none"],
            capture_output=True,
            text=True,
            env=env,
            stdin=subprocess.DEVNULL,
            check=True,
        )
        wall = time.perf_counter() - began
    found = REPORTED.search(done.stdout)
    if found is None:
        raise SystemExit(f"carom run did not report its compile time:\n{done.stdout}")
    return float(found.group(1)), wall


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--trials", type=int, default=3)
    parser.add_argument("--base", type=Path, help="another carom tree's src/ to compare with")
    parser.add_argument("--one-core", action="store_true", help="also pinned to one CPU")
    parser.add_argument("--scene", default="case-1", help="the scene run (default case-1)")
    parser.add_argument("--no-record", action="store_true", help="do not append to RESULTS.md")
    args = parser.parse_args()

    trees = {"this tree": SRC} | ({"base": args.base} if args.base else {})
    modes = [False, True] if args.one_core else [False]
    results: dict[tuple[str, bool], list[tuple[float, float]]] = {}
    for k in range(args.trials):
        names = list(trees) if k % 2 == 0 else list(reversed(trees))
        for name in names:
            for one_core in modes:
                compile_s, wall = trial(trees[name], one_core, args.scene)
                results.setdefault((name, one_core), []).append((compile_s, wall))
                cores = "1 CPU" if one_core else "all CPUs"
                print(f"trial {k + 1}, {name}, {cores}: compile {compile_s:.1f} s, "
                      f"wall {wall:.1f} s", flush=True)  # fmt: skip
    lines = [
        "| tree | CPUs | compile, reported [s]: median (min-max) | wall [s]: median |",
        "|---|---|---|---|",
    ]
    for (name, one_core), runs in results.items():
        compiled = [c for c, _ in runs]
        lines.append(
            f"| {name} | {'1' if one_core else 'all'} | {statistics.median(compiled):.1f} "
            f"({min(compiled):.1f}-{max(compiled):.1f}) | "
            f"{statistics.median(w for _, w in runs):.1f} |"
        )
    body = "\n".join(lines) + "\n"
    print(body)
    if not args.no_record:
        record(
            f"Cold start: carom run {args.scene} with an empty kernel cache",
            body,
            (
                f"{args.trials} trials per row, each a fresh process and an empty "
                "NUMBA_CACHE_DIR, trees alternating; compile = the seconds carom run reports "
                "for compiling or loading the kernels; wall = the whole command, animation off",
                "target (issue 16, item 4): cold compile under 15 s"
                + (f"; base: {args.base}" if args.base else ""),
            ),
        )


if __name__ == "__main__":
    main()
