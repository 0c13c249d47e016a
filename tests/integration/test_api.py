"""The Python API end to end, in this process: masters, nodes, topics, services, params, bags."""

from __future__ import annotations

import asyncio
import os
import sys
import threading
import time
from collections.abc import Iterator
from pathlib import Path

import pytest

import rostools
from rostools import (
    AsyncNode,
    Master,
    Node,
    NotFoundError,
    RostoolsError,
    ServiceError,
    TimeoutExpired,
    UsageError,
    message,
    message_class,
)


@pytest.fixture(scope="module")
def master() -> Iterator[Master]:
    with Master() as m:
        yield m


@pytest.fixture
def env_master(master: Master, monkeypatch: pytest.MonkeyPatch) -> Iterator[Master]:
    """The module's master as ``ROS_MASTER_URI``; the default node is closed afterwards."""
    from rostools._api import functions

    monkeypatch.setenv("ROS_MASTER_URI", master.uri)
    yield master
    functions.reset()


def test_messages_are_built_as_topic_pub_reads_values() -> None:
    String = message_class("std_msgs/String")  # noqa: N806 - named as genpy names it
    assert message("std_msgs/String", {"data": "a"}) == String(data="a")
    assert message("std_msgs/String", "data: a") == String("a")
    assert message("std_msgs/String", data="a") == String(data="a")
    twist = message("geometry_msgs/Twist", {"linear": {"x": 1.5}})
    assert (twist.linear.x, twist.angular.z) == (1.5, 0.0)
    with pytest.raises(UsageError, match=r"field linear\.x: expected a number"):
        message("geometry_msgs/Twist", {"linear": {"x": "fast"}})
    with pytest.raises(NotFoundError, match="unknown message type nope/Nope"):
        message("nope/Nope")


def test_topics_between_two_nodes(master: Master) -> None:
    with Node("talker", master.uri) as talker, Node("listener", master.uri) as listener:
        got: list[object] = []
        done = threading.Event()

        def on_message(msg: object) -> None:
            # a callback runs on a thread of its own: the blocking API works from it
            got.append((msg, listener.get_param("/rosdistro")))
            done.set()

        with_callback = listener.subscribe("/chatter", on_message)
        iterated = listener.subscribe("/chatter", msg_type="std_msgs/String")
        pub = talker.advertise("/chatter", "std_msgs/String")
        pub.wait_for_subscribers(1, timeout=5)
        pub.publish(data="one")
        pub.publish({"data": "two"})
        assert [iterated.get(5).data, iterated.get(5).data] == ["one", "two"]  # type: ignore[attr-defined]
        assert done.wait(5)
        assert got[0] == (message("std_msgs/String", data="one"), "noetic\n")
        assert listener.last_messages() == {"/chatter": message("std_msgs/String", data="two")}
        with pytest.raises(UsageError, match="expected a string"):
            pub.publish(data=3)
        with pytest.raises(TimeoutExpired, match=r"no message on /chatter within 0\.1 s"):
            iterated.get(0.1)
        with_callback.close()
        iterated.close()
        assert listener.last_messages() == {}  # the last subscription unsubscribed the node


def test_module_functions_follow_ros_master_uri(env_master: Master, tmp_path: Path) -> None:
    rostools.set_param("/robot", {"speed": 2, "name": "r2"})
    assert rostools.get_param("/robot/speed") == 2
    assert rostools.get_param("/missing", "fallback") == "fallback"
    with pytest.raises(NotFoundError, match="parameter /missing is not set"):
        rostools.get_param("/missing")
    rostools.delete_param("/robot/name")
    assert not rostools.has_param("/robot/name")
    rostools.publish("/latched", message("std_msgs/Int32", data=7))
    assert rostools.wait_for_message("/latched", timeout=5) == message("std_msgs/Int32", data=7)
    with pytest.raises(UsageError, match="the type of /unknown is not known"):
        rostools.publish("/unknown", {"data": 1})
    with Master() as other:  # a new master: the functions start a node there
        os.environ["ROS_MASTER_URI"] = other.uri
        assert not rostools.has_param("/robot")
        os.environ["ROS_MASTER_URI"] = env_master.uri
    assert rostools.get_param("/robot") == {"speed": 2}


def test_services_and_their_failures(env_master: Master) -> None:
    def handle(request: object) -> dict[str, object]:
        if not request.data:  # type: ignore[attr-defined]
            raise ValueError("refused")
        return {"success": True, "message": "on"}

    with Node("server", env_master.uri) as server:
        server.advertise_service("/switch", "std_srvs/SetBool", handle)
        rostools.wait_for_service("/switch", timeout=5)
        answer = rostools.call_service("/switch", data=True)
        assert (answer.success, answer.message) == (True, "on")  # type: ignore[attr-defined]
        with pytest.raises(ServiceError, match="refused"):
            rostools.call_service("/switch", {"data": False}, "std_srvs/SetBool")
    with pytest.raises(NotFoundError, match="unknown service /switch"):
        rostools.call_service("/switch", data=True, timeout=2)
    for reply in ("first", "restarted"):  # a server restarted elsewhere is found again
        with Node(f"server_{reply}", env_master.uri) as again:
            again.advertise_service(
                "/switch", "std_srvs/SetBool", lambda r, m=reply: {"message": m}
            )
            answer = rostools.call_service("/switch", data=True, timeout=5)
            assert answer.message == reply  # type: ignore[attr-defined]


