"""Regression: ``make test`` failed under load with exit code 120 from ``carom cases`` whose
reader had gone away.

The reader closed the pipe after carom's last write had gone into Python's buffer but before
it reached the pipe: the write failed when the interpreter flushed standard output at exit,
outside the command's BrokenPipeError handler (exit code 120, "Exception ignored"). Whether
that happened depended on scheduling. Here the pipe's read end is closed before carom starts,
so every run takes the same path: each write that reaches the pipe fails, whether inside the
command (a large output) or at the final flush (an output smaller than the buffer). Without
PYTHONUNBUFFERED, the old code failed three of these four cases every time (all but the large
output).
"""

from __future__ import annotations

import os
import subprocess
import sys

import pytest


@pytest.mark.parametrize(
    "args",
    [
        ["cases"],  # about 9 KB: the buffer fills inside the command
        ["cases", "--brief"],  # under the 8 KB buffer: written only by the final flush
        ["scenes"],
        ["--version"],  # argparse prints and exits on its own
    ],
)
def test_a_reader_gone_before_carom_writes_is_not_an_error(args: list[str]) -> None:
    # block-buffered standard output, as in a user's shell (PYTHONUNBUFFERED would make every
    # print write at once, and hide the failure at exit)
    env = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}
    read_end, write_end = os.pipe()
    os.close(read_end)  # no reader, ever: EPIPE on the first write that reaches the pipe
    try:
        done = subprocess.run(
            [sys.executable, "-m", "carom", *args],
            stdout=write_end,
            stderr=subprocess.PIPE,
            stdin=subprocess.DEVNULL,
            timeout=120,
            text=True,
            env=env,
        )
    finally:
        os.close(write_end)
    assert done.returncode == 0, done.stderr
    assert done.stderr == ""
