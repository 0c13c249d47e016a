"""A publisher that sends a message that does not decode: the live commands say so and go on.

rostopic echo carries on past such a message; ours skip it with one notice naming the
publisher, unless ``--strict`` asks them to stop (exit 1), as a CI job may.
"""

from __future__ import annotations

import json
import socket
import struct
import time

import pytest

from rostools.msgs.store import BuiltinSource, TypeStore
from rostools.msgs.topictype import TopicType
from rostools.wire.tcpros import publisher_header
from tests.support.fakepeer import FakePublisher, frame, header_type_header, valid_header
from tests.support.procs import start_cli

#: The audit's frame: a string whose length says 2 GiB, and four bytes of it.
LYING_STRING = bytes.fromhex("ffffff7f61626364")


def _string(text: str) -> bytes:
    return frame(struct.pack("<I", len(text)) + text.encode())


def _header(seq: int) -> bytes:
    now = time.time()
    return frame(struct.pack("<III", seq, int(now), int(now % 1 * 1e9)) + struct.pack("<I", 0))


def _run(cli_env: dict[str, str], *argv: str) -> tuple[int, str, str]:
    proc = start_cli(*argv, env=cli_env)
    try:
        code = proc.popen.wait(30)
        out, err = proc.output()
    finally:
        proc.stop()
    return code, out, err


def _strings_with_a_lie(sock: socket.socket) -> None:
    sock.sendall(valid_header("/t") + _string("before") + frame(LYING_STRING))
    for i in range(50):
        sock.sendall(_string(f"after{i}") + frame(LYING_STRING))
        time.sleep(0.02)


@pytest.mark.parametrize("fmt", ["text", "json"])
def test_echo_skips_a_message_that_does_not_decode(
    rostools_master: str, cli_env: dict[str, str], fmt: str
) -> None:
    # the defect: the first such message ended echo with exit 1
    with FakePublisher(rostools_master, "/t", _strings_with_a_lie):
        code, out, err = _run(cli_env, "topic", "echo", "/t", "-n", "3", "--timeout", "20",
                              "--format", fmt)  # fmt: skip
    assert code == 0, err
    if fmt == "text":
        assert out.split("---\n")[:3] == [
            'data: "before"\n',
            'data: "after0"\n',
            'data: "after1"\n',
        ]
    else:
        records = [json.loads(line) for line in out.splitlines()]
        assert [r["data"] for r in records if "data" in r] == ["before", "after0", "after1"]
        event = next(r for r in records if r.get("event") == "message_skipped")
        assert event["node"] == "/fake"
    lines = [line for line in err.splitlines() if "skipped" in line]
    assert lines[0] == (
        "rostools: skipped a 8-byte message from /fake: a message on /t does not decode as "
        "std_msgs/String: message is shorter than its type says (--strict stops instead)"
    ), err
    assert lines[-1] == "rostools: skipped 2 messages that did not decode, from /fake", err
    assert "Traceback" not in err


def test_echo_strict_stops_at_the_first(rostools_master: str, cli_env: dict[str, str]) -> None:
    with FakePublisher(rostools_master, "/t", _strings_with_a_lie):
        code, out, err = _run(cli_env, "topic", "echo", "/t", "--strict", "--timeout", "20")
    assert code == 1
    assert out == 'data: "before"\n---\n'  # what came before it is printed
    assert err.splitlines()[-1].startswith(
        "rostools: a message on /t does not decode as std_msgs/String: "
    ), err


def test_hz_filter_skips_what_does_not_decode(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    with FakePublisher(rostools_master, "/t", _strings_with_a_lie):
        code, out, err = _run(cli_env, "topic", "hz", "/t", "--filter", "True", "--timeout",
                              "2.5", "--format", "json")  # fmt: skip
    assert code == 0, err
    assert "skipped a 8-byte message from /fake" in err
    assert [json.loads(line)["topic"] for line in out.splitlines() if "rate" in line]


def _headers_with_short_ones(sock: socket.socket) -> None:
    sock.sendall(header_type_header("/h"))
    for i in range(60):
        sock.sendall(_header(i) + frame(b"\x01\x02"))
        time.sleep(0.02)


def _points_with_short_ones(sock: socket.socket) -> None:
    point = TopicType.of(TypeStore([BuiltinSource()]), "geometry_msgs/PointStamped")
    sock.sendall(publisher_header("/fake", "/p", point.md5sum, point.type, point.definition, False))
    for i in range(60):
        sock.sendall(frame(_header(i)[4:] + bytes(24)) + frame(b"\x01\x02"))
        time.sleep(0.02)


def test_delay_skips_a_message_too_short_for_its_stamp(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    # the defect: struct.error ended delay at the first short message
    kind = "geometry_msgs/PointStamped"
    with FakePublisher(rostools_master, "/p", _points_with_short_ones, msg_type=kind):
        code, out, err = _run(cli_env, "topic", "delay", "/p", "--timeout", "2.5", "--format",
                              "json")  # fmt: skip
    assert code == 0, err
    assert "rostools: skipped a 2-byte message from /fake: a message on /p is 2 bytes" in err
    assert [json.loads(line) for line in out.splitlines() if '"delay"' in line]


def test_plot_skips_and_counts_what_does_not_decode(
    rostools_master: str, cli_env: dict[str, str]
) -> None:
    with FakePublisher(rostools_master, "/h", _headers_with_short_ones, msg_type="std_msgs/Header"):
        code, out, err = _run(cli_env, "topic", "plot", "/h/seq", "-n", "5", "--timeout", "20",
                              "--format", "json")  # fmt: skip
    assert code == 0, err
    (record,) = [json.loads(line) for line in out.splitlines() if '"series"' in line]
    assert record["value"] == [0, 1, 2, 3, 4]
    assert "skipped a 2-byte message from /fake" in err