@pytest.mark.parametrize("name", ["run.bag", "run.mcap"])
def test_record_and_read_back(env_master: Master, tmp_path: Path, name: str) -> None:
    with Node("talker", env_master.uri) as talker:
        pub = talker.advertise("/count", "std_msgs/Int32")
        with rostools.record(["/count"], tmp_path / name) as rec:
            pub.wait_for_subscribers(1, timeout=5)
            for i in range(5):
                pub.publish(data=i)
            deadline = time.monotonic() + 5
            while rec.counts.get("/count", 0) < 5 and time.monotonic() < deadline:
                time.sleep(0.01)
    read = list(rostools.read_bag(rec.path))
    assert [(m.topic, m.message.data) for m in read] == [("/count", i) for i in range(5)]  # type: ignore[attr-defined]
    assert read[0].message == message("std_msgs/Int32", data=0)
    assert read[0].time.to_sec() > 0


def test_a_snapshot_makes_its_folder(
    env_master: Master, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    # the example of docs/api.md, where logs/ did not exist: the write failed
    monkeypatch.chdir(tmp_path)
    with Node("talker", env_master.uri) as talker:
        pub = talker.advertise("/status", "std_msgs/String")
        with rostools.snapshot(folder="logs/today", duration=60) as snap:
            pub.wait_for_subscribers(1, timeout=5)
            pub.publish(data="ok")
            deadline = time.monotonic() + 10
            while True:  # until the message is buffered
                try:
                    written = snap.write("crash.bag")
                    break
                except RostoolsError as err:
                    assert "no messages buffered" in str(err) and time.monotonic() < deadline
                    time.sleep(0.01)
    assert written == Path("logs/today/crash.bag")
    assert [m.message.data for m in rostools.read_bag(written)] == ["ok"]  # type: ignore[attr-defined]
    with pytest.raises(UsageError, match=r"^cannot write /proc/logs: No such file or directory$"):
        rostools.snapshot(folder="/proc/logs").start()


def test_the_async_form_on_the_callers_loop() -> None:
    async def main() -> list[str]:
        async with Master() as m, AsyncNode("a", m.uri) as node:
            sub = await node.subscribe("/words")
            await node.publish("/words", {"data": "hi"}, "std_msgs/String")
            await node.set_param("~private", 1)
            assert await node.get_param(f"{node.name}/private") == 1
            seen = []
            async for msg in sub:
                seen.append(msg.data)  # type: ignore[attr-defined]
                break
            return seen

    assert asyncio.run(main()) == ["hi"]


def test_a_blocking_call_on_the_api_loop_is_refused(master: Master) -> None:
    from rostools._api import loop

    async def inside() -> None:
        Node("x", master.uri)

    with pytest.raises(UsageError, match="would wait forever"):
        loop.run(inside())


def test_a_process_that_exits_fails_the_wait_at_once(env_master: Master) -> None:
    from rostools.testing import start_process

    began = time.monotonic()
    code = "import sys; print('no ROS here'); sys.exit(3)"
    with pytest.raises(AssertionError, match=r"exited with 3 before node /x;.*\n.*no ROS here"):
        start_process([sys.executable, "-c", code], wait_for_node="/x", timeout=30)
    assert time.monotonic() - began < 10


def test_a_process_leaves_no_temporary_log(env_master: Master) -> None:
    """Without a log of the caller's, the output goes to a temporary file, removed at the stop
    (one was left in the temporary folder by every such process); the output is kept."""
    from rostools.testing import RosProcess

    proc = RosProcess([sys.executable, "-c", "print('said')"])
    log = proc.log
    proc.popen.wait(30)
    assert log.exists()
    proc.stop()
    assert not log.exists()
    assert proc.output() == "said\n" and proc.tail() == "said"


def test_a_callback_gets_a_message_that_arrives_as_it_subscribes(
    master: Master, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A latched message may arrive before ``subscribe`` returns: the callback still gets it."""
    from rostools._api import loop

    run = loop.run

    def slow_run(coro: object, timeout: float | None = None) -> object:
        result = run(coro, timeout)  # type: ignore[arg-type]
        time.sleep(0.3)  # the latched message lands here, before subscribe returns
        return result

    with Node("latcher", master.uri) as talker, Node("late", master.uri) as listener:
        pub = talker.advertise("/early", "std_msgs/Int32", latch=True)
        pub.publish(message("std_msgs/Int32", data=3))
        got = threading.Event()
        monkeypatch.setattr(loop, "run", slow_run)
        listener.subscribe("/early", lambda msg: got.set())
        monkeypatch.setattr(loop, "run", run)
        assert got.wait(5)
