"""Test configuration: reproducible hypothesis runs (same examples on every machine).

``CAROM_HYPOTHESIS=deep`` runs 3000 fresh random examples per property instead: a search for
new counter-examples, not part of CI.
"""

from __future__ import annotations

import os

import pytest
from hypothesis import HealthCheck, settings
from hypothesis.internal.conjecture import providers

# Hypothesis (6.131 on) also draws constants it finds in the source of every local module
# imported so far. Which modules those are depends on the order tests run in and on how
# pytest-xdist shares them out, so a derandomized test drew different examples in different
# runs: a latent counter-example showed up in one run and not the next. Drawing none keeps a
# test's examples a function of the test alone. (A private hook: if Hypothesis renames it,
# this fails loudly here rather than silently.)
assert callable(providers._get_local_constants), "Hypothesis moved its local constants"
providers._get_local_constants = lambda: providers.Constants()

JIT_DISABLED = os.environ.get("NUMBA_DISABLE_JIT", "0") not in ("", "0")


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    """Under NUMBA_DISABLE_JIT=1 (the kernels run as plain Python, for coverage) skip the runs
    of millions of collisions: they would take hours. The JIT run executes them."""
    if not JIT_DISABLED:
        return
    skip = pytest.mark.skip(reason="needs the JIT: millions of collisions in plain Python")
    for item in items:
        if "needs_jit" in item.keywords:
            item.add_marker(skip)


settings.register_profile(
    "carom",
    max_examples=300 if os.environ.get("CI") else 150,
    deadline=None,
    derandomize=True,  # bit-identical test runs: a failure seen once is seen every time
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.register_profile(
    "deep",
    max_examples=3000,
    deadline=None,
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.load_profile("deep" if os.environ.get("CAROM_HYPOTHESIS") == "deep" else "carom")
