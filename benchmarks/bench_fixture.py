"""The pytest plugin's per-test master beside rostest's per-file cost, a roscore start-up.

Ours: the setup plus teardown of the ``ros_master`` fixture, as pytest times them, over a
generated suite of tests that each take a fresh master (median; the first test, which also
starts the API's loop, is reported in the note). Theirs: ``roscore`` from launch until its
master answers ``getSystemState`` (what rostest waits for before a test file's first test).
"""

from __future__ import annotations

import json
import statistics
import subprocess
import sys
import tempfile
import time
import xmlrpc.client
from pathlib import Path

from benchmarks.common import Result, free_port, have, ros_env, start, stop

#: Tests in the generated suite, each with a master of its own.
TESTS = 40
#: roscore launches timed.
ROSCORE_RUNS = 5
GOAL = 0.1

_SUITE = f"""
import pytest

@pytest.mark.parametrize("i", range({TESTS}))
def test_fresh_master(i, ros_master):
    assert ros_master.uri
"""

_TIMER = """
import json, os

DURATIONS = []

def pytest_runtest_logreport(report):
    if report.when in ("setup", "teardown"):
        DURATIONS.append((report.nodeid, report.when, report.duration))

def pytest_sessionfinish(session):
    with open(os.environ["FIXTURE_TIMES"], "w") as f:
        json.dump(DURATIONS, f)
"""


def _fixture_seconds() -> tuple[float, float]:
    """Median and first setup+teardown of ``ros_master``, from a pytest run."""
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        (folder / "test_suite.py").write_text(_SUITE)
        (folder / "conftest.py").write_text(_TIMER)
        times = folder / "times.json"
        env = ros_env("http://127.0.0.1:9/")
        env["FIXTURE_TIMES"] = str(times)
        subprocess.run(
            [sys.executable, "-m", "pytest", "-q", "-p", "no:cacheprovider", str(folder)],
            cwd=folder,
            env=env,
            check=True,
            stdout=subprocess.DEVNULL,
        )
        per_test: dict[str, float] = {}
        for nodeid, _, seconds in json.loads(times.read_text()):
            per_test[nodeid] = per_test.get(nodeid, 0.0) + seconds
    costs = list(per_test.values())
    return statistics.median(costs[1:]), costs[0]


def _roscore_seconds() -> float:
    """Median time from launching roscore until its master answers getSystemState."""
    samples = []
    for _ in range(ROSCORE_RUNS):
        port = free_port()
        uri = f"http://127.0.0.1:{port}/"
        began = time.perf_counter()
        proc = start(
            ["roscore", "-p", str(port)],
            ros_env(uri),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.DEVNULL,
        )
        try:
            proxy = xmlrpc.client.ServerProxy(uri)
            deadline = began + 30
            while True:
                try:
                    proxy.getSystemState("/bench")
                    break
                except OSError:
                    if time.perf_counter() > deadline:
                        raise RuntimeError("roscore did not answer") from None
                    time.sleep(0.01)
            samples.append(time.perf_counter() - began)
        finally:
            stop(proc)
    return statistics.median(samples)


def bench_fixture() -> list[Result]:
    ours, first = _fixture_seconds()
    theirs = _roscore_seconds() if have("roscore") else None
    return [
        Result(
            "ros_master fixture start+stop, per test",
            "ms",
            ours * 1e3,
            None if theirs is None else theirs * 1e3,
            f"<= {GOAL}x roscore start-up",
            None if theirs is None else ours <= GOAL * theirs,
            f"setup+teardown as pytest times them, median of {TESTS - 1} tests (the first,"
            f" which starts the API's loop: {first * 1e3:.1f} ms); roscore: launch until"
            f" getSystemState answers, median of {ROSCORE_RUNS}",
        )
    ]


BENCHMARKS = {"fixture": bench_fixture}
