"""rostools across hosts, beside real ROS 1 in the same set-up, on both masters.

Each scenario checks that rostools delivers what ROS 1 delivers there; the misconfigured
ones check that it says what is wrong, where ROS 1 is silent.
"""

from __future__ import annotations

import json
import struct
import subprocess
import sys
from pathlib import Path

import pytest

from rostools.bag.formats.access import open_writer
from tests.multihost.conftest import Site
from tests.support.bagdata import STRING_MD5
from tests.support.env import SYSTEM_PYTHON, needs_ros1
from tests.support.netlab import Host, Lab
from tests.support.procs import NODES, Proc

# one worker runs them all: one lab of namespaces and its masters (session fixtures), not one
# per worker
pytestmark = [pytest.mark.multihost, needs_ros1, pytest.mark.xdist_group("netns")]

PLAYED = 48


def rospy(host: Host, script: str, *args: str, env: dict[str, str]) -> Proc:
    """A real rospy node from ``tests/support/ros1_nodes`` on ``host``."""
    return host.start([SYSTEM_PYTHON, str(NODES / script), *args], env)


def talker(host: Host, topic: str, name: str, env: dict[str, str]) -> Proc:
    """A rospy talker at 20 Hz named ``name``."""
    return rospy(host, "talker.py", topic, "20", "0", "-1", f"__name:={name}", env=env)


def rostools(host: Host, *args: str, env: dict[str, str]) -> Proc:
    """A long-running rostools command on ``host``."""
    return host.start([sys.executable, "-m", "rostools", *args], env)


def write_played(path: Path) -> Path:
    """A bag of ``PLAYED`` std_msgs/String messages "m0".. on /played, 10 ms apart."""
    with open_writer(path) as writer:
        conn = writer.add_connection(
            "/played", "std_msgs/String", STRING_MD5, "string data\n", callerid="/recorder"
        )
        for i in range(PLAYED):
            text = f"m{i}".encode()
            writer.write(conn, 100 * 10**9 + i * 10**7, struct.pack("<I", len(text)) + text)
    return path


def heard(listener: Proc, count: int, timeout: float = 20.0) -> int:
    """How many of ``count`` expected messages a rospy listener printed."""
    got = 0
    try:
        for _ in range(count):
            listener.expect("^got ", timeout)
            got += 1
    except AssertionError:
        pass
    return got


def test_rospy_talker_on_b_is_heard_on_c(site: Site, tmp_path: Path) -> None:
    lab, env = site.lab, site.env()
    proc = talker(lab["hostb"], "/chatter", "talker_b", env)
    try:
        echo = lab["hostc"].rostools(
            "topic", "echo", "/chatter", "-n", "3", "--timeout", "20", env=env
        )
        assert echo.returncode == 0 and echo.stdout.count('data: "hello') == 3, echo.stderr
        hz = lab["hostc"].rostools(
            "topic", "hz", "/chatter", "--timeout", "2.5", "-F", "json", env=env
        )
        assert abs(json.loads(hz.stdout.splitlines()[-1])["rate"] - 20) < 2, hz.stdout
        bag = tmp_path / "c.bag"
        record = lab["hostc"].rostools(
            "bag", "record", "/chatter", "--duration", "2", "-O", str(bag), env=env
        )
        assert record.returncode == 0, record.stderr
        info = lab["hostc"].rostools("bag", "info", str(bag), "-F", "json", env=env)
        assert json.loads(info.stdout)["messages"] >= 25
        if site.kind == "roscore":  # ROS 1 in the same set-up
            theirs = lab["hostc"].run(["rostopic", "echo", "-n", "3", "/chatter"], env, 30)
            assert theirs.stdout.count('data: "hello') == 3
    finally:
        proc.stop()


def tools(site: Site) -> list[str]:
    """rostools, and on a real roscore the ROS 1 tool too: the same set-up, both ways."""
    return ["rostools", "rosbag"] if site.kind == "roscore" else ["rostools"]


