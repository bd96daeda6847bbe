"""Running a snippet of Python in a fresh process, for what only a new interpreter shows
(kernels compiled or loaded from the cache, counters that start at zero)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path
from typing import Any

from carom.engines.edmd import aside

ROOT = Path(__file__).resolve().parents[1]


def fresh_python(code: str, **env: str) -> Any:
    """Run ``code`` in a new interpreter on this checkout's sources, with ``env`` added to
    the environment and no compile helper started (it compiles what it needs itself); fail
    with its standard error unless it exits 0; return the JSON its standard output holds."""
    done = subprocess.run(
        [sys.executable, "-c", code],
        capture_output=True,
        text=True,
        env={**os.environ, "PYTHONPATH": str(ROOT / "src"), aside.HELPER_FLAG: "1", **env},
        stdin=subprocess.DEVNULL,
        check=False,
    )
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout)


def from_a_terminal(command: list[str]) -> list[str]:
    """``command`` (a Python program's argument list, ``sys.executable`` first) started as a
    terminal starts it, with Ctrl-C (SIGINT) at its default, however the test suite itself
    was started: a background shell (``make test &``, ``nohup``, a scheduler) starts its
    children ignoring SIGINT, and carom keeps an inherited SIG_IGN (POSIX's rule), so a test
    that sends SIGINT as a terminal would must undo it first."""
    assert command[0] == sys.executable
    restore = (
        "import os, signal, sys; signal.signal(signal.SIGINT, signal.SIG_DFL); "
        "os.execv(sys.executable, [sys.executable, *sys.argv[1:]])"
    )
    return [sys.executable, "-c", restore, *command[1:]]
