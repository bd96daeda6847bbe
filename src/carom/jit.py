"""Where compiled kernels are cached, the one way kernel packages import their modules, and
helpers compiled for kernels only.

Compiled kernels are cached on disk, in a directory named by a hash of every source file of
the kernel packages (:data:`KERNEL_PACKAGES`). Numba's own cache keys a function on its own
file only, so editing a kernel it calls from another file (``geometry/toi.py`` under
``engines/edmd/loop.py``), or a constant it reads from one, would otherwise run stale machine
code. The directory is ``$NUMBA_CACHE_DIR/carom-<hash>`` if that variable is set, else
``$XDG_CACHE_HOME/carom/kernels-<hash>`` (default ``~/.cache``); a temporary directory is used
when neither is writable.

Numba picks a function's cache directory when it is decorated, so each kernel package's
``__init__`` imports its modules inside :func:`kernel_cache`.

**Helpers for kernels only** (:func:`kernel_only`). Numba gives every compiled function two
wrappers besides itself: one that unboxes Python arguments (for calls from Python) and one with
a C signature. Both are lowered, optimised and turned into machine code with it. A helper that
only compiled code calls needs neither: without them on the event loop's helpers, LLVM's share
of a cold ``carom run case-1`` on one CPU went from 13.1 to 10.0 s. Such a helper is compiled
without them (``no_cpython_wrapper``, ``no_cfunc_wrapper``) by a dispatcher
(:class:`KernelOnly`) that refuses a call from Python with a ``TypeError`` instead of jumping
to an entry point that does not exist. Call it from a jitted function; its Python source
stays at ``.py_func``.

**Leaf kernels** (:func:`leaf`). Numba counts references to the arrays a compiled function
holds, with atomic instructions, and where a function branches its optimiser often keeps the
counts it could have dropped: a call of a small helper taking three arrays cost 30 ns where
its arithmetic takes 2 (measured: the broad phase's pair test; in the exact path's islands
the counts took a quarter of the time). A kernel that allocates no array and returns none
needs no counting at all: compiled without Numba's runtime (:data:`NO_REFCOUNTING`, as the
event loop's kernels are), it takes the arrays its caller holds, which keeps them alive
through the call, and counts nothing.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import tempfile
from collections.abc import Callable, Iterator
from functools import cache
from pathlib import Path
from typing import Any, TypeVar, cast, overload

import numba
from numba.core.registry import CPUDispatcher

__all__ = [
    "KERNEL_PACKAGES",
    "NO_REFCOUNTING",
    "KernelOnly",
    "kernel_cache",
    "kernel_cache_dir",
    "kernel_only",
    "kernel_tag",
    "kernels_cached",
    "leaf",
    "usable_cpus",
]

#: Numba's option for a kernel compiled without reference counting (an internal flag; the remedy
#: Numba's developers give in numba#2345): :func:`leaf`, and the event loop's kernels
#: (:mod:`carom.engines.edmd.jitflags`)
NO_REFCOUNTING: dict[str, Any] = {"_nrt": False}

#: the packages that hold Numba kernels, or constants and functions a kernel reads
KERNEL_PACKAGES = ("engines", "geometry", "laws")

_config: Any = numba.config
_HERE = Path(__file__).resolve().parent


def kernel_sources(root: Path = _HERE) -> list[Path]:
    """Every source file of the kernel packages under ``root``, in a fixed order."""
    return sorted(p for name in KERNEL_PACKAGES for p in (root / name).rglob("*.py"))


def kernel_tag(root: Path = _HERE) -> str:
    """A hash of every kernel source file of the package at ``root`` (16 hex digits)."""
    digest = hashlib.sha256()
    for path in kernel_sources(root):
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:16]


@cache
def kernel_cache_dir() -> str:
    """The cache directory of carom's kernels (created if need be)."""
    tag = kernel_tag()
    user = os.environ.get("NUMBA_CACHE_DIR")
    if user:
        candidates = [os.path.join(user, f"carom-{tag}")]
    else:
        home = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        candidates = [os.path.join(home, "carom", f"kernels-{tag}")]
    candidates.append(os.path.join(tempfile.gettempdir(), f"carom-kernels-{tag}"))
    for candidate in candidates:
        try:
            os.makedirs(candidate, exist_ok=True)
        except OSError:
            continue
        if os.access(candidate, os.W_OK):
            return candidate
    return candidates[-1]


@contextlib.contextmanager
def kernel_cache() -> Iterator[None]:
    """Kernels decorated inside this block are cached in :func:`kernel_cache_dir`."""
    previous = _config.CACHE_DIR
    _config.CACHE_DIR = kernel_cache_dir()
    try:
        yield
    finally:
        _config.CACHE_DIR = previous


def kernels_cached() -> bool:
    """Whether the event loop's machine code is in the cache (else the first run compiles it,
    which takes 10 to 20 s once per install)."""
    return any(Path(kernel_cache_dir()).glob("*/loop.run_frames-*.nbi"))


_F = TypeVar("_F", bound=Callable[..., Any])


class KernelOnly(CPUDispatcher):
    """A dispatcher for a function compiled without entry points from Python
    (:func:`kernel_only`): it runs only inside compiled code, and a call from Python raises
    ``TypeError`` (there is nothing to jump to)."""

    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        name = f"{self.py_func.__module__}.{self.py_func.__qualname__}"
        raise TypeError(
            f"{name} runs only inside compiled kernels (it is compiled without an entry point "
            "from Python): call it from an @njit function, or run its Python source, "
            f"{name}.py_func"
        )


def kernel_only(**options: Any) -> Callable[[_F], _F]:
    """A decorator like ``numba.njit(cache=True, **options)`` for a helper that only compiled
    code calls: compiled without the wrappers a call from Python or C needs, by a
    :class:`KernelOnly` dispatcher. Without the JIT (``NUMBA_DISABLE_JIT=1``) it returns the
    function itself, as ``njit`` does."""
    no_wrappers = {"no_cpython_wrapper": True, "no_cfunc_wrapper": True}
    targetoptions = {**options, "nopython": True, **no_wrappers}

    def decorate(func: _F) -> _F:
        if _config.DISABLE_JIT:
            return func
        dispatcher = KernelOnly(py_func=func, locals={}, targetoptions=dict(targetoptions))
        dispatcher.enable_caching()
        return cast(_F, dispatcher)

    return decorate


@overload
def leaf(func: _F) -> _F: ...


@overload
def leaf(func: None = None, **options: Any) -> Callable[[_F], _F]: ...


def leaf(func: _F | None = None, **options: Any) -> _F | Callable[[_F], _F]:
    """``numba.njit(cache=True, **options)`` for a kernel that allocates no array (no
    ``np.empty``, no copy, no slice kept), returns none and calls only kernels like it:
    compiled without Numba's reference counting (module docstring), so a call from a loop
    costs what its arithmetic costs. ``@leaf`` or ``@leaf(fastmath=...)``. Without the JIT it
    returns the function itself."""
    settings: dict[str, Any] = {"cache": True, **options, **NO_REFCOUNTING}
    if func is None:
        return cast(Callable[[_F], _F], numba.njit(**settings))
    return cast(_F, numba.njit(**settings)(func))


def usable_cpus() -> int:
    """How many CPUs this process may run on (its affinity where the system has one, as on
    Linux; else every CPU)."""
    affinity = getattr(os, "sched_getaffinity", None)
    if affinity is not None:
        return len(affinity(0))
    return os.cpu_count() or 1
