"""``rostools doctor`` on loopback: each check's verdict, exit code and JSON."""

from __future__ import annotations

import email.utils
import json
import time
import xmlrpc.client

import pytest

from rostools.master.server import MasterThread
from rostools.node import rpc as graph_xmlrpc
from rostools.rosgraph.hostcheck import Doctor
from tests.support.env import run_cli
from tests.support.procs import free_port


def by_name(checks: list[dict[str, object]]) -> dict[object, dict[str, object]]:
    return {c["name"]: c for c in checks}


def test_a_healthy_graph_passes(rostools_master: str, cli_env: dict[str, str]) -> None:
    done = run_cli("doctor", "-F", "json", env=cli_env)
    assert done.returncode == 0, done.stdout + done.stderr
    report = json.loads(done.stdout)
    checks = by_name(report["checks"])
    assert report["ok"] and checks["master"]["status"] == "ok"
    assert checks["nodes"]["verdict"] == "the one node answers from here"
    assert checks["clock"]["status"] == "ok"  # rostools core sends a Date header


def test_dead_nodes_and_a_stopped_clock_fail(rostools_master: str, cli_env: dict[str, str]) -> None:
    proxy = xmlrpc.client.ServerProxy(rostools_master)
    dead = f"http://127.0.0.1:{free_port()}/"
    proxy.registerPublisher("/dead", "/t", "std_msgs/String", dead)
    proxy.setParam("/t", "/use_sim_time", True)
    done = run_cli("doctor", env=cli_env)
    assert done.returncode == 4  # the first failure: a node that cannot be reached
    lines = done.stdout.splitlines()
    assert lines[2] == (
        f"FAIL  nodes      1 of 2 nodes cannot be reached from here: /dead at {dead} "
        "(connection refused at 127.0.0.1, a loopback address) (hint: set ROS_IP or "
        "ROS_HOSTNAME on their hosts; 'rostools node cleanup' purges nodes that died)"
    )
    assert lines[3].startswith("FAIL  sim time   /use_sim_time is true but nothing publishes")
    assert done.stderr == "rostools: doctor: 2 of 5 checks failed (nodes, sim time)\n"


def test_no_master_is_exit_4(cli_env: dict[str, str]) -> None:
    done = run_cli("doctor", env=cli_env)  # cli_env points at the discard port
    assert done.returncode == 4
    assert done.stdout.startswith("FAIL  master     cannot reach the master at http://127.0.0.1:9")
    assert "SKIP  nodes      needs the master" in done.stdout


def test_a_skewed_clock_is_measured(monkeypatch: pytest.MonkeyPatch) -> None:
    ahead = email.utils.formatdate(time.time() + 30, usegmt=True)
    monkeypatch.setattr(graph_xmlrpc, "http_date", lambda: ahead)
    with MasterThread() as master:
        clock = Doctor(master.uri, env={"ROS_IP": "127.0.0.1"}).run()[-1]
    assert clock.status == "fail" and clock.exit_code == 1
    assert clock.verdict == "clocks differ from ours: the master by +30 s"
