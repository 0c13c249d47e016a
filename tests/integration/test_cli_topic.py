"""``rostools topic`` as a user runs it, on ``rostools core``, with rostools on both ends."""

from __future__ import annotations

import json
import signal
import time
from pathlib import Path

import yaml

from tests.support.env import run_cli
from tests.support.load import scaled
from tests.support.procs import start_cli, wait_for


def wait_listed(topic: str, env: dict[str, str]) -> None:
    wait_for(
        lambda: topic in run_cli("topic", "list", env=env).stdout.split(), 15, f"{topic} listed"
    )


def test_pub_then_echo_in_every_format(rostools_master: str, cli_env: dict[str, str]) -> None:
    pub = start_cli(
        "topic",
        "pub",
        "/pt",
        "geometry_msgs/PointStamped",
        "{header: {frame_id: map}, point: {x: 1.5}}",
        env=cli_env,
    )
    try:
        wait_listed("/pt", cli_env)
        text = run_cli("topic", "echo", "/pt", "-n", "1", "--timeout", "10", env=cli_env)
        assert text.returncode == 0, text.stderr
        assert '  frame_id: "map"\npoint: \n  x: 1.5\n' in text.stdout and text.stdout.endswith(
            "---\n"
        )
        data = json.loads(
            run_cli("topic", "echo", "/pt", "-n", "1", "-F", "json", env=cli_env).stdout
        )
        assert data["point"] == {"x": 1.5, "y": 0.0, "z": 0.0}
        field = run_cli("topic", "echo", "/pt/point/x", "-n", "1", env=cli_env)
        assert field.stdout == "1.5\n---\n"
        csv = run_cli("topic", "echo", "/pt", "-p", "-n", "1", env=cli_env).stdout.splitlines()
        assert csv[0] == (
            "%time,field.header.seq,field.header.stamp,field.header.frame_id,"
            "field.point.x,field.point.y,field.point.z"
        )
        assert csv[1].endswith(",map,1.5,0.0,0.0")
        typ = run_cli("topic", "type", "/pt/point/x", env=cli_env).stdout
        assert typ == "geometry_msgs/PointStamped point/x float64\n"
        info = run_cli("topic", "info", "/pt", env=cli_env).stdout
        assert info.startswith(
            "Type: geometry_msgs/PointStamped\n\nPublishers: \n * /rostools_pub_"
        )
        assert "/pt" in run_cli("topic", "find", "geometry_msgs/PointStamped", env=cli_env).stdout
    finally:
        pub.stop()


def test_rate_meters(rostools_master: str, cli_env: dict[str, str]) -> None:
    pub = start_cli(
        "topic",
        "pub",
        "-r",
        "50",
        "/pt",
        "geometry_msgs/PointStamped",
        "{header: auto}",
        "-s",
        env=cli_env,
    )
    try:
        wait_listed("/pt", cli_env)
        hz = run_cli(
            "topic", "hz", "/pt", "--timeout", "3.5", "-F", "json", env=cli_env, timeout=30
        )
        rows = [json.loads(line) for line in hz.stdout.splitlines()]
        assert hz.returncode == 0 and rows, hz.stderr
        assert abs(rows[-1]["rate"] - 50) < 2.5
        # YAML is asked for, YAML it gets (hz, bw and delay printed JSON), one document a report.
        docs = run_cli(
            "topic", "hz", "/pt", "--timeout", "2.5", "-F", "yaml", env=cli_env, timeout=30
        ).stdout
        assert docs.endswith("---\n") and "rate: " in docs and "{" not in docs, docs
        assert all(d["topic"] == "/pt" for d in yaml.safe_load_all(docs) if d)
        bw = run_cli("topic", "bw", "/pt", "--timeout", "2.5", env=cli_env, timeout=30).stdout
        assert bw.startswith("average: ") and "mean: 0.04KB min: 0.04KB" in bw  # 40-byte messages
        delay = run_cli(
            "topic", "delay", "/pt", "--timeout", "2.5", "-F", "json", env=cli_env, timeout=30
        )
        assert 0 <= json.loads(delay.stdout.splitlines()[-1])["delay"] < 0.5
    finally:
        pub.stop()


