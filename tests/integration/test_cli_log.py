"""``rostools log`` on ``rostools core`` alone: echo through its /rosout, and our own nodes'
logger services (``node/loggers.py``), with completion of their loggers."""

from __future__ import annotations

import json
import logging
from collections.abc import Iterator

import pytest

from rostools.node import loggers
from tests.support.env import run_cli
from tests.support.procs import Proc, start_cli, wait_for


def _served(env: dict[str, str], node: str) -> bool:
    found = run_cli("service", "list", node, env=env).stdout.split()
    return f"{node}/set_logger_level" in found


@pytest.fixture
def rt_node(rostools_master: str, cli_env: dict[str, str]) -> Iterator[str]:
    """A rostools node (``topic pub``) named /rt_pub, once its logger services are up."""
    proc = start_cli(
        "topic",
        "pub",
        "/rt_topic",
        "std_msgs/Empty",
        "{}",
        "-r",
        "2",
        "__name:=rt_pub",
        env=cli_env,
    )
    try:
        wait_for(lambda: _served(cli_env, "/rt_pub"), 30, "/rt_pub's logger services")
        yield "/rt_pub"
    finally:
        proc.stop()


def test_our_nodes_list_get_and_set_their_python_loggers(
    rt_node: str, cli_env: dict[str, str]
) -> None:
    listed = run_cli("log", "list", rt_node, env=cli_env)
    assert listed.returncode == 0, listed.stderr
    names = listed.stdout.split()
    assert names[0] == "rostools" and "rostools.node.node" in names
    got = run_cli("log", "get", rt_node, "rostools.node.node", env=cli_env)
    assert got.stdout == "WARN\n"  # Python's default: the root logger's WARNING
    done = run_cli("log", "set", rt_node, "rostools.node.node", "debug", env=cli_env)
    assert done.returncode == 0, done.stderr
    assert run_cli("log", "get", rt_node, "rostools.node.node", env=cli_env).stdout == "DEBUG\n"
    every = run_cli("log", "get", rt_node, "-F", "json", env=cli_env)
    levels = {d["logger"]: d["level"] for d in json.loads(every.stdout)}
    assert levels["rostools.node.node"] == "DEBUG" and levels["rostools"] == "WARN"


def test_our_nodes_refuse_a_logger_they_do_not_have(rt_node: str, cli_env: dict[str, str]) -> None:
    """A peer may not make us create loggers: one line, exit 1, and nothing created."""
    got = run_cli("log", "set", rt_node, "not.ours", "info", env=cli_env)
    assert got.returncode == 1 and got.stderr.count("\n") == 1, got.stderr
    assert "no logger not.ours" in got.stderr
    assert "not.ours" not in run_cli("log", "list", rt_node, env=cli_env).stdout


def test_completion_offers_a_nodes_loggers_and_the_levels(
    rt_node: str, cli_env: dict[str, str]
) -> None:
    env = {**cli_env, "ROSTOOLS_COMPLETE_DEADLINE": "30"}  # a busy machine: not what is tested
    words = ["rostools", "log", "set", rt_node, ""]
    got = run_cli("__complete", "bash", "4", *words, env=env).stdout.splitlines()
    assert "rostools.node.node\tWARN" in got
    words = ["rostools", "log", "set", rt_node, "rostools", ""]
    got = run_cli("__complete", "bash", "5", *words, env=env).stdout.split()
    assert got == ["debug", "info", "warn", "error", "fatal"]


LOG = (
    "{{header: {{stamp: {{secs: 5, nsecs: 0}}}}, level: {level}, name: '{name}', "
    "msg: '{msg}', file: f.py, function: fn, line: 7, topics: [/a]}}"
)


def test_echo_follows_rosout_agg_of_our_core(rostools_master: str, cli_env: dict[str, str]) -> None:
    """Messages published on /rosout reach echo through core's /rosout_agg, filtered."""
    echo = start_cli("log", "echo", "-l", "info", "--grep", "keep", "-F", "json", env=cli_env)
    pubs: list[Proc] = []
    try:
        wait_for(lambda: _subscribed(cli_env, "/rosout_agg"), 30, "echo on /rosout_agg")
        for level, name, msg in [
            (1, "/a", "keep debug"),
            (4, "/b", "keep warn"),
            (8, "/c", "drop error"),
        ]:
            text = LOG.format(level=level, name=name, msg=msg)
            pubs.append(
                start_cli(
                    "topic", "pub", "/rosout", "rosgraph_msgs/Log", text, "-r", "5", env=cli_env
                )
            )
        line = json.loads(echo.expect('"msg":"keep', 30))
        assert line["name"] == "/b" and line["level"] == 4 and line["topics"] == ["/a"]
        assert line["header"]["stamp"] == {"secs": 5, "nsecs": 0} and line["line"] == 7
        for _ in range(5):  # more of them, and never the filtered ones
            assert '"/b"' in echo.expect('"msg":', 30)
    finally:
        for pub in pubs:
            pub.stop()
        echo.stop()


def _subscribed(env: dict[str, str], topic: str) -> bool:
    info = run_cli("topic", "info", topic, env=env).stdout
    return "rostools_log" in info


def test_echo_timeout_with_a_count_is_exit_5(rostools_master: str, cli_env: dict[str, str]) -> None:
    got = run_cli("log", "echo", "-n", "1", "--timeout", "1", env=cli_env)
    assert got.returncode == 5 and got.stderr.count("\n") == 1, got.stderr


def test_logger_bytes_round_trip_and_match_the_type_table() -> None:
    """The struct codec agrees with the type store's md5sums and its own reading."""
    from rostools.msgs.codec import Codec
    from rostools.msgs.store import BuiltinSource, TypeStore

    store = TypeStore([BuiltinSource()])
    assert store.srv_md5(loggers.GET_LOGGERS[0]) == loggers.GET_LOGGERS[1]
    assert store.srv_md5(loggers.SET_LOGGER_LEVEL[0]) == loggers.SET_LOGGER_LEVEL[1]
    pairs = [("ros", "INFO"), ("ros.x", "debug")]
    data = loggers.encode_loggers(pairs)
    codec = Codec.of(store)
    decoded = codec.decode("roscpp/GetLoggersResponse", data)
    assert [(lg.name, lg.level) for lg in decoded.loggers] == pairs
    assert loggers.decode_loggers(data) == pairs
    assert loggers.decode_set(loggers.encode_set("a.b", "warn")) == ("a.b", "warn")
    with pytest.raises(loggers.LoggerBytesError):
        loggers.decode_loggers(b"\xff\xff\xff\x7f")  # 2**31 loggers in 4 bytes: refused at once
    logging.getLogger("rostools.test_only")  # a logger of ours appears in the list
    assert "rostools.test_only" in dict(loggers.our_loggers())
