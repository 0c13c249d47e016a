"""The pytest plugin (entry point ``pytest11``): a master per test, nodes, recordings, processes.

Fixtures:

- ``ros_master``: a fresh master on a free port for each test (or one per module with
  ``pytestmark = pytest.mark.ros_master(scope="module")``). ``ROS_MASTER_URI`` points at
  it for the test and the processes it starts, and ``ROS_IP`` is loopback unless
  ``ROS_IP`` or ``ROS_HOSTNAME`` is set; both are restored afterwards.
- ``ros_node``: a ``rostools.Node`` on that master.
- ``ros_record``: ``ros_record("/a", "/b")`` starts recording those topics into the test's
  ``tmp_path``; ``.stop()`` hands back the bag's path (it stops by itself at the end).
- ``ros_process``: ``ros_process(["/usr/bin/python3", "talker.py"], wait_for_node="/talker")``
  starts a command under the master; it is stopped by its PID at the end.

When a test fails, its report gets a "ROS graph" section: topics, services, nodes,
parameters, the last message of each subscribed topic, and the tail of each process's output.
With ``--ros-snapshot SECONDS``, a snapshot recorder buffers every topic during each test that
uses ``ros_master``; when the test fails, the last SECONDS go to a bag beside the test report
(``--ros-snapshot-dir``; default: the JUnit XML's folder, else ``ros-snapshots``), and the
report's "ROS snapshot" section names it.

Every pytest run imports this module, so it imports nothing heavy: the fixtures load the API
when a test asks for them.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pytest

if TYPE_CHECKING:
    from rostools._api.bags import Recording
    from rostools._api.blocking import Node
    from rostools._api.bridges import WebBridge
    from rostools._api.master import Master
    from rostools._api.snapshots import SnapshotRecorder
    from rostools.testing.process import RosProcess

MARKER = "ros_master"
#: How often the test's snapshot recorder asks its master for new topics (s).
SNAPSHOT_POLL = 0.1


class _TestState:
    """What the fixtures set up for one test, for its failure report."""

    def __init__(self, master_uri: str) -> None:
        self.master_uri = master_uri
        self.nodes: list[Node] = []
        self.processes: list[RosProcess] = []
        self.recordings: list[Recording] = []
        self.snapshot: SnapshotRecorder | None = None


_STATE = pytest.StashKey[_TestState]()


def pytest_addoption(parser: pytest.Parser) -> None:
    """``--ros-snapshot SECONDS`` and ``--ros-snapshot-dir DIR``."""
    group = parser.getgroup("rostools")
    group.addoption(
        "--ros-snapshot",
        type=float,
        default=None,
        metavar="SECONDS",
        help="buffer every topic during each ros_master test; on a failure, write the last "
        "SECONDS to a bag and name it in the report",
    )
    group.addoption(
        "--ros-snapshot-dir",
        default=None,
        metavar="DIR",
        help="where --ros-snapshot bags go (default: the --junitxml folder, else ros-snapshots)",
    )


def _snapshot_folder(config: pytest.Config) -> Path:
    given = config.getoption("ros_snapshot_dir")
    if given:
        return Path(given)
    xml = getattr(config.option, "xmlpath", None)
    return Path(xml).resolve().parent if xml else config.invocation_params.dir / "ros-snapshots"


def _start_snapshot(config: pytest.Config, master_uri: str) -> SnapshotRecorder | None:
    seconds = config.getoption("ros_snapshot")
    if not seconds:
        return None
    from rostools._api.snapshots import SnapshotRecorder

    return SnapshotRecorder(
        None, _snapshot_folder(config), master_uri, duration=seconds, poll_period=SNAPSHOT_POLL
    ).start()


def pytest_configure(config: pytest.Config) -> None:
    """Declare the marker."""
    config.addinivalue_line(
        "markers",
        f'{MARKER}(scope="module"): the tests of a module share one master (rostools plugin)',
    )


def _shared(request: pytest.FixtureRequest) -> bool:
    marker = request.node.get_closest_marker(MARKER)
    if marker is None:
        return False
    scope = marker.kwargs.get("scope", marker.args[0] if marker.args else "function")
    if scope not in ("function", "module"):
        raise pytest.UsageError(f'{MARKER}(scope=...) is "function" or "module", not {scope!r}')
    return bool(scope == "module")


@pytest.fixture(scope="module")
def _ros_module_master() -> Iterator[Master]:
    from rostools._api.master import Master

    master = Master().start()
    try:
        yield master
    finally:
        master.stop()


@pytest.fixture
def ros_master(request: pytest.FixtureRequest) -> Iterator[Master]:
    """A master on a free port for this test, with ``ROS_MASTER_URI`` pointing at it."""
    from rostools._api import functions
    from rostools._api.master import Master

    shared = _shared(request)
    master: Master = request.getfixturevalue("_ros_module_master") if shared else Master().start()
    saved = {k: os.environ.get(k) for k in ("ROS_MASTER_URI", "ROS_IP")}
    os.environ["ROS_MASTER_URI"] = master.uri
    if not os.environ.get("ROS_IP") and not os.environ.get("ROS_HOSTNAME"):
        os.environ["ROS_IP"] = "127.0.0.1"  # the test's graph stays on loopback
    state = request.node.stash[_STATE] = _TestState(master.uri)
    from rostools.testing import helpers

    helpers.last_seen.clear()
    try:
        state.snapshot = _start_snapshot(request.config, master.uri)
        yield master
    finally:
        if state.snapshot is not None:
            state.snapshot.stop()
        functions.reset()  # the default node lived on this master
        for key, value in saved.items():
            if value is None:
                os.environ.pop(key, None)
            else:
                os.environ[key] = value
        if not shared:
            master.stop()


@pytest.fixture
def ros_node(ros_master: Master, request: pytest.FixtureRequest) -> Iterator[Node]:
    """A node on the test's master, closed after the test."""
    from rostools._api.blocking import Node

    node = Node("pytest", ros_master.uri)
    request.node.stash[_STATE].nodes.append(node)
    try:
        yield node
    finally:
        node.close()


