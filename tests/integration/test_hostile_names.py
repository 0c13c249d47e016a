"""Names from peers and files with line breaks and terminal escapes: one line each in text.

Through the master (see ``tests.support.hostilenames``), a publisher's header and a bag.
Text output escapes them all (``\\n``, ``\\x1b``...); ``--format json`` gives them raw.
"""

from __future__ import annotations

import json
import socket
import struct
from pathlib import Path
from typing import Any

import pytest
import yaml

from tests.support.env import run_cli
from tests.support.fakepeer import STRING_MD5, FakePublisher, frame
from tests.support.hostilenames import (
    NASTY,
    NODE,
    PARAM,
    RAW,
    RAW_SHOWN,
    SERVICE,
    SHOWN,
    TOPIC,
    TYPE,
    URDF,
    call,
    cli,
    register,
    shown,
)


@pytest.fixture
def hostile(rostools_master: str) -> str:
    """The hostile registrations (``hostilenames.register``); the dead URI."""
    return register(rostools_master)


def test_graph_names_are_escaped_in_text(hostile: str, cli_env: dict[str, str]) -> None:
    # before: each of these printed the names raw, "/x" and "/y" on lines of their own
    out, _ = cli(cli_env, "topic", "list")
    assert shown(TOPIC) in out and "/plain" in out
    out, _ = cli(cli_env, "topic", "list", "-v")
    assert f" * {shown(TOPIC)} [{shown(TYPE)}] 1 publisher" in out
    assert f" * {shown(TOPIC)} [{shown(TYPE)}] 1 subscriber" in out
    out, _ = cli(cli_env, "topic", "info", "/plain")
    publisher = f" * {shown(NODE)} ({shown(hostile)})"
    assert out[:4] == [f"Type: {shown(TYPE)}", "", "Publishers: ", publisher]
    out, _ = cli(cli_env, "topic", "type", "/plain")
    assert out == [shown(TYPE)]
    out, _ = cli(cli_env, "topic", "find", TYPE)
    assert out == ["/plain", shown(TOPIC)]
    out, _ = cli(cli_env, "topic", "list", "--host")
    assert out[0] == "Host [127.0.0.1]:" and f"  {shown(TOPIC)}" in out
    out, _ = cli(cli_env, "node", "list")
    assert shown(NODE) in out and "/legal" in out
    out, _ = cli(cli_env, "node", "list", "-a")
    assert f"{shown(hostile)} \t{shown(NODE)}" in out
    # /legal cannot be contacted (exit 4; it was an internal error, exit 1, as its URI's path
    # could not be encoded); what the master says of it is printed first
    out, err = cli(cli_env, "node", "info", "/legal", code=4)
    assert f" * {shown(TOPIC)} [{shown(TYPE)}]" in out
    assert f" * {shown(SERVICE)}" in out
    assert f"contacting node {shown(hostile)} ..." in out
    assert len(err) == 1 and err[0].startswith("rostools: "), err
    out, _ = cli(cli_env, "service", "list")
    assert shown(SERVICE) in out
    out, _ = cli(cli_env, "service", "list", "-n")
    assert f"{shown(SERVICE)} /legal" in out
    out, _ = cli(cli_env, "param", "list")
    assert shown(PARAM) in out
    out, _ = cli(cli_env, "node", "graph")
    assert f"    └── {shown(TOPIC)} [{shown(TYPE)}] → /legal" in out
    assert shown(NODE) in out
    out, _ = cli(cli_env, "node", "graph", "-F", "dot")
    assert f'  "t:{shown(TOPIC)}" -> "n:/legal";' in out
    # the nodes' URI had its path refused by http.client: "it does not speak the ROS XML-RPC
    # API (UnicodeEncodeError)"; now the path is percent-encoded and the port refuses
    out, _ = cli(cli_env, "doctor", "-t", "2", code=4)
    nodes = next(line for line in out if line.startswith("FAIL  nodes"))
    assert f"{shown(NODE)} at {shown(hostile)} (connection refused at 127.0.0.1" in nodes, out


def test_parameter_values_are_data_and_stay_as_they_are(
    hostile: str, cli_env: dict[str, str]
) -> None:
    # a URDF's line breaks are its own: param get prints the value's YAML, and -p the text
    # as it is, as rosparam -p does
    from rostools.cli.param.plainyaml import dump

    done = run_cli("param", "get", "/urdf", env=cli_env)
    assert done.returncode == 0, done.stderr
    assert done.stdout == dump(URDF) + "\n"
    assert yaml.safe_load(done.stdout) == URDF
    done = run_cli("param", "get", "/urdf", "-p", env=cli_env)
    assert (done.returncode, done.stdout) == (0, URDF + "\n"), done.stderr


def test_json_keeps_the_names_raw(hostile: str, cli_env: dict[str, str]) -> None:
    def data(*args: str) -> Any:
        done = run_cli(*args, "-F", "json", env=cli_env)
        assert done.returncode == 0, done.stderr
        return json.loads(done.stdout)

    assert {"topic": TOPIC, "type": TYPE, "publishers": [NODE], "subscribers": ["/legal"]} in (
        data("topic", "list")
    )
    info = data("topic", "info", "/plain")
    assert (info["type"], info["publishers"]) == (TYPE, [{"node": NODE, "uri": hostile}])
    assert NODE in data("node", "list")
    assert {"service": SERVICE, "nodes": ["/legal"]} in data("service", "list")
    assert PARAM in data("param", "list")


