"""How busy this machine is, measured once per run: the factor that a test's deadlines scale by.

A test checks behaviour, not speed (speed lives in ``benchmarks/``), but a test must still
give up on a peer that never answers. Its deadline is generous on a quiet machine, and grows
with the load: two CPU hogs on two cores, or other test runs beside this one. The factor is
measured in the first pytest process (``tests/conftest.py``) and handed to xdist's workers
and to child processes through ``ROSTOOLS_TEST_LOAD``, which a user may also set.
"""

from __future__ import annotations

import os
import time

ENV = "ROSTOOLS_TEST_LOAD"
#: How long the CPU share is sampled.
SAMPLE = 0.2
#: Past this, a machine is too busy for any deadline to mean much.
MOST = 8.0


def measure() -> float:
    """The load factor now: at least 1, more when a busy thread gets less than a whole CPU,
    or when more processes wait to run than there are CPUs."""
    cpus = len(os.sched_getaffinity(0))
    started, cpu_started = time.monotonic(), time.thread_time()
    while time.monotonic() - started < SAMPLE:
        pass
    share = (time.thread_time() - cpu_started) / (time.monotonic() - started)
    queued = os.getloadavg()[0] / cpus
    return min(MOST, max(1.0, 1 / max(share, 1 / MOST), queued))


def factor() -> float:
    """This run's load factor (measured on first use, then kept in the environment)."""
    if (given := os.environ.get(ENV)) is None:
        given = f"{measure():.2f}"
        os.environ[ENV] = given
    return float(given)


def scaled(seconds: float) -> float:
    """``seconds`` on a quiet machine, as a deadline on this one now."""
    return seconds * factor()
