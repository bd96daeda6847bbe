"""Test configuration: reproducible hypothesis runs (same examples on every machine)."""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

settings.register_profile(
    "carom",
    max_examples=300 if os.environ.get("CI") else 150,
    deadline=None,
    derandomize=True,  # bit-identical test runs: a failure seen once is seen every time
    database=None,
    suppress_health_check=[HealthCheck.too_slow],
)
settings.load_profile("carom")
