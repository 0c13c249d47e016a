"""``rostools bridge`` with our master and nodes, through websockets' own client."""

from __future__ import annotations

import json
import struct
from collections.abc import Iterator
from pathlib import Path

import pytest
from websockets.exceptions import InvalidStatus
from websockets.sync.client import connect

from tests.support.env import run_cli
from tests.support.foxglove import SDK, V1, Client, ros_string, start_bridge
from tests.support.procs import start_cli, subscribers, wait_for

STRING_DEF = "string data\n"


@pytest.fixture
def chatter(cli_env: dict[str, str], rostools_master: str) -> Iterator[None]:
    """``/chatter``: std_msgs/String "hi" at 20 Hz, on the test's master."""
    pub = start_cli(
        "topic", "pub", "-r", "20", "/chatter", "std_msgs/String", "data: hi", env=cli_env
    )
    try:
        yield
    finally:
        pub.stop()


@pytest.mark.parametrize("subprotocol", [V1, SDK])
def test_a_topic_is_advertised_with_its_definition_and_forwarded_as_bytes(
    rostools_master: str, cli_env: dict[str, str], chatter: None, subprotocol: str
) -> None:
    bridge, url = start_bridge(cli_env)
    try:
        with Client(url, subprotocol) as client:
            assert client.ws.subprotocol == subprotocol
            assert {"parameters", "services", "connectionGraph", "clientPublish"} <= set(
                client.server_info["capabilities"]
            )
            channel = client.channel("/chatter")
            assert channel["encoding"] == "ros1"
            assert channel["schemaEncoding"] == "ros1msg"
            assert (channel["schemaName"], channel["schema"]) == ("std_msgs/String", STRING_DEF)
            sub = client.subscribe("/chatter")
            (stamp, payload), *_ = client.receive(sub, 3)
            assert payload == ros_string("hi")
            assert stamp > 1_600_000_000 * 10**9  # a receive time in ns
    finally:
        bridge.stop()


def test_the_bridge_subscribes_on_demand_and_lets_go(
    rostools_master: str, cli_env: dict[str, str], chatter: None
) -> None:
    bridge, url = start_bridge(cli_env)

    def bridge_subscribes() -> bool:
        return any("rostools_bridge" in n for n in subscribers(rostools_master, "/chatter"))

    try:
        with Client(url) as first, Client(url) as second:
            first.channel("/chatter")
            assert not bridge_subscribes()  # known type: advertised without subscribing
            a = first.subscribe("/chatter")
            b = second.subscribe("/chatter")
            first.receive(a)
            second.receive(b)
            assert bridge_subscribes()
            first.send({"op": "unsubscribe", "subscriptionIds": [a]})
            second.receive(b, len(second.messages[b]) + 3)  # the other reader goes on
            assert bridge_subscribes()
            second.send({"op": "unsubscribe", "subscriptionIds": [b]})
            wait_for(lambda: not bridge_subscribes(), 15, "the bridge to unsubscribe")
    finally:
        bridge.stop()


