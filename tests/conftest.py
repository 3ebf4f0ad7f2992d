"""Suite-wide test settings.

Hypothesis runs derandomized (the same examples on every machine and every run), without
per-example deadlines (the suite runs on loaded 2-core CI machines under several BLAS kernels).
``HYPOTHESIS_PROFILE=dev`` searches with fresh random examples instead.
"""

import os

from hypothesis import HealthCheck, settings

settings.register_profile(
    "ci", derandomize=True, deadline=None, print_blob=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
settings.register_profile("dev", deadline=None, max_examples=200)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci"))
