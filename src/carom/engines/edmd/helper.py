"""The compile helper of a cold start (:mod:`carom.engines.edmd.aside`), run as
``python -m carom.engines.edmd.helper [--gravity] [--spins]``: it builds a two-sphere engine
of the caller's kind and samples it, which compiles the engine's build kernels into the shared
cache while the caller compiles the event loop."""

from __future__ import annotations

import sys

from carom.engines.edmd.aside import two_spheres
from carom.engines.edmd.driver import EdmdEngine
from carom.engines.edmd.settings import EdmdSettings

__all__ = ["main"]


def main() -> None:
    """The helper: build a two-sphere engine and sample it (compiling the build kernels), under
    gravity if called with ``--gravity``, one sphere spinning with ``--spins``."""
    flags = sys.argv[1:]
    bodies, env = two_spheres("--gravity" in flags, "--spins" in flags)
    EdmdEngine(bodies, env, EdmdSettings(), 0.0).sample()


if __name__ == "__main__":
    main()