@pytest.fixture
def ros_record(
    ros_master: Master, tmp_path: Path, request: pytest.FixtureRequest
) -> Iterator[Callable[..., Recording]]:
    """``ros_record("/a", "/b", name="run.bag")``: a started recording in ``tmp_path``."""
    from rostools._api.bags import Recording
    from rostools.testing.readable import readable

    started: list[Recording] = request.node.stash[_STATE].recordings

    @readable
    def start(*topics: str, name: str | None = None) -> Recording:
        __tracebackhide__ = True
        path = tmp_path / (name or f"recording{len(started) + 1}.bag")
        recording = Recording(list(topics), path, ros_master.uri).start()
        started.append(recording)
        return recording

    try:
        yield start
    finally:
        for recording in started:
            recording.stop()


@pytest.fixture
def ros_bridge(ros_master: Master) -> Iterator[WebBridge]:
    """``rostools bridge`` of the test's master, on a free loopback port (``ros_bridge.url``).

    It serves every topic, and stops after the test.
    """
    from rostools._api.bridges import bridge

    with bridge(master_uri=ros_master.uri) as running:
        yield running


@pytest.fixture
def ros_process(
    ros_master: Master, tmp_path: Path, request: pytest.FixtureRequest
) -> Iterator[Callable[..., RosProcess]]:
    """``ros_process(argv, wait_for_node=..., wait_for_topic=...)``: a command under the master.

    Its ``ROS_HOME`` and logs are kept in ``tmp_path``; it is stopped by its PID at the end.
    """
    from rostools.testing.process import RosProcess
    from rostools.testing.readable import readable

    started: list[RosProcess] = request.node.stash[_STATE].processes

    @readable
    def start(
        argv: list[str],
        *,
        env: dict[str, str] | None = None,
        cwd: str | Path | None = None,
        wait_for_node: str | None = None,
        wait_for_topic: str | None = None,
        timeout: float = 10.0,
    ) -> RosProcess:
        __tracebackhide__ = True
        child = dict(os.environ)
        home = tmp_path / "ros_home"
        child.setdefault("ROS_HOME", str(home))
        child.setdefault("ROS_LOG_DIR", str(home / "log"))
        child.update(env or {})
        log = tmp_path / f"process{len(started) + 1}.log"
        proc = RosProcess(argv, child, cwd, log)
        started.append(proc)
        if wait_for_node is not None:
            proc.wait_for_node(wait_for_node, timeout)
        if wait_for_topic is not None:
            proc.wait_for_topic(wait_for_topic, timeout)
        return proc

    try:
        yield start
    finally:
        for proc in reversed(started):
            proc.stop()


@pytest.hookimpl(wrapper=True)
def pytest_runtest_makereport(item: pytest.Item, call: pytest.CallInfo[None]) -> Any:
    """A failed test that used ``ros_master`` gets the graph in its report."""
    report = yield
    state = item.stash.get(_STATE, None)
    if state is not None and report.failed and report.when in ("setup", "call"):
        try:
            report.sections.append(("ROS graph", _describe(state)))
        except Exception as err:  # noqa: BLE001 - a report must not fail the run
            report.sections.append(("ROS graph", f"(could not be read: {err!r})"))
        if state.snapshot is not None and state.snapshot.running:
            line = _write_snapshot(item, report, state.snapshot)
            report.sections.append(("ROS snapshot", line))
    return report


def _write_snapshot(item: pytest.Item, report: pytest.TestReport, snap: SnapshotRecorder) -> str:
    """Write the test's last seconds beside the report; the line that names the bag."""
    seconds = item.config.getoption("ros_snapshot")
    name = "".join(c if c.isalnum() or c in "-." else "_" for c in item.nodeid) + ".bag"
    try:
        path = snap.write(name, before=seconds)
    except Exception as err:  # noqa: BLE001 - a report must not fail the run
        return f"(no snapshot: {err})"
    report.user_properties.append(("ros_snapshot", str(path)))
    return f"the last {seconds:g} s of the graph: {path}"


def _describe(state: _TestState) -> str:
    from rostools._api import functions
    from rostools.testing.helpers import last_seen
    from rostools.testing.report import graph_report

    last: dict[str, Any] = dict(last_seen)
    for node in [*state.nodes, *functions.default_nodes()]:
        if not node.closed:
            for topic, msg in node.last_messages().items():
                if msg is not None or topic not in last:
                    last[topic] = msg
    extra: list[str] = []
    for rec in state.recordings:
        extra.append(f"recording: {rec.path} ({'recording' if rec.running else 'stopped'})")
    for proc in state.processes:
        status = "running" if proc.running else f"exited with {proc.returncode}"
        extra.append(f"process {proc.pid} {' '.join(proc.argv)} ({status}); output tail:")
        extra.extend(f"  | {line}" for line in proc.tail().splitlines())
    return graph_report(state.master_uri, last, extra)