def published(host: Host, topic: str, env: dict[str, str]) -> None:
    """Until the master lists ``topic`` (asked from ``host``)."""
    for _ in range(100):
        if topic in host.rostools("topic", "list", "-p", env=env).stdout.split():
            return
    raise AssertionError(f"{topic} was never published")


def delivered(site: Site, tool: str, bag: Path, player: Host, env: dict[str, str], to: Host) -> int:
    """How many messages of ``bag``, played on ``player``, a rospy listener on ``to`` heard."""
    listener = rospy(to, "listener.py", "/played", env=site.env())
    try:
        listener.expect("ready", 20)
        play = (
            [sys.executable, "-m", "rostools", "bag", "play", str(bag)]
            if tool == "rostools"
            else ["rosbag", "play", str(bag)]
        )
        done = player.run([*play, "--wait-for-subscribers"], env, timeout=60)
        assert done.returncode == 0, done.stderr
        return heard(listener, PLAYED)
    finally:
        listener.stop()


def test_play_on_b_is_heard_on_c(site: Site, tmp_path: Path) -> None:
    lab = site.lab
    bag = write_played(tmp_path / "played.bag")
    for tool in tools(site):
        assert delivered(site, tool, bag, lab["hostb"], site.env(), lab["hostc"]) == PLAYED, tool


def test_pub_on_b_is_heard_on_c(site: Site) -> None:
    lab, env = site.lab, site.env()
    pub = rostools(lab["hostb"], "topic", "pub", "-r", "10", "/pubbed", "std_msgs/String",
                   "data: from b", env=env)  # fmt: skip
    listener = rospy(lab["hostc"], "listener.py", "/pubbed", env=env)
    try:
        listener.expect("got from b", 20)
    finally:
        listener.stop()
        pub.stop()


def test_play_on_the_masters_host_with_localhost_is_heard_on_b(site: Site, tmp_path: Path) -> None:
    # the defect: with ROS_MASTER_URI=http://localhost:11311 and no ROS_IP, rostools gave
    # out 127.0.0.1 and delivered 0 of 48 to a subscriber on another host; rosbag, 48
    lab = site.lab
    local = site.env(ROS_MASTER_URI=f"http://localhost:{site.port}")
    bag = write_played(tmp_path / "played.bag")
    for tool in tools(site):
        assert delivered(site, tool, bag, lab["robot"], local, lab["hostb"]) == PLAYED, tool


def test_service_and_params_across_hosts(site: Site) -> None:
    lab, env = site.lab, site.env()
    server = rospy(lab["hostb"], "add_two_ints_server.py", env=env)
    try:
        called = lab["hostc"].rostools(
            "service", "call", "/add_two_ints", "{a: 2, b: 3}", "--wait", "--timeout", "20",
            env=env,
        )  # fmt: skip
        assert called.returncode == 0 and called.stdout == "sum: 5\n", called.stderr
    finally:
        server.stop()
    assert lab["hostc"].rostools("param", "set", "/across", "[1, 2]", env=env).returncode == 0
    got = lab["hostb"].rostools("param", "get", "/across", "-F", "json", env=env)
    assert json.loads(got.stdout) == [1, 2]


def test_node_commands_across_hosts(site: Site) -> None:
    lab, env = site.lab, site.env()
    proc = talker(lab["hostb"], "/chatter", "talker_n", env)
    try:
        c = lab["hostc"]
        ping = c.rostools("node", "ping", "/talker_n", "-c", "1", "--timeout", "20", env=env)
        for _ in range(40):  # the talker registers about a second after it starts
            if ping.returncode == 0:
                break
            ping = c.rostools("node", "ping", "/talker_n", "-c", "1", env=env)
        assert ping.returncode == 0, ping.stderr
        info = c.rostools("node", "info", "/talker_n", env=env)
        assert "contacting node http://hostb:" in info.stdout and "/chatter" in info.stdout
        assert c.rostools("node", "kill", "/talker_n", env=env).returncode == 0
        assert proc.popen.wait(15) == 0
    finally:
        proc.stop()