def test_notices_and_bag_record_escape_peer_names(hostile: str, cli_env: dict[str, str]) -> None:
    # the notice was escaped by one_line's move to errors.py. Its reason was "it does not
    # speak the ROS XML-RPC API ('latin-1' codec can't encode character '\u2028' ...)": the
    # URI's path went into the request line as it was, and is now percent-encoded
    _, err = cli(cli_env, "topic", "echo", "/plain", "--timeout", "3", code=5)
    told = [line for line in err if "cannot connect to" in line]
    assert len(told) == 1, err
    assert told[0].startswith(
        f"rostools: cannot connect to {shown(NODE)} at {shown(hostile)} (publisher of /plain): "
        "connection refused at 127.0.0.1"
    ), told
    # before: "Subscribing to /x" and "/y" on two lines
    bag = Path(cli_env["HOME"]).parent / "all.bag"
    _, err = cli(cli_env, "bag", "record", "-a", "--duration", "2", "-O", str(bag))
    assert f"Subscribing to {shown(TOPIC)}" in err, err


def hostile_header(sock: socket.socket) -> None:
    """A publisher's reply whose caller id and type hold ESC and CR, then one message."""
    from rostools.wire.tcpros import publisher_header

    header = publisher_header(
        "/fake" + RAW, "/hdr", STRING_MD5, "std_msgs/Str" + RAW + "ing", "string data\n", False
    )
    sock.sendall(header + frame(struct.pack("<I", 2) + b"hi"))


def test_header_and_bag_names_are_escaped(
    rostools_master: str, cli_env: dict[str, str], tmp_path: Path
) -> None:
    # before: the summary printed the header's type raw, ESC and CR included
    bag = tmp_path / "hdr.bag"
    with FakePublisher(rostools_master, "/hdr", hostile_header):
        _, err = cli(cli_env, "bag", "record", "/hdr", "-l", "1", "-O", str(bag))
    # the summary gives the type recorded, the header's (not the master's: issue 32), escaped
    assert f"  /hdr [std_msgs/Str{RAW_SHOWN}ing]: 1 msg" in err, err
    assert "\x1b" not in err and "\r" not in err, err
    out, _ = cli(cli_env, "bag", "info", str(bag))
    assert f"types:       std_msgs/Str{RAW_SHOWN}ing [{STRING_MD5}]" in out
    assert out[-1].startswith("topics:      /hdr   1 msg"), out
    assert out[-1].endswith(f" : std_msgs/Str{RAW_SHOWN}ing"), out
    done = run_cli("bag", "info", str(bag), "-F", "json", env=cli_env)
    assert json.loads(done.stdout)["topics"][0]["type"] == "std_msgs/Str" + RAW + "ing"


def test_bag_topic_names_are_escaped(cli_env: dict[str, str], tmp_path: Path) -> None:
    from rostools.bag.formats.access import open_writer

    topic = "/b" + RAW + NASTY
    bag = tmp_path / "names.bag"
    with open_writer(bag) as writer:
        conn = writer.add_connection(topic, "std_msgs/String", STRING_MD5, "string data\n",
                                     callerid="/w" + RAW)  # fmt: skip
        writer.write(conn, 1, struct.pack("<I", 2) + b"hi")
    escaped = "/b" + RAW_SHOWN + SHOWN
    out, _ = cli(cli_env, "topic", "list", "-b", str(bag))
    assert out == [escaped]
    out, _ = cli(cli_env, "bag", "info", str(bag))
    assert any(line.startswith(f"topics:      {escaped}   1 msg") for line in out), out
    done = run_cli("topic", "list", "-b", str(bag), "-F", "json", env=cli_env)
    assert json.loads(done.stdout) == [{"topic": topic, "type": "std_msgs/String"}]


def test_a_host_name_with_a_line_separator_is_a_name_that_does_not_resolve(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    # before: node info and node ping ended in "internal error: UnicodeEncodeError" (exit 1),
    # and echo said the node "does not speak the ROS XML-RPC API"
    call(
        rostools_master,
        "registerPublisher",
        "/hosty",
        "/t",
        "std_msgs/String",
        "http://h\u2028x:1/",
    )
    _, err = cli(cli_env, "node", "info", "/hosty", code=4)
    assert err == [
        "rostools: cannot reach the node /hosty at http://h\\u2028x:1/: 'h\\u2028x' is not a "
        "host name"
    ]
    _, err = cli(cli_env, "node", "ping", "-c", "1", "/hosty", code=4)
    assert err[-1].endswith("'h\\u2028x' is not a host name"), err
    _, err = cli(cli_env, "topic", "echo", "/t", "--timeout", "3", code=5)
    assert (
        "rostools: cannot connect to /hosty at http://h\\u2028x:1/ (publisher of /t): "
        "h\\u2028x does not resolve here; set ROS_IP or ROS_HOSTNAME on that host to an address "
        "others reach it at"
    ) in err, err