def test_a_type_nobody_here_knows_is_learnt_from_the_publisher(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    (tmp_path / "odd_msgs" / "msg").mkdir(parents=True)
    (tmp_path / "odd_msgs" / "msg" / "Odd.msg").write_text("float64 x\nstring note\n")
    pub_env = dict(cli_env, ROSTOOLS_MSG_PATH=str(tmp_path))
    bridge, url = start_bridge(cli_env)
    try:
        with Client(url) as client:
            pub = start_cli(
                "topic", "pub", "-r", "10", "/odd", "odd_msgs/Odd", "{x: 1.5, note: n}", env=pub_env
            )
            try:
                channel = client.channel("/odd")  # appears once it is published
                assert (channel["schemaName"], channel["schema"]) == (
                    "odd_msgs/Odd",
                    "float64 x\nstring note\n",
                )
                sub = client.subscribe("/odd")
                (_, payload), *_ = client.receive(sub)
                assert payload == struct.pack("<d", 1.5) + ros_string("n")
            finally:
                pub.stop()
            gone = channel["id"]
            client.wait(lambda m: m.get("op") == "unadvertise" and gone in m["channelIds"])
    finally:
        bridge.stop()


def test_a_latched_message_reaches_every_new_subscriber(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    pub = start_cli("topic", "pub", "/map_name", "std_msgs/String", "data: the map", env=cli_env)
    bridge, url = start_bridge(cli_env)
    try:
        for _ in range(2):  # the second client subscribes after the bridge already has it
            with Client(url) as client:
                sub = client.subscribe("/map_name")
                assert client.receive(sub)[0][1] == ros_string("the map")
    finally:
        bridge.stop()
        pub.stop()


def test_a_token_is_required_before_the_upgrade_whatever_the_protocol(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    bridge, url = start_bridge(cli_env, "--token", "s3cret")
    try:
        for bad in (url, url + "/?token=wrong"):
            with pytest.raises(InvalidStatus) as refused:
                Client(bad)
            assert refused.value.response.status_code == 401
        # a client that offers no Foxglove subprotocol is spoken rosbridge v2 to, with the token
        with connect(url + "/?token=s3cret", subprotocols=["not.foxglove"]) as other:  # type: ignore[list-item]
            assert other.subprotocol is None
        with pytest.raises(InvalidStatus) as refused:
            connect(url, subprotocols=["not.foxglove"])  # type: ignore[list-item]
        assert refused.value.response.status_code == 401
        with Client(url + "/?token=s3cret") as client:
            assert client.server_info["op"] == "serverInfo"
        bridge.expect(r'"event": ?"refused".*token', 15)
    finally:
        bridge.stop()


def test_what_a_hostile_client_sends_gets_a_status_and_costs_nobody_else(
    rostools_master: str, cli_env: dict[str, str], chatter: None
) -> None:
    bridge, url = start_bridge(cli_env)
    try:
        with Client(url) as good, Client(url) as bad:
            sub = good.subscribe("/chatter")
            good.receive(sub)
            for junk, reason in [
                ("{not json", "not JSON"),
                ("[1, 2]", "not a JSON object"),
                (json.dumps({"op": "explode"}), "unknown op"),
                (json.dumps({"op": "subscribe", "subscriptions": 5}), "subscriptions missing"),
                (
                    json.dumps({"op": "subscribe", "subscriptions": [{"id": -1, "channelId": 1}]}),
                    "id missing or not an id",
                ),
                (
                    json.dumps(
                        {"op": "subscribe", "subscriptions": [{"id": 1, "channelId": 99999}]}
                    ),
                    "no channel 99999",
                ),
                (b"\x01\x07\x00\x00\x00hello", "did not advertise"),
                (b"\x09", "unknown binary opcode"),
                (b"\x02\x01\x00\x00\x00\x01\x00\x00\x00\xff\x00\x00\x00", "runs past the end"),
            ]:
                bad.send(junk)
                bad.status(reason)
            before = len(good.messages[sub])
            good.receive(sub, before + 3)  # still served
        bridge.expect(r'"event": ?"refused"', 15)
    finally:
        bridge.stop()


def test_a_subscription_flood_is_refused_past_the_limit(
    rostools_master: str, cli_env: dict[str, str], chatter: None
) -> None:
    from rostools.web.client import MAX_SUBSCRIPTIONS

    bridge, url = start_bridge(cli_env)
    try:
        with Client(url) as client:
            channel = client.channel("/chatter")["id"]
            many = [{"id": i, "channelId": channel} for i in range(MAX_SUBSCRIPTIONS + 5)]
            client.send({"op": "subscribe", "subscriptions": many})
            client.status(f"more than {MAX_SUBSCRIPTIONS} subscriptions", 60)
    finally:
        bridge.stop()


def test_a_client_publishes_on_the_graph_with_its_own_schema(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    bridge, url = start_bridge(cli_env)
    echo = None
    try:
        with Client(url) as client:
            client.send(
                {
                    "op": "advertise",
                    "channels": [
                        {
                            "id": 3,
                            "topic": "/from_browser",
                            "encoding": "ros1",
                            "schemaName": "web_msgs/Note",
                            "schema": "string text\nint32 n\n",
                        }
                    ],
                }
            )
            wait_for(
                lambda: "/from_browser" in run_cli("topic", "list", env=cli_env).stdout,
                20,
                "the client's topic",
            )
            echo = start_cli("topic", "echo", "/from_browser", "-n", "1", "-F", "json", env=cli_env)
            wait_for(lambda: subscribers(rostools_master, "/from_browser"), 20, "echo")
            payload = ros_string("typed in a browser") + struct.pack("<i", 7)

            def echoed() -> bool:
                client.send(b"\x01\x03\x00\x00\x00" + payload)
                return echo is not None and echo.popen.poll() is not None

            wait_for(echoed, 20, "echo to print the client's message")
            out, _ = echo.output()
            assert json.loads(out.splitlines()[0]) == {"text": "typed in a browser", "n": 7}
            assert (
                run_cli("topic", "type", "/from_browser", env=cli_env).stdout == "web_msgs/Note\n"
            )
            client.send({"op": "unadvertise", "channelIds": [3]})
            wait_for(
                lambda: "/from_browser" not in run_cli("topic", "list", env=cli_env).stdout,
                20,
                "the client's topic to go",
            )
    finally:
        bridge.stop()
        if echo is not None:
            echo.stop()


def test_parameters_get_set_and_follow(rostools_master: str, cli_env: dict[str, str]) -> None:
    run_cli("param", "set", "/robot/speed", "1.5", env=cli_env)
    run_cli("param", "set", "/robot/name", "r2", env=cli_env)
    bridge, url = start_bridge(cli_env)
    try:
        with Client(url) as client:
            client.send({"op": "getParameters", "parameterNames": ["/robot/speed"], "id": "a"})
            got = client.wait(lambda m: m.get("id") == "a")
            assert got["parameters"] == [{"name": "/robot/speed", "value": 1.5, "type": "float64"}]
            client.send({"op": "getParameters", "parameterNames": [], "id": "all"})
            every = client.wait(lambda m: m.get("id") == "all")["parameters"]
            assert {"name": "/robot/name", "value": "r2"} in every
            client.send(
                {
                    "op": "setParameters",
                    "parameters": [{"name": "/robot/gains", "value": [1, 2, 3]}],
                    "id": "set",
                }
            )
            client.wait(lambda m: m.get("id") == "set")
            assert (
                run_cli("param", "get", "/robot/gains", env=cli_env).stdout == "- 1\n- 2\n- 3\n\n"
            )
            client.send({"op": "subscribeParameterUpdates", "parameterNames": ["/robot/speed"]})

            update: list[dict[str, object]] = []

            def updated() -> bool:
                run_cli("param", "set", "/robot/speed", "2.5", env=cli_env)
                try:
                    update.append(client.wait(lambda m: m.get("op") == "parameterValues", 2))
                except AssertionError:
                    return False  # set before the bridge followed it: set it again
                return True

            wait_for(updated, 30, "paramUpdate")
            assert update[0]["parameters"] == [
                {"name": "/robot/speed", "value": 2.5, "type": "float64"}
            ]
    finally:
        bridge.stop()


def test_the_connection_graph_and_a_topic_that_goes(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    bridge, url = start_bridge(cli_env)
    try:
        with Client(url) as client:
            client.send({"op": "subscribeConnectionGraph"})
            pub = start_cli(
                "topic", "pub", "-r", "5", "/seen", "std_msgs/String", "data: x", env=cli_env
            )
            try:
                update = client.wait(
                    lambda m: (
                        m.get("op") == "connectionGraphUpdate"
                        and any(t["name"] == "/seen" for t in m["publishedTopics"])
                    )
                )
                (entry,) = [t for t in update["publishedTopics"] if t["name"] == "/seen"]
                assert entry["publisherIds"][0].startswith("/rostools_pub")
            finally:
                pub.stop()
            client.wait(
                lambda m: m.get("op") == "connectionGraphUpdate" and "/seen" in m["removedTopics"]
            )
    finally:
        bridge.stop()


def test_sim_time_is_sent_as_time(rostools_master: str, cli_env: dict[str, str]) -> None:
    run_cli("param", "set", "/use_sim_time", "true", env=cli_env)
    clock = start_cli(
        "topic", "pub", "-r", "50", "/clock", "rosgraph_msgs/Clock", "clock: {secs: 42, nsecs: 7}",
        env=cli_env,
    )  # fmt: skip
    bridge, url = start_bridge(cli_env)
    try:
        with Client(url) as client:
            assert "time" in client.server_info["capabilities"]
            client.poll(lambda: any(b[0] == 2 for b in client.binary), 20, "a time message")
            (stamp,) = struct.unpack_from("<Q", next(b for b in client.binary if b[0] == 2), 1)
            assert stamp == 42 * 10**9 + 7
    finally:
        bridge.stop()
        clock.stop()


def test_bad_options_are_one_line(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    for args, words in [
        (["--max-rate", "/t=fast"], "--max-rate /t=fast: give TOPIC=HZ"),
        (["--certfile", str(tmp_path / "none.pem")], "cannot use the certificate"),
        (["--keyfile", "k.pem"], "--keyfile needs --certfile"),
    ]:
        done = run_cli("bridge", "--port", "0", *args, env=cli_env)
        assert done.returncode == 2, done.stderr
        assert done.stderr.count("\n") == 1 and words in done.stderr


def test_wss_with_a_certificate_and_a_warning_off_loopback(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    import ssl
    import subprocess

    cert, key = tmp_path / "cert.pem", tmp_path / "key.pem"
    subprocess.run(
        ["openssl", "req", "-x509", "-newkey", "rsa:2048", "-nodes", "-days", "1",
         "-subj", "/CN=127.0.0.1", "-addext", "subjectAltName=IP:127.0.0.1",
         "-keyout", str(key), "-out", str(cert)],
        check=True, capture_output=True, timeout=60,
    )  # fmt: skip
    bridge, url = start_bridge(
        cli_env, "--address", "0.0.0.0", "--certfile", str(cert), "--keyfile", str(key)
    )
    try:
        assert url.startswith("wss://127.0.0.1:")
        bridge.expect("listening on 0.0.0.0: anyone who reaches it can read", stderr=True)
        trusting = ssl.create_default_context(cafile=str(cert))
        with Client(url, ssl=trusting) as client:
            assert client.server_info["op"] == "serverInfo"
        with connect(url, ssl=trusting) as rosbridge:  # a rosbridge client: wss:// as well
            rosbridge.send(json.dumps({"op": "call_service", "id": 1, "service": "/none"}))
            assert (
                json.loads(rosbridge.recv(timeout=30))["values"] == "Service /none does not exist"
            )
        with pytest.raises(ssl.SSLError):
            Client(url)  # a client that does not trust the certificate is not let in
    finally:
        bridge.stop()


def test_the_live_table_on_a_terminal(
    rostools_master: str, cli_env: dict[str, str], chatter: None
) -> None:
    import re
    import sys

    import pexpect

    argv = ["-m", "rostools", "bridge", "--port", "0"]
    child = pexpect.spawn(sys.executable, argv, env=cli_env, timeout=30, encoding="utf-8")
    try:
        child.expect(r"rostools bridge: ws://127\.0\.0\.1:(\d+)")
        url = f"ws://127.0.0.1:{child.match.group(1)}"
        with Client(url) as client:
            sub = client.subscribe("/chatter")
            client.receive(sub, 3)
            child.expect(r"1 clients, \d+ topics")
            child.expect(re.escape("/chatter"))
        child.sendintr()
        child.expect(pexpect.EOF)
    finally:
        child.close(force=True)
    assert child.exitstatus == 0


def test_clients_subscribing_at_once_get_each_message_once(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    pub = start_cli(
        "topic",
        "pub",
        "-r",
        "50",
        "/counted",
        "geometry_msgs/PointStamped",
        "{header: auto}",
        env=cli_env,
    )
    bridge, url = start_bridge(cli_env)
    try:
        clients = [Client(url) for _ in range(4)]
        try:
            subs = [c.subscribe("/counted") for c in clients]  # four at once, none read yet
            for client, sub in zip(clients, subs, strict=True):
                seqs = [struct.unpack_from("<I", p)[0] for _, p in client.receive(sub, 20)]
                assert len(set(seqs)) == len(seqs), f"a message came twice: {seqs}"
        finally:
            for client in clients:
                client.close()
    finally:
        bridge.stop()
        pub.stop()


def test_no_master_is_one_line_and_exit_4(cli_env: dict[str, str]) -> None:
    done = run_cli("bridge", "--port", "0", env=cli_env)  # cli_env's master: the discard port
    assert done.returncode == 4
    assert (
        done.stderr.startswith("rostools: cannot reach the master") and done.stderr.count("\n") == 1
    )


def test_a_client_that_leaves_is_reported_with_what_it_was_sent(
    rostools_master: str, cli_env: dict[str, str], chatter: None
) -> None:
    bridge, url = start_bridge(cli_env)
    try:
        with Client(url) as client:
            sub = client.subscribe("/chatter")
            received = len(client.receive(sub, 3))
        left = json.loads(bridge.expect(r'"event": ?"disconnected"', 15))
        assert left["messages"] >= received and left["bytes"] >= received * 6
    finally:
        bridge.stop()
