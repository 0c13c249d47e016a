"""``topic echo -b`` and ``topic list -b``, set beside rostopic on the same bag (issue 13)."""

from __future__ import annotations

import re
import struct
import subprocess
from pathlib import Path

import pytest

from rostools.bag.formats.access import open_writer
from tests.support.env import needs_ros1, run_cli
from tests.support.procs import Proc, ros_env, start_cli, wait_for

pytestmark = [pytest.mark.interop, needs_ros1]

SEP = "=" * 80
POINT_STAMPED_DEF = (
    f"std_msgs/Header header\ngeometry_msgs/Point point\n{SEP}\nMSG: std_msgs/Header\n"
    f"uint32 seq\ntime stamp\nstring frame_id\n{SEP}\nMSG: geometry_msgs/Point\n"
    "float64 x\nfloat64 y\nfloat64 z\n"
)
POINT_STAMPED_MD5 = "c63aecb41bfdfd6b7e1fac37c7cbe7bf"


def test_plot_time_is_the_record_time(tmp_path: Path) -> None:
    """``-p`` writes the bag's record time in %time, not ``header.stamp``, as rostopic does."""
    bag = tmp_path / "h.bag"
    with open_writer(bag) as writer:
        conn = writer.add_connection(
            "/h", "geometry_msgs/PointStamped", POINT_STAMPED_MD5, POINT_STAMPED_DEF
        )
        for i in range(2):
            header = struct.pack("<III", i, 100 + i, 5) + struct.pack("<I", 1) + b"f"
            data = header + struct.pack("<3d", i, 2.5, -1.0)
            writer.write(conn, 200_000_000_000 + i, data)  # recorded 100 s after its stamp
    ours = run_cli("topic", "echo", "-b", str(bag), "-p", "-n", "2", "/h")
    theirs = subprocess.run(
        ["rostopic", "echo", "-b", str(bag), "-p", "-n", "2", "/h"],
        capture_output=True, text=True, timeout=60, check=False,
    )  # fmt: skip
    assert theirs.returncode == 0, theirs.stderr
    assert ours.stdout.splitlines()[1].startswith("200000000000,")  # was 100000000005
    assert ours.stdout == theirs.stdout


def test_list_of_one_topic_counts_its_messages(tmp_path: Path) -> None:
    """``list -b BAG /ns``: rostopic's "N message(s) from ... to ..." (it printed the name)."""
    bag = tmp_path / "l.bag"
    string_md5 = "992ce8a1687cec8c8bd883ec73ca41d1"
    with open_writer(bag) as writer:
        conns = [
            writer.add_connection(t, "std_msgs/String", string_md5, "string data\n")
            for t in ("/ns/a", "/ns/b", "/other")
        ]
        for i in range(30):
            writer.write(conns[i % 3], 1_795_459_893_000_000_000 + i * 7_000_000_000, b"\0\0\0\0")
    for name in ("/ns", "/ns/b"):
        ours = run_cli("topic", "list", "-b", str(bag), name)
        theirs = subprocess.run(
            ["rostopic", "list", "-b", str(bag), name],
            capture_output=True, text=True, timeout=60, check=False,
        )  # fmt: skip
        assert theirs.returncode == 0, theirs.stderr
        assert ours.stdout == theirs.stdout and "message(s) from" in ours.stdout


def _averages(text: str, what: str) -> list[float]:
    return [float(v) for v in re.findall(rf"average {what}: (-?[0-9.]+)", text)]