def test_an_unresolvable_publisher_is_named_where_ros1_is_silent(site: Site) -> None:
    # hoste gives out its name, which no host resolves: nobody can connect to its talker
    lab, env = site.lab, site.env()
    proc = talker(lab["hoste"], "/from_e", "talker_e", env)
    try:
        c = lab["hostc"]
        published(c, "/from_e", env)
        echo = c.rostools("topic", "echo", "/from_e", "-n", "1", "--timeout", "2", env=env)
        assert echo.returncode == 5
        assert (
            "cannot connect to /talker_e at http://hoste:" in echo.stderr
            and "(publisher of /from_e): hoste does not resolve here; set ROS_IP or "
            "ROS_HOSTNAME on that host"
            in echo.stderr
        ), echo.stderr
        doctor = c.rostools("doctor", "-F", "json", env=env)
        nodes = next(x for x in json.loads(doctor.stdout)["checks"] if x["name"] == "nodes")
        assert doctor.returncode == 4 and "/talker_e" in nodes["details"]["unreachable"]
        on_e = lab["hoste"].rostools("doctor", env=env)
        assert on_e.returncode == 1
        assert "FAIL  this host  this host gives out 'hoste', which does not resolve here" in (
            on_e.stdout
        )
        assert "(hint: set ROS_IP=10.223.0.5)" in on_e.stdout
        if site.kind == "roscore":  # ROS 1 hears nothing and says nothing
            with pytest.raises(subprocess.TimeoutExpired):
                c.run(["rostopic", "echo", "-n", "1", "/from_e"], env, timeout=3)
    finally:
        proc.stop()
    # and the doctor's hint is the fix
    fixed = talker(lab["hoste"], "/from_e", "talker_e", site.env(ROS_IP="10.223.0.5"))
    try:
        echo = lab["hostc"].rostools(
            "topic", "echo", "/from_e", "-n", "1", "--timeout", "20", env=env
        )
        assert echo.returncode == 0, echo.stderr
    finally:
        fixed.stop()


def test_a_hostname_on_127_0_1_1_is_named_by_the_doctor(site: Site) -> None:
    lab, env = site.lab, site.env()
    doctor = lab["hostd"].rostools("doctor", env=env)
    assert doctor.returncode == 1
    assert (
        "this host gives out 'hostd', which resolves here to 127.0.1.1, a loopback address, "
        "while the master is on another host (hint: set ROS_IP=10.223.0.4)"
    ) in doctor.stdout
    proc = rostools(lab["hostd"], "topic", "pub", "-r", "10", "/from_d", "std_msgs/String",
                    "data: d", env=env)  # fmt: skip
    try:
        published(lab["hostc"], "/from_d", env)
        echo = lab["hostc"].rostools(
            "topic", "echo", "/from_d", "-n", "1", "--timeout", "2", env=env
        )
        assert echo.returncode == 5 and "hostd does not resolve here" in echo.stderr
    finally:
        proc.stop()


def test_an_unreachable_master_is_one_line(lab: Lab, tmp_path: Path) -> None:
    site = Site(lab, "none", 11311, tmp_path)
    env = site.env(ROS_MASTER_URI="http://10.223.0.99:11311", ROSTOOLS_MASTER_TIMEOUT="2")
    listed = lab["hostc"].rostools("topic", "list", env=env, timeout=30)
    assert listed.returncode in (4, 5) and len(listed.stderr.splitlines()) == 1, listed.stderr
    assert "10.223.0.99" in listed.stderr
    doctor = lab["hostc"].rostools("doctor", env=env, timeout=30)
    assert doctor.returncode in (4, 5)
    assert doctor.stdout.startswith("FAIL  master     cannot reach the master at http://10.223")
