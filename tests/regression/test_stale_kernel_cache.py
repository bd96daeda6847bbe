"""Regression: editing a kernel another kernel calls ran stale machine code from Numba's cache.

Numba keys a cached function on its own source file; edmd.py's cached code kept an old
toi.shell_exit_time after toi.py changed. The cache directory is now named by a hash of every
file of the kernel packages, so any edit to any of them starts a fresh cache.
"""

from __future__ import annotations

import ast
import importlib
import pkgutil
import shutil
from pathlib import Path

import pytest

import carom
from carom.jit import KERNEL_PACKAGES, kernel_cache_dir, kernel_sources, kernel_tag

ROOT = Path(carom.__file__).parent


def test_editing_any_kernel_file_changes_the_cache_directory(tmp_path: Path) -> None:
    copy = tmp_path / "carom"
    shutil.copytree(ROOT, copy, ignore=shutil.ignore_patterns("__pycache__"))
    before = kernel_tag(copy)
    for source in kernel_sources(copy):
        text = source.read_text()
        source.write_text(text + "\n# an edit\n")
        assert kernel_tag(copy) != before, source
        source.write_text(text)
    assert kernel_tag(copy) == before


def test_every_kernel_lives_in_a_hashed_package() -> None:
    # a module that compiles kernels, or that a kernel module imports from, outside the hashed
    # packages would escape the hash: its edits would run stale machine code (compare/monitor.py
    # calls numba.njit on a self-contained kernel, which Numba's own cache keys correctly)
    hashed = set(kernel_sources(ROOT))
    for path in ROOT.rglob("*.py"):
        tree = ast.parse(path.read_text())
        names = {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}
        if "njit" in names:
            assert path in hashed, path
    for path in hashed:
        tree = ast.parse(path.read_text())
        if "njit" not in {n.id for n in ast.walk(tree) if isinstance(n, ast.Name)}:
            continue  # a driver or NumPy code beside the kernels: imports what it likes
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and (node.module or "").startswith("carom."):
                package = node.module.split(".")[1]  # type: ignore[union-attr]
                assert package in (*KERNEL_PACKAGES, "jit", "_inputs", "errors"), (
                    path,
                    node.module,
                )


@pytest.mark.needs_jit
def test_every_kernel_is_cached_in_the_hashed_directory() -> None:
    # Numba picks a kernel's cache directory when it is decorated: a kernel module imported
    # outside its package's kernel_cache() block (edmd/renumber.py and rigid3d/impacts.py
    # were, by their drivers), or a kernel decorated later (carom.collide's passes, made on
    # first use), was cached beside its source, keyed on its own file only
    from numba.core.dispatcher import Dispatcher

    from carom.laws import batch

    root = Path(kernel_cache_dir())
    seen = 0
    for package in KERNEL_PACKAGES:
        base = importlib.import_module(f"carom.{package}")
        for info in pkgutil.walk_packages(base.__path__, f"carom.{package}."):
            module = importlib.import_module(info.name)
            for name, value in vars(module).items():
                if isinstance(value, Dispatcher) and value.__module__ == module.__name__:
                    seen += 1
                    where = Path(value._cache._cache_path)
                    assert where.is_relative_to(root), (module.__name__, name, where)
    assert seen > 100  # every kernel module was found (232 kernels at the time of writing)
    for case in range(len(batch.CASES) + 1):
        where = Path(batch._make_pass(case)._cache._cache_path)
        assert where.is_relative_to(root), (case, where)
