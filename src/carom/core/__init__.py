"""Numba kernels: plain floats and arrays in, plain floats and arrays out. No I/O, no objects.

Compiled kernels are cached on disk, in a directory named by a hash of every kernel source
file. Numba's own cache keys a function on its own file only, so editing a kernel it calls
from another file (``toi.py`` under ``edmd.py``) would otherwise run stale machine code.
The directory is ``$NUMBA_CACHE_DIR/carom-<hash>`` if that variable is set, else
``$XDG_CACHE_HOME/carom/kernels-<hash>`` (default ``~/.cache``); a temporary directory is used
when neither is writable.
"""

from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path
from typing import Any

import numba

_config: Any = numba.config


def kernel_cache_dir(here: Path | None = None) -> str:
    """The cache directory for the kernels in ``here`` (default: this package)."""
    here = Path(__file__).resolve().parent if here is None else here
    digest = hashlib.sha256()
    for path in sorted(here.glob("*.py")):
        digest.update(path.name.encode())
        digest.update(path.read_bytes())
    tag = digest.hexdigest()[:16]
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


_previous = _config.CACHE_DIR
_config.CACHE_DIR = kernel_cache_dir()
try:
    # every kernel module is decorated here, while the cache directory points at ours
    from carom.core import calendar, edmd, laws, neighbors, prefetch, toi  # noqa: F401
finally:
    _config.CACHE_DIR = _previous
