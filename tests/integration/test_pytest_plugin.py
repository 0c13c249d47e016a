"""The pytest plugin, run by pytester: isolation between tests (in one process and under
pytest-xdist), the module marker, the helpers, recordings, processes, and failure reports."""

from __future__ import annotations

import json
import os

import pytest

# pytester's in-process runs forget the modules a run imported. asyncio's C half cannot be
# imported twice (a second asyncio's CancelledError is not the one its tasks raise), and the
# API's loop should be one per process: both are imported here, before any run.
import rostools._api.functions
import rostools.testing.helpers  # noqa: F401
from rostools.bag.formats.access import open_bag

pytest_plugins = ["pytester"]

#: Each test leaves a topic and a parameter behind, and checks it sees no one else's.
ISOLATION = """
import json, os, sys
import pytest
import rostools

def _check_and_leave(name, ros_master, ros_node):
    from rostools.rosgraph.masterapi import MasterProxy
    proxy = MasterProxy(ros_master.uri, "/check")
    topics = {t for t, _ in proxy.system_state()[0]}
    params = set(proxy.param_names())
    assert not {t for t in topics if t.startswith("/left_by_")}, topics
    assert not {p for p in params if p.startswith("/left_by_")}, params
    assert os.environ["ROS_MASTER_URI"] == ros_master.uri
    ros_node.publish(f"/left_by_{name}", {"data": name}, "std_msgs/String")
    rostools.set_param(f"/left_by_{name}", 1)
    assert rostools.get_param(f"/left_by_{name}") == 1
    # a master is known by its /run_id: its port may be handed out again once it has stopped
    row = [name, os.environ.get("PYTEST_XDIST_WORKER", "-"), rostools.get_param("/run_id")]
    with open(os.environ["SEEN_FILE"], "a") as f:
        f.write(json.dumps(row) + "\\n")

@pytest.mark.parametrize("name", ["a", "b", "c", "d"])
def test_isolated(name, ros_master, ros_node):
    _check_and_leave(name, ros_master, ros_node)
"""


def _seen(path: str) -> list[list[str]]:
    with open(path) as f:
        return [json.loads(line) for line in f]


