"""Suite-wide test settings.

Hypothesis runs derandomized (the same examples on every machine and every run), without
per-example deadlines (the suite runs on loaded 2-core CI machines under several BLAS kernels).
``HYPOTHESIS_PROFILE=dev`` searches with fresh random examples instead.

Tests marked ``slow`` (reduced study runs of a minute or more) are skipped unless ``FDIKIT_SLOW=1``;
``.ci/run`` runs them once, after the kernel runs (``FDIKIT_SLOW=1 pytest -m slow``), so one suite run
stays within the 8-minute budget.
"""

import os

import pytest
from hypothesis import HealthCheck, settings


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: a reduced study run of a minute or more (run with FDIKIT_SLOW=1)")


def pytest_collection_modifyitems(config, items):
    if os.environ.get("FDIKIT_SLOW") == "1":
        return
    skip = pytest.mark.skip(reason="slow study run: set FDIKIT_SLOW=1 (.ci/run does, once)")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)

settings.register_profile(
    "ci", derandomize=True, deadline=None, print_blob=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
settings.register_profile("dev", deadline=None, max_examples=200)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))