def test_rates_follow_sim_time_from_clock(
    tmp_path: Path, rostools_master: str, cli_env: dict[str, str]
) -> None:
    """Under /use_sim_time, hz and delay use /clock as rostopic's do (issue 13, defect 2).

    A bag recorded at 10 Hz in 2020, stamps equal to record times, played at twice its pace
    with --clock: in ROS time the rate is 10 Hz and the delay near 0; by the wall clock the
    rate is 20 Hz (hz --wall-time), and the delay was years (430.547 s in the issue's run).
    """
    bag = tmp_path / "sim.bag"
    start = 1_600_000_000_000_000_000
    with open_writer(bag) as writer:
        conn = writer.add_connection(
            "/pose", "geometry_msgs/PointStamped", POINT_STAMPED_MD5, POINT_STAMPED_DEF
        )
        for i in range(400):
            t = start + i * 100_000_000
            header = struct.pack("<III", i, t // 10**9, t % 10**9) + struct.pack("<I", 0)
            writer.write(conn, t, header + struct.pack("<3d", i, 0.0, 0.0))
    assert run_cli("param", "set", "/use_sim_time", "true", env=cli_env).returncode == 0
    player = start_cli("bag", "play", str(bag), "--clock", "-r", "2", env=cli_env)
    meters: dict[str, Proc] = {}
    out = {}
    try:
        wait_for(lambda: "/pose" in run_cli("topic", "list", env=cli_env).stdout, 15, "play")
        ros = ros_env(rostools_master, tmp_path / "ros_home")
        meters = {
            "ours hz": start_cli("topic", "hz", "/pose", env=cli_env),
            "ours wall hz": start_cli("topic", "hz", "/pose", "--wall-time", env=cli_env),
            "ours delay": start_cli("topic", "delay", "/pose", env=cli_env),
            "rostopic hz": Proc(["rostopic", "hz", "/pose"], env=ros),
            "rostopic delay": Proc(["rostopic", "delay", "/pose"], env=ros),
        }
        for name, proc in meters.items():  # three each: the last two are checked
            for _ in range(3):
                proc.expect("^average (rate|delay): ", 20)
            out[name] = "".join(proc.seen)
    finally:
        for proc in meters.values():
            proc.stop()
        player.stop()
    rates = {k: _averages(v, "rate")[-2:] for k, v in out.items() if "hz" in k}
    delays = {k: _averages(v, "delay")[-2:] for k, v in out.items() if "delay" in k}
    assert all(rates.values()) and all(delays.values()), out
    assert all(9.0 < r < 11.0 for r in rates["rostopic hz"] + rates["ours hz"]), rates
    assert all(18.0 < r < 22.0 for r in rates["ours wall hz"]), rates
    assert all(abs(d) < 0.5 for d in delays["rostopic delay"] + delays["ours delay"]), delays


@pytest.mark.parametrize(
    ("name", "namespace"),
    [("chatter", ""), ("/chatter", ""), ("chatter/data", ""), ("chatter", "/ns")],
)
def test_relative_names_in_a_bag_resolve_as_rostopics(
    tmp_path: Path, cli_env: dict[str, str], name: str, namespace: str
) -> None:
    """A bag's relative topic (``chatter``) and a relative name typed (``chatter``) both
    resolve, as rostopic resolves them, to ``/chatter`` (``/ns/chatter`` in ROS_NAMESPACE
    /ns). It was "topic /chatter is not in BAG" (corpus embag/test_2.bag)."""
    bag = tmp_path / "rel.bag"
    string_md5 = "992ce8a1687cec8c8bd883ec73ca41d1"
    with open_writer(bag) as writer:
        conns = [
            writer.add_connection(t, "std_msgs/String", string_md5, "string data\n")
            for t in ("chatter", "/other", "/ns/chatter")
        ]
        for i in range(9):
            text = f"{conns[i % 3].topic} {i}".encode()
            writer.write(conns[i % 3], 10**9 + i, struct.pack("<I", len(text)) + text)
    env = {**cli_env, "ROS_NAMESPACE": namespace} if namespace else cli_env
    argv = ["echo", "-b", str(bag), name]
    ours = run_cli("topic", *argv, env=env)
    theirs = subprocess.run(["rostopic", *argv], env=env, capture_output=True, text=True,
                            timeout=60, check=False)  # fmt: skip
    assert theirs.returncode == 0, theirs.stderr
    assert ours.returncode == 0, ours.stderr
    assert ours.stdout == theirs.stdout
    # /ns/chatter is the bag's chatter too in /ns: both connections, in time order
    assert ours.stdout.count("---") == (6 if namespace else 3)