def test_each_test_has_its_own_master(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    seen = pytester.path / "seen.jsonl"
    monkeypatch.setenv("SEEN_FILE", str(seen))
    before = os.environ.get("ROS_MASTER_URI")
    pytester.makepyfile(test_isolation=ISOLATION)
    pytester.runpytest_inprocess("-p", "no:cacheprovider").assert_outcomes(passed=4)
    assert len({run_id for _, _, run_id in _seen(str(seen))}) == 4
    assert os.environ.get("ROS_MASTER_URI") == before  # restored after each test


def test_isolation_holds_under_xdist(
    pytester: pytest.Pytester, monkeypatch: pytest.MonkeyPatch
) -> None:
    seen = pytester.path / "seen.jsonl"
    monkeypatch.setenv("SEEN_FILE", str(seen))
    pytester.makepyfile(test_isolation=ISOLATION)
    result = pytester.runpytest_subprocess("-p", "xdist", "-n", "2", "-p", "no:cacheprovider")
    result.assert_outcomes(passed=4)
    rows = _seen(str(seen))
    assert {worker for _, worker, _ in rows} == {"gw0", "gw1"}
    assert len({run_id for _, _, run_id in rows}) == 4


def test_the_module_marker_shares_one_master_and_helpers_measure(
    pytester: pytest.Pytester,
) -> None:
    pytester.makepyfile(
        test_shared="""
        import sys, threading, time
        import pytest
        import rostools
        from rostools.testing import assert_message, assert_topic_rate

        pytestmark = pytest.mark.ros_master(scope="module")
        URIS = []

        def test_first(ros_master):
            URIS.append(ros_master.uri)
            rostools.set_param("/shared", "yes")

        def test_second_sees_the_first(ros_master, ros_node, ros_record, ros_process):
            URIS.append(ros_master.uri)
            assert URIS[0] == URIS[1] and rostools.get_param("/shared") == "yes"
            recording = ros_record("/ticks")
            pub = ros_node.advertise("/ticks", "std_msgs/Int32")
            stop = threading.Event()

            def tick():
                # on a schedule, not sleep-after-publish: a loaded machine slows each
                # turn, and the rate must still hold on average
                i, due = 0, time.monotonic()
                while not stop.is_set():
                    pub.publish(data=i)
                    i += 1
                    due += 0.02
                    time.sleep(max(0.0, due - time.monotonic()))

            thread = threading.Thread(target=tick)
            thread.start()
            try:
                assert 40 <= assert_topic_rate("/ticks", 50, tolerance=0.2, within=5) <= 60
                with pytest.raises(AssertionError, match=r"published at .* Hz, expected 10 Hz"):
                    assert_topic_rate("/ticks", 10, tolerance=0.1, within=1.2)
                assert assert_message("/ticks", lambda m: m.data > 5, timeout=2).data > 5
            finally:
                stop.set()
                thread.join()
            bag = recording.stop()
            assert bag.name == "recording1.bag" and len(recording.messages()) > 20
            child = ros_process(
                [sys.executable, "-m", "rostools", "topic", "pub", "/num", "std_msgs/Int32", "7"],
                wait_for_topic="/num",
            )
            assert assert_message("/num", {"data": 7}, timeout=5).data == 7
            assert child.stop() == 0 and not child.running
        """
    )
    result = pytester.runpytest_inprocess("-p", "no:cacheprovider")
    result.assert_outcomes(passed=2)


def test_a_failure_report_shows_the_graph(pytester: pytest.Pytester) -> None:
    pytester.makepyfile(
        test_fails="""
        import sys
        from rostools.testing import assert_message

        def test_wrong_value(ros_master, ros_node, ros_process):
            ros_node.set_param("/gain", 2)
            ros_node.publish("/status", {"data": "ok"}, "std_msgs/String")
            ros_node.subscribe("/status")
            ros_process([sys.executable, "-c", "print('child says hi', flush=True); input()"])
            assert_message("/status", {"data": "ready"}, timeout=0.5)
        """
    )
    result = pytester.runpytest_inprocess("-p", "no:cacheprovider")
    result.assert_outcomes(failed=1)
    result.stdout.fnmatch_lines(
        [
            "*AssertionError: no message on /status matching the predicate within 0.5 s:"
            " 1 came, the last: std_msgs/String(data='ok'); publishers: [[]'/pytest_*'[]]",
            "*- ROS graph -*",
            "master: http://127.0.0.1:*/",
            "  /status [[]std_msgs/String[]]",
            "    publishers: /pytest_*",
            "parameters (4): /gain, /rosdistro, /rosversion, /run_id",
            "last message of each subscribed topic:",
            "  /status: std_msgs/String(data='ok')",
            "process * -c print('child says hi'*",
            "  | child says hi",
        ]
    )


def test_a_failure_writes_the_last_seconds_to_a_bag_named_in_the_report(
    pytester: pytest.Pytester,
) -> None:
    pytester.makepyfile(
        test_snap="""
        import pytest
        from rostools.testing import assert_message

        @pytest.mark.parametrize("fail", [False, True])
        def test_speed(ros_node, fail):
            pub = ros_node.advertise("/speed", "std_msgs/Float64")
            sub = ros_node.subscribe("/speed")
            pub.wait_for_subscribers(2, timeout=10)  # ours, and the snapshot recorder's
            for value in (1.0, 2.0, 3.0):
                pub.publish(data=value)
                sub.get(timeout=5)
            assert not fail, "too fast"
        """
    )
    result = pytester.runpytest_inprocess("-p", "no:cacheprovider", "--ros-snapshot", "5")
    result.assert_outcomes(passed=1, failed=1)
    result.stdout.fnmatch_lines(["*- ROS snapshot -*", "the last 5 s of the graph: *.bag"])
    folder = pytester.path / "ros-snapshots"
    (bag,) = folder.iterdir()  # only the failing test wrote one
    assert bag.name == "test_snap.py__test_speed_True_.bag"
    assert str(bag) in result.stdout.str()
    with open_bag(bag) as reader:
        assert [c.topic for c in reader.connections] == ["/speed"]
        assert reader.info().message_count == 3


def test_a_failing_helper_shows_the_tests_line_and_the_message(pytester: pytest.Pytester) -> None:
    # the defect: each failure printed some 30 lines of the helper's source before its message
    pytester.makepyfile(
        test_readable="""
        import sys
        from rostools.testing import assert_message

        def test_no_match(ros_node):
            ros_node.publish("/status", {"data": "ok"}, "std_msgs/String")
            assert_message("/status", {"data": "ready"}, timeout=0.5)

        def test_refused_by_the_master(ros_master):
            assert_message("/bad name", timeout=0.5)

        def test_a_process_that_ends(ros_process):
            ros_process([sys.executable, "-c", "print('bye')"], wait_for_node="/talker")
        """
    )
    result = pytester.runpytest_inprocess("-p", "no:cacheprovider")
    result.assert_outcomes(failed=3)
    result.stdout.fnmatch_lines(
        [
            '>       assert_message("/status", {"data": "ready"}, timeout=0.5)',
            "E       AssertionError: no message on /status matching the predicate within 0.5 s:*",
            "test_readable.py:6: AssertionError",
            '>       assert_message("/bad name", timeout=0.5)',
            "E       *MasterError: ERROR: parameter [[]topic[]] contains illegal chars",
            "test_readable.py:9: MasterError",
            '>       ros_process(*wait_for_node="/talker")',
            "E       AssertionError: * exited with 0 before node /talker; its output:",
            "E       bye",
            "test_readable.py:12: AssertionError",
        ]
    )
    internals = ("rostools/testing/", "rostools/_api/", "rostools/rosgraph/", "rostools/node/")
    shown = [line for line in result.outlines if any(part in line for part in internals)]
    assert not shown, shown
