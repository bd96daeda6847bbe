"""Regression: editing a kernel another kernel calls ran stale machine code from Numba's cache.

Numba keys a cached function on its own source file; edmd.py's cached code kept an old
toi.shell_exit_time after toi.py changed. The cache directory is now named by a hash of every
kernel file, so any edit to any of them starts a fresh cache.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import carom.core
from carom.core import kernel_cache_dir


def test_editing_any_kernel_file_changes_the_cache_directory(tmp_path: Path) -> None:
    copy = tmp_path / "core"
    shutil.copytree(
        Path(carom.core.__file__).parent, copy, ignore=shutil.ignore_patterns("__pycache__")
    )
    before = kernel_cache_dir(copy)
    assert before == kernel_cache_dir(copy)  # stable while nothing changes
    toi = copy / "toi.py"
    toi.write_text(toi.read_text() + "\n# an edit\n")
    assert kernel_cache_dir(copy) != before
