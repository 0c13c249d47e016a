"""The fuzz suites' shared budget: a fixed seed and a bounded number of cases in CI.

``ROSTOOLS_FUZZ_EXAMPLES`` raises the number of cases per test for long runs
(``python -m benchmarks.fuzz --hours N``); the seed stays fixed unless ``ROSTOOLS_FUZZ_SEED``
changes it, so a failure found once is found again.
"""

from __future__ import annotations

import os

from hypothesis import HealthCheck, settings

#: Cases per fuzz test.
EXAMPLES = int(os.environ.get("ROSTOOLS_FUZZ_EXAMPLES", "150"))
SEED = int(os.environ.get("ROSTOOLS_FUZZ_SEED", "20261123"))

settings.register_profile(
    "fuzz",
    max_examples=EXAMPLES,
    deadline=None,
    derandomize=False,
    database=None,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large],
)
FUZZ = settings.get_profile("fuzz")
