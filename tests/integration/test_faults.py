"""Peers that cannot be reached, and signals during shutdown, on ``rostools core``."""

from __future__ import annotations

import json
import os
import signal
import time
import xmlrpc.client
from pathlib import Path

from rostools.node.watch import SUBSCRIBER_CHECK_PERIOD
from tests.support.bagdata import recorded
from tests.support.env import run_cli
from tests.support.procs import free_port, start_cli, subscribers, wait_for


def register(master: str, method: str, node: str, topic: str, uri: str) -> None:
    with xmlrpc.client.ServerProxy(master) as proxy:
        code, message, _ = getattr(proxy, method)(node, topic, "std_msgs/String", uri)
        assert code == 1, message


def test_a_publisher_that_refuses_is_reported_once(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    # before: echo retried in silence and ended with "did not deliver"
    dead = f"http://127.0.0.1:{free_port()}/"
    register(rostools_master, "registerPublisher", "/ghost", "/haunted", dead)
    done = run_cli("topic", "echo", "/haunted", "--timeout", "3", env=cli_env, timeout=30)
    assert done.returncode == 5
    lines = [line for line in done.stderr.splitlines() if "cannot connect" in line]
    assert lines == [
        f"rostools: cannot connect to /ghost at {dead} (publisher of /haunted): connection "
        "refused at 127.0.0.1, a loopback address; set ROS_IP or ROS_HOSTNAME on that host to "
        "an address others reach it at"
    ], done.stderr
    streamed = run_cli("topic", "hz", "/haunted", "--timeout", "2.5", "-F", "json", env=cli_env)
    events = [json.loads(line) for line in streamed.stdout.splitlines()]
    assert [(e["event"], e["node"], e["uri"]) for e in events] == [
        ("peer_unreachable", "/ghost", dead)
    ]


def test_a_subscriber_that_never_connects_is_named(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    # before: a publisher whose subscribers could not reach it said nothing at all
    pub = start_cli("topic", "pub", "-r", "5", "/lonely", "std_msgs/String", "data: x", env=cli_env)
    try:
        deaf = f"http://127.0.0.1:{free_port()}/"
        register(rostools_master, "registerSubscriber", "/deaf", "/lonely", deaf)
        pub.expect("/deaf subscribes to /lonely", 20, stderr=True)  # after 3 s of silence
        # The time is the behaviour here: the next check comes and says nothing more.
        time.sleep(SUBSCRIBER_CHECK_PERIOD * 1.5)
        pub.signal(signal.SIGINT)
        _, err = pub.output()
    finally:
        pub.stop()
    assert (
        "rostools: /deaf subscribes to /lonely but has not contacted us in 3 s: it may not "
        "reach http://127.0.0.1:"
    ) in err, err
    assert err.count("/deaf subscribes") == 1


def test_a_second_sigint_during_shutdown_still_unregisters(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    # before: the second Ctrl-C interrupted the unregister call with a KeyboardInterrupt
    # traceback and left the node registered. The master is paused so that the second
    # signal lands while the unregister call waits.
    core_pid = int(xmlrpc.client.ServerProxy(rostools_master).getPid("/t")[2])
    echo = start_cli("topic", "echo", "/rosout", env=cli_env)
    try:
        wait_for(lambda: len(subscribers(rostools_master, "/rosout")) >= 2, 15, "echo subscribed")
        os.kill(core_pid, signal.SIGSTOP)
        try:
            # Nothing outside the process tells that its unregister call has begun, or that
            # the second signal has been taken; 0.3 s is ample for either.
            echo.signal(signal.SIGINT)
            time.sleep(0.3)
            echo.signal(signal.SIGINT)
            time.sleep(0.3)
        finally:
            os.kill(core_pid, signal.SIGCONT)
        assert echo.popen.wait(10) == 0
    finally:
        echo.stop()
    _, err = echo.output()
    assert "Traceback" not in err and "KeyboardInterrupt" not in err, err
    assert len(subscribers(rostools_master, "/rosout")) == 1  # only core's own /rosout is left


def test_sighup_finalises_a_recording(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    # an SSH session that drops sends SIGHUP; C++ rosbag leaves the file .active
    pub = start_cli("topic", "pub", "-r", "20", "/hup", "std_msgs/String", "data: x", env=cli_env)
    out = tmp_path / "hup.bag"
    rec = start_cli("bag", "record", "/hup", "-O", str(out), env=cli_env)
    try:
        wait_for(lambda: recorded(Path(f"{out}.active"), "/hup"), 15, "a message recorded")
        rec.signal(signal.SIGHUP)
        assert rec.popen.wait(10) == 0
    finally:
        rec.stop()
        pub.stop()
    assert out.exists() and not Path(f"{out}.active").exists()
    info = run_cli("bag", "info", str(out), "-F", "json", env=cli_env)
    assert info.returncode == 0 and json.loads(info.stdout)["messages"] > 0
