"""Running the carom command as a user would: a subprocess, no standard input."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path


def carom(
    *args: str | Path, cwd: Path | None = None, **env: str
) -> subprocess.CompletedProcess[str]:
    """``python -m carom ARGS`` with matplotlib off-screen and ``env`` added to the
    environment; its exit code and output (text)."""
    return subprocess.run(
        [sys.executable, "-m", "carom", *map(str, args)],
        capture_output=True,
        text=True,
        cwd=cwd,
        stdin=subprocess.DEVNULL,
        timeout=300,
        env={**os.environ, "MPLBACKEND": "Agg", **env},
    )
