"""The master: XML-RPC calls per second and memory, beside the real rosmaster in one run."""

from __future__ import annotations

import os
import signal
import socket
import statistics
import subprocess
import sys
import time
import xmlrpc.client
from pathlib import Path

from benchmarks.common import BENCH_VENV, Result, masters, status_kb

LOAD = Path(__file__).with_name("xmlrpc_load.py")
SECONDS = 4.0


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        port: int = s.getsockname()[1]
        return port


def _start(argv: list[str], port: int, env: dict[str, str]) -> subprocess.Popen[bytes]:
    proc = subprocess.Popen(
        argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, start_new_session=True
    )
    proxy = xmlrpc.client.ServerProxy(f"http://127.0.0.1:{port}/")
    deadline = time.monotonic() + 20
    while time.monotonic() < deadline:
        try:
            proxy.getPid("/bench")
            return proc
        except OSError:
            time.sleep(0.05)
    _stop(proc)
    raise RuntimeError(f"{argv[0]} did not start")


def _stop(proc: subprocess.Popen[bytes]) -> None:
    for sig in (signal.SIGINT, signal.SIGKILL):
        if proc.poll() is None:
            os.killpg(proc.pid, sig)
            try:
                proc.wait(5)
            except subprocess.TimeoutExpired:
                continue


def _populate(port: int, topics: int, services: int) -> None:
    proxy = xmlrpc.client.ServerProxy(f"http://127.0.0.1:{port}/")
    multi = xmlrpc.client.MultiCall(proxy)
    for i in range(topics):
        node = f"/node{i % 10}"
        api = f"http://127.0.0.1:{30000 + i % 10}/"
        multi.registerPublisher(node, f"/topic{i}", "std_msgs/String", api)
        multi.registerSubscriber(node, f"/topic{(i + 1) % topics}", "std_msgs/String", api)
    for i in range(services):
        multi.registerService(
            f"/node{i % 10}",
            f"/srv{i}",
            f"rosrpc://127.0.0.1:{31000 + i}",
            f"http://127.0.0.1:{30000 + i % 10}/",
        )
    multi()


def _rate(port: int, clients: int, workload: str) -> float:
    procs = [
        subprocess.Popen(
            [sys.executable, str(LOAD), str(port), str(SECONDS), f"/c{i}", workload],
            stdout=subprocess.PIPE,
            text=True,
        )
        for i in range(clients)
    ]
    total = sum(int(p.communicate()[0].strip()) for p in procs)
    return total / SECONDS


#: Rounds of every set-up, each master in turn: the machine is shared and its load drifts.
ROUNDS = 3
#: (workload, clients). ``register`` with 1 client is issue 14's set-up: one keep-alive
#: client, pre-encoded registerPublisher/unregisterPublisher pairs, back to back.
SETUPS = [("state", 1), ("state", 4), ("register", 1), ("register", 4)]


def bench_master_rates() -> list[Result]:
    env = {k: v for k, v in os.environ.items() if not k.startswith("ROS")}
    env["ROS_HOME"] = str(BENCH_VENV.parent / "build" / "ros_home")
    samples: dict[tuple[str, str, int], list[float]] = {}
    rss: dict[str, int] = {}
    ports: dict[str, int] = {}
    procs: dict[str, subprocess.Popen[bytes]] = {}
    try:
        # Both masters run at once and take turns, so drift in the machine's load hits both.
        for name, argv in masters().items():
            ports[name] = _free_port()
            procs[name] = _start([*argv, str(ports[name])], ports[name], env)
            _populate(ports[name], 50, 20)
        for workload, clients in SETUPS:
            for _ in range(ROUNDS):
                for name, port in ports.items():
                    rate = _rate(port, clients, workload)
                    samples.setdefault((name, workload, clients), []).append(rate)
    finally:
        for proc in procs.values():
            _stop(proc)
    for name, argv in masters().items():
        port = _free_port()
        proc = _start([*argv, str(port)], port, env)
        try:
            _populate(port, 1000, 0)
            time.sleep(0.5)
            rss[name] = status_kb(proc.pid)
        finally:
            _stop(proc)
    results = []
    labels = {"state": "getSystemState", "register": "registerPublisher+unregisterPublisher"}
    for workload, clients in SETUPS:
        ours = statistics.median(samples[("ours", workload, clients)])
        theirs_samples = samples.get(("theirs", workload, clients))
        theirs = statistics.median(theirs_samples) if theirs_samples else None
        met = None if theirs is None else ours >= 2 * theirs
        results.append(
            Result(
                f"master {labels[workload]}, {clients} client(s)",
                "calls/s",
                ours,
                theirs,
                ">= 2x rosmaster",
                met,
                f"one keep-alive raw-socket client each, the same for both; median of {ROUNDS}"
                " rounds, the masters in turn",
            )
        )
    results.append(
        Result(
            "master resident memory, 1000 topics registered",
            "MB",
            rss["ours"] / 1024,
            rss.get("theirs", 0) / 1024 or None,
            "report",
            None,
        )
    )
    return results


BENCHMARKS = {"master_rates": bench_master_rates}