def test_a_topic_not_published_holds_no_other_back(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    """hz measures the topics that are published while one it was given is not (it waited
    for each in turn, and printed nothing until the timeout)."""
    pub = start_cli("topic", "pub", "-r", "20", "/pt", "geometry_msgs/PointStamped",
                    "{header: auto}", "-s", env=cli_env)  # fmt: skip
    try:
        wait_listed("/pt", cli_env)
        done = run_cli("topic", "hz", "/nobody", "/pt", "--timeout", "3", "-F", "json",
                       env=cli_env, timeout=30)  # fmt: skip
        assert done.returncode == 0, done.stderr
        rows = [json.loads(line) for line in done.stdout.splitlines()]
        assert rows and all(row["topic"] == "/pt" for row in rows), done.stdout
        assert "topic [/nobody] does not appear to be published yet" in done.stderr
        assert "subscribed to [/pt]" in done.stderr
    finally:
        pub.stop()


def test_filter_sees_m_and_topic(rostools_master: str, cli_env: dict[str, str]) -> None:
    pub = start_cli("topic", "pub", "-r", "20", "/nums", "std_msgs/Int32", "7", env=cli_env)
    try:
        wait_listed("/nums", cli_env)
        out = run_cli(
            "topic",
            "echo",
            "/nums",
            "-n",
            "2",
            "--filter",
            "m.data == 7 and topic == '/nums'",
            env=cli_env,
        )
        assert out.stdout == "data: 7\n---\ndata: 7\n---\n"
        none = run_cli(
            "topic", "echo", "/nums", "--filter", "m.data > 7", "--timeout", "1.5", env=cli_env
        )
        assert none.returncode == 5
        bad = run_cli("topic", "echo", "/nums", "--filter", "m.data ==", env=cli_env)
        assert bad.returncode == 2 and "not a Python expression" in bad.stderr
        # One compiler: an expression that raises is exit 2 everywhere (echo said 1, bag 2).
        for verb in ("echo", "hz"):
            raised = run_cli(
                "topic", verb, "/nums", "--filter", "m.nosuch", "--timeout", "5", env=cli_env
            )
            assert raised.returncode == 2, raised.stderr
            last = raised.stderr.splitlines()[-1]  # hz says "subscribed to [/nums]" first
            assert last.startswith("rostools: 'm.nosuch' failed on /nums: AttributeError"), last
    finally:
        pub.stop()


def test_unknown_topic_waits_only_as_long_as_asked(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    start = time.monotonic()
    out = run_cli("topic", "echo", "/nobody", "--timeout", "1", env=cli_env)
    assert out.returncode == 5
    assert "does not appear to be published yet" in out.stderr
    assert "did not deliver a message within 1 s" in out.stderr
    assert time.monotonic() - start < scaled(8)
    assert run_cli("topic", "info", "/nobody", env=cli_env).returncode == 3
    assert run_cli("topic", "hz", "/nobody", "--timeout", "1", env=cli_env).returncode == 5


def test_types_are_learnt_from_the_publisher(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    (tmp_path / "my_robot" / "msg").mkdir(parents=True)
    (tmp_path / "my_robot" / "msg" / "Battery.msg").write_text(
        "# custom\nfloat32 volts\nstring[] cells\n"
    )
    pub = start_cli(
        "topic",
        "pub",
        "/battery",
        "my_robot/Battery",
        "{volts: 12.5, cells: [a, b]}",
        "--msg-path",
        str(tmp_path),
        env=cli_env,
    )
    try:
        wait_listed("/battery", cli_env)
        out = run_cli("topic", "echo", "/battery", "-n", "1", env=cli_env)  # no --msg-path here
        assert out.stdout == "volts: 12.5\ncells: \n  - a\n  - b\n---\n", out.stderr
        typ = run_cli("topic", "type", "/battery/volts", env=cli_env)
        assert typ.stdout == "my_robot/Battery volts float32\n", typ.stderr
    finally:
        pub.stop()


def test_pub_from_file_and_stdin(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    docs = tmp_path / "msgs.yaml"
    docs.write_text("data: one\n---\ndata: two\n---\ndata: three\n")
    echo = start_cli(
        "topic", "echo", "/words", "-n", "3", "-F", "json", "--timeout", "20", env=cli_env
    )
    try:
        out = run_cli(
            "topic", "pub", "/words", "std_msgs/String", "-f", str(docs), "-r", "5", env=cli_env
        )
        assert out.returncode == 0, out.stderr
        assert echo.popen.wait(20) == 0
        assert [json.loads(x)["data"] for x in echo.output()[0].splitlines()] == [
            "one",
            "two",
            "three",
        ]
    finally:
        echo.stop()
    piped = run_cli(
        "topic", "pub", "/words2", "std_msgs/String", env=cli_env, input="data: a\n---\ndata: b\n"
    )
    assert piped.returncode == 0, piped.stderr


def test_echo_follows_a_restarted_publisher(rostools_master: str, cli_env: dict[str, str]) -> None:
    echo = start_cli("topic", "echo", "/beat", "-F", "json", env=cli_env)
    try:
        for text in ("first", "second"):
            pub = start_cli(
                "topic", "pub", "-r", "10", "/beat", "std_msgs/String", f"data: {text}", env=cli_env
            )
            echo.expect(text, timeout=20)
            pub.signal(signal.SIGKILL)  # no clean unregistration
            pub.stop()
    finally:
        echo.stop()


def test_echo_stops_cleanly_when_its_node_is_shut_down(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    import xmlrpc.client

    pub = start_cli("topic", "pub", "/quiet", "std_msgs/Empty", env=cli_env)
    echo = start_cli("topic", "echo", "/quiet", env=cli_env)
    try:
        proxy = xmlrpc.client.ServerProxy(rostools_master)
        wait_for(
            lambda: any(
                n.startswith("/rostools_echo")
                for _, nodes in proxy.getSystemState("/t")[2][1]
                for n in nodes
            ),
            15,
            "echo registered",
        )
        node = next(
            n
            for _, nodes in proxy.getSystemState("/t")[2][1]
            for n in nodes
            if n.startswith("/rostools_echo")
        )
        uri = proxy.lookupNode("/t", node)[2]
        xmlrpc.client.ServerProxy(uri).shutdown("/t", "test")
        assert echo.popen.wait(10) == 0
        state = proxy.getSystemState("/t")[2]
        assert not any(t == "/quiet" for t, _ in state[1])  # it unregistered on its way out
    finally:
        echo.stop()
        pub.stop()


def test_quick_commands_match_the_typer_path(rostools_master: str, cli_env: dict[str, str]) -> None:
    """Every command the launcher runs without Typer prints what the Typer path prints."""
    pub = start_cli("topic", "pub", "/ns/a", "std_msgs/Empty", env=cli_env)
    typer_env = cli_env | {"ROSTOOLS_NO_QUICK": "1"}
    try:
        wait_listed("/ns/a", cli_env)
        assert run_cli("param", "set", "/p", "{a: [1, 2], b: hi}", env=cli_env).returncode == 0
        lines = [
            ["topic", "list"], ["topic", "list", "/ns"], ["topic", "list", "ns", "-v"],
            ["--format", "json", "topic", "list"], ["topic", "info", "/ns/a"],
            ["topic", "find", "std_msgs/Empty"], ["topic", "info", "/nope"],
            ["param", "get", "/p"], ["param", "get", "/p", "-p"], ["param", "get", "/nope"],
            ["param", "list"], ["param", "get", "/p", "-F", "json"],
            ["service", "list", "-n"], ["service", "uri", "/rosout/get_loggers"],
            ["service", "node", "/rosout/get_loggers"], ["service", "type", "/rosout/get_loggers"],
            ["node", "list", "-a"], ["node", "list", "-u"], ["msg", "md5", "std_msgs/String"],
            ["param", "get"], ["param", "get", "/p", "--bogus"], ["topic", "list", "-vp"],
            ["topic", "type", "/ns/a"], ["topic", "type", "/ns/a/x"], ["topic", "type", "/no"],
            ["node", "info", "/rosout", "-q"], ["node", "info", "/rosout", "-F", "json"],
            ["node", "info", "/nope"], ["param", "get", "/p/a"],
        ]  # fmt: skip
        for args in lines:
            quick = run_cli(*args, env=cli_env)
            slow = run_cli(*args, env=typer_env)
            assert (quick.returncode, quick.stdout, quick.stderr) == (
                slow.returncode, slow.stdout, slow.stderr,
            ), args  # fmt: skip
        assert run_cli("topic", "list", "/ns", env=cli_env).stdout == "/ns/a\n"
    finally:
        pub.stop()


def test_remapping_arguments(rostools_master: str, cli_env: dict[str, str]) -> None:
    pub = start_cli("topic", "pub", "/other", "std_msgs/String", "data: remapped", env=cli_env)
    try:
        wait_listed("/other", cli_env)
        out = run_cli(
            "topic",
            "echo",
            "/chatter",
            "-n",
            "1",
            "/chatter:=/other",
            "__name:=watcher",
            env=cli_env,
        )
        assert out.stdout == 'data: "remapped"\n---\n', out.stderr
        private = run_cli(
            "topic", "echo", "/other", "-n", "1", "__name:=probe", "_gain:=2.5", env=cli_env
        )
        assert private.returncode == 0
        assert run_cli("param", "get", "/probe/gain", env=cli_env).stdout == "2.5\n"
    finally:
        pub.stop()


def test_pub_verbose_prints_every_message(rostools_master: str, cli_env: dict[str, str]) -> None:
    """``-v -r`` says each message it sends, as rostopic does (it said only the first)."""
    done = run_cli(
        "topic", "pub", "-v", "-r", "20", "--timeout", "1", "/vv", "std_msgs/String", "data: v",
        env=cli_env, timeout=30,
    )  # fmt: skip
    said = [ln for ln in done.stdout.splitlines() if ln == 'publishing data: "v"']
    assert len(said) >= 15, done.stdout


def test_pub_use_rostime_stamps_with_clock(rostools_master: str, cli_env: dict[str, str]) -> None:
    """``pub --use-rostime``: ``now`` is /clock's time under sim time; without it, wall time.

    rostopic pub stamps 0 when its first /clock has not come yet (seen here, latched); ours
    waits up to 2 s for it.
    """
    assert run_cli("param", "set", "/use_sim_time", "true", env=cli_env).returncode == 0
    clock_msg = ["rosgraph_msgs/Clock", "{clock: {secs: 1234}}"]
    clock = start_cli("topic", "pub", "/clock", *clock_msg, "-r", "20", env=cli_env)
    header = ["std_msgs/Header", "{stamp: now}"]
    pubs = [
        start_cli("topic", "pub", "/ros", *header, "--use-rostime", env=cli_env),
        start_cli("topic", "pub", "/wall", *header, env=cli_env),
    ]
    try:
        stamps = {}
        for topic in ("/ros", "/wall"):
            echo = run_cli(
                "topic", "echo", topic, "-n", "1", "-F", "json", "--timeout", "20", env=cli_env
            )
            assert echo.returncode == 0, echo.stderr
            stamps[topic] = json.loads(echo.stdout)["stamp"]["secs"]
        assert stamps["/ros"] == 1234 and stamps["/wall"] > 1_700_000_000, stamps
    finally:
        for proc in [*pubs, clock]:
            proc.stop()
