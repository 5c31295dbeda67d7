"""Settings for every test process (headless and window)."""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

# Hypothesis fails an example that runs longer than 200 ms (its default deadline) and a
# test whose data is slow to generate (the too_slow health check): pass conditions on the
# wall clock, which a loaded machine can break. Correctness is what the tests check.
# In CI the examples are derived from each test's name (derandomize), so a run is
# repeatable; elsewhere they are random, so that every local run explores new inputs.
settings.register_profile(
    "mirrorlab",
    deadline=None,
    suppress_health_check=[HealthCheck.too_slow],
    derandomize=bool(os.environ.get("CI")),
)
settings.load_profile("mirrorlab")
