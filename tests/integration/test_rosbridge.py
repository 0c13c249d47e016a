"""``rostools bridge`` speaking rosbridge v2, with our master and nodes, through websockets' own
client: one port for both protocols, the encodings, fragments, statuses and their levels, and
what a client may not do. The real clients (roslib, roslibpy, rospy) and parity with the real
rosbridge_server are ``tests/interop/test_rosbridge_peer.py``'s.
"""

from __future__ import annotations

import base64
import json
import struct
import time
from collections.abc import Iterator
from typing import Any

import pytest
from websockets.exceptions import InvalidStatus
from websockets.sync.client import ClientConnection, connect

from tests.support.foxglove import V1, Client, ros_string, start_bridge
from tests.support.load import scaled
from tests.support.procs import Proc, publishers, start_cli, subscribers, wait_for
from tests.support.rosbridge_parity import Session, _is

Message = dict[str, Any]


@pytest.fixture
def chatter(cli_env: dict[str, str], rostools_master: str) -> Iterator[None]:
    """``/chatter``: std_msgs/String "hi" at 20 Hz, on the test's master."""
    pub = start_cli(
        "topic", "pub", "-r", "20", "/chatter", "std_msgs/String", "data: hi", env=cli_env
    )
    try:
        wait_for(lambda: bool(publishers(rostools_master, "/chatter")), 15, "/chatter")
        yield
    finally:
        pub.stop()


@pytest.fixture
def bridge(cli_env: dict[str, str], rostools_master: str) -> Iterator[tuple[Proc, str]]:
    """``rostools bridge`` (both protocols) on the test's master; its URL."""
    proc, url = start_bridge(cli_env)
    try:
        yield proc, url
    finally:
        proc.stop()


def rosbridge(url: str) -> ClientConnection:
    """A client that offers no subprotocol: a rosbridge one."""
    return connect(url, open_timeout=scaled(10), max_size=None, compression=None)


def subscribe(s: Session, **fields: Any) -> None:
    s.send({"op": "subscribe", "topic": "/chatter", "type": "std_msgs/String", **fields})


def test_one_port_serves_both_protocols(chatter: None, bridge: tuple[Proc, str]) -> None:
    _, url = bridge
    with Client(url, V1) as fox, rosbridge(url) as ws:
        assert fox.ws.subprotocol == V1 and ws.subprotocol is None
        s = Session(ws)
        subscribe(s, id="s1")
        got = s.until(_is("publish", topic="/chatter"))
        assert got == {"op": "publish", "topic": "/chatter", "msg": {"data": "hi"}}
        sub = fox.subscribe("/chatter")
        (_, payload), *_ = fox.receive(sub, 2)
        assert payload == ros_string("hi")
        # the Foxglove client is told of channels; the rosbridge one only what it asked for
        assert all(m.get("op") == "publish" for m in s.inbox)


@pytest.mark.parametrize("protocol", ["foxglove", "rosbridge"])
def test_protocol_restricts_what_clients_get(
    cli_env: dict[str, str], rostools_master: str, chatter: None, protocol: str
) -> None:
    proc, url = start_bridge(cli_env, "--protocol", protocol)
    try:
        if protocol == "foxglove":
            with pytest.raises(InvalidStatus) as refused:
                rosbridge(url)
            assert refused.value.response.status_code == 400
            with Client(url, V1) as fox:
                assert fox.ws.subprotocol == V1
        else:
            with connect(url, subprotocols=[V1], open_timeout=scaled(10)) as ws:  # type: ignore[list-item]
                assert ws.subprotocol is None  # a Foxglove client is not spoken to in its protocol
                s = Session(ws)
                subscribe(s)
                assert s.until(_is("publish", topic="/chatter"))["msg"] == {"data": "hi"}
    finally:
        proc.stop()


def test_bad_input_is_answered_by_a_status_with_the_ops_id(bridge: tuple[Proc, str]) -> None:
    _, url = bridge
    with rosbridge(url) as ws:
        s = Session(ws)
        s.send({"op": "no_such_op", "id": "u1"})
        status = s.until(_is("status", id="u1"))
        assert status["level"] == "error" and "unknown op 'no_such_op'" in status["msg"]
        s.send('{"op": "publish", "topic"')
        assert "not a JSON message" in s.until(_is("status"))["msg"]
        s.send({"op": "subscribe", "id": "s2"})
        assert s.until(_is("status", id="s2"))["msg"] == (
            "subscribe: expected a topic field but none was found"
        )
        s.send({"op": "publish", "id": "p1", "topic": "/x", "msg": {"data": 1}})
        assert "its type is not known: advertise it first" in s.until(_is("status", id="p1"))["msg"]
        s.send({"op": "advertise", "id": "a1", "topic": "/x", "type": "std_msgs/String"})
        s.send({"op": "publish", "id": "p2", "topic": "/x", "msg": {"data": 1}})
        assert s.until(_is("status", id="p2"))["msg"] == (
            "publish: /x: std_msgs/String message requires a string for field data, "
            "but got a <class 'int'>"
        )
        s.ws.send(b"\x00\x01")
        assert "binary messages are not understood" in s.until(_is("status"))["msg"]
        # an id that cannot key a subscription (the defect: a TypeError ended the client)
        s.send({"op": "subscribe", "id": ["a"], "topic": "/x", "type": "std_msgs/String"})
        assert "id must be a string or a number" in s.until(_is("status"))["msg"]
        s.send({"op": "no_such_op", "id": "still here"})
        assert s.until(_is("status", id="still here"))


def test_set_level_chooses_which_statuses_a_client_hears(bridge: tuple[Proc, str]) -> None:
    _, url = bridge
    with rosbridge(url) as ws:
        s = Session(ws)
        s.send({"op": "set_level", "id": "l1", "level": "loud"})
        assert "'loud' is not one of info, warning, error, none" in s.until(_is("status"))["msg"]
        s.send({"op": "unadvertise", "id": "w1", "topic": "/never"})  # a warning
        s.send({"op": "no_such_op", "id": "e1"})
        assert s.until(_is("status"))["id"] == "e1"  # at "error", the warning is not heard
        s.send({"op": "set_level", "level": "warning"})
        s.send({"op": "unadvertise", "id": "w2", "topic": "/never"})
        assert s.until(_is("status"))["level"] == "warning"
        s.send({"op": "set_level", "level": "none"})
        s.send({"op": "no_such_op", "id": "e2"})
        s.send({"op": "call_service", "id": "c1", "service": "/no_such_service"})
        answer = s.until(_is("service_response", id="c1"))
        assert answer["values"] == "Service /no_such_service does not exist"
        assert not answer["result"] and not [m for m in s.inbox if m.get("op") == "status"]


def test_cbor_raw_sends_the_tcpros_bytes_with_the_time_they_came(
    chatter: None, bridge: tuple[Proc, str]
) -> None:
    _, url = bridge
    with rosbridge(url) as ws:
        s = Session(ws)
        before = time.time()
        s.send({"op": "subscribe", "topic": "/chatter", "compression": "cbor-raw"})
        frame = s.until(lambda m: "cbor" in m)["cbor"]
        assert (frame["op"], frame["topic"]) == ("publish", "/chatter")
        raw = frame["msg"]
        assert bytes.fromhex(raw["bytes"]["bytes"]) == ros_string("hi")
        assert before - 1 <= raw["secs"] + raw["nsecs"] / 1e9 <= time.time() + 1


def test_png_compression_is_the_json_in_an_image(chatter: None, bridge: tuple[Proc, str]) -> None:
    _, url = bridge
    with rosbridge(url) as ws:
        s = Session(ws)
        subscribe(s, compression="png")
        png = base64.b64decode(s.until(_is("png"))["data"])
        assert png.startswith(b"\x89PNG") and b"IDAT" in png


def test_fragments_out_and_in(chatter: None, bridge: tuple[Proc, str]) -> None:
    _, url = bridge
    with rosbridge(url) as ws:
        s = Session(ws)
        subscribe(s, fragment_size=10)
        first = s.until(_is("fragment", num=0))
        parts = [first] + [
            s.until(_is("fragment", id=first["id"], num=n)) for n in range(1, first["total"])
        ]
        whole = json.loads("".join(p["data"] for p in parts))
        assert whole == {"op": "publish", "topic": "/chatter", "msg": {"data": "hi"}}
        s.send({"op": "unsubscribe", "topic": "/chatter", "fragment_size": 100000})
        call = json.dumps({"op": "call_service", "id": "c9", "service": "/nothing_here"})
        # a client's own fragments, sent last one first
        pieces = [call[n : n + 7] for n in range(0, len(call), 7)]
        for num in reversed(range(len(pieces))):
            s.send({"op": "fragment", "id": "f1", "data": pieces[num], "num": num,
                    "total": len(pieces)})  # fmt: skip
        assert s.until(_is("service_response", id="c9"))["values"] == (
            "Service /nothing_here does not exist"
        )


def test_throttle_rate_and_queue_length(chatter: None, bridge: tuple[Proc, str]) -> None:
    _, url = bridge
    with rosbridge(url) as ws:
        s = Session(ws)
        subscribe(s, id="slow", throttle_rate=1000, queue_length=1)
        s.until(_is("publish", topic="/chatter"))
        began = time.monotonic()
        s.until(_is("publish", topic="/chatter"))
        s.until(_is("publish", topic="/chatter"))
        # two more at 20 Hz would take 0.1 s; at most one a second, they take over one
        assert time.monotonic() - began > 1.0
        subscribe(s, id="fast")  # the lowest throttle of a client's subscriptions wins
        s.inbox.clear()
        for _ in range(10):
            s.until(_is("publish", topic="/chatter"))


def test_a_client_that_floods_costs_only_itself(chatter: None, bridge: tuple[Proc, str]) -> None:
    _, url = bridge
    with rosbridge(url) as quiet, rosbridge(url) as noisy:
        s = Session(quiet)
        subscribe(s)
        s.until(_is("publish", topic="/chatter"))
        for n in range(2000):  # refused, each with a status it never reads
            noisy.send(json.dumps({"op": "no_such_op", "id": n}))
        s.inbox.clear()
        for _ in range(10):
            s.until(_is("publish", topic="/chatter"))


def test_read_only_refuses_what_writes(cli_env: dict[str, str], rostools_master: str) -> None:
    proc, url = start_bridge(cli_env, "--read-only")
    try:
        with rosbridge(url) as ws:
            s = Session(ws)
            s.send({"op": "advertise", "id": "a", "topic": "/w", "type": "std_msgs/String"})
            assert "read-only" in s.until(_is("status", id="a"))["msg"]
            s.send({"op": "advertise_service", "id": "b", "service": "/w",
                    "type": "std_srvs/Empty"})  # fmt: skip
            assert "read-only" in s.until(_is("status", id="b"))["msg"]
            s.send({"op": "call_service", "id": "c", "service": "/rosout/get_loggers"})
            answer = s.until(_is("service_response", id="c"))
            assert answer["values"] == "this bridge is read-only (--read-only)"
    finally:
        proc.stop()


def test_a_ros_node_calls_a_service_a_web_client_serves(
    cli_env: dict[str, str], bridge: tuple[Proc, str]
) -> None:
    _, url = bridge
    with rosbridge(url) as ws:
        s = Session(ws)
        s.send({"op": "advertise_service", "service": "/add", "type": "rospy_tutorials/AddTwoInts"})
        call = start_cli("service", "call", "--wait", "/add", "a: 2\nb: 40", env=cli_env)
        try:
            request = s.until(_is("call_service", service="/add"))
            assert request["id"] == "service_request:/add:1" and request["args"] == {
                "a": 2,
                "b": 40,
            }
            s.send({"op": "service_response", "service": "/add", "id": request["id"],
                    "values": {"sum": 42}, "result": True})  # fmt: skip
            call.expect(r"sum: 42", scaled(20))
        finally:
            call.stop()


def test_a_cbor_frame_carries_typed_arrays(
    cli_env: dict[str, str], bridge: tuple[Proc, str]
) -> None:
    _, url = bridge
    pub = start_cli("topic", "pub", "-r", "10", "/floats", "std_msgs/Float32MultiArray",
                    "data: [1.5, -2.0]", env=cli_env)  # fmt: skip
    try:
        with rosbridge(url) as ws:
            s = Session(ws)
            s.send({"op": "subscribe", "topic": "/floats", "type": "std_msgs/Float32MultiArray",
                    "compression": "cbor"})  # fmt: skip
            got = s.until(lambda m: "cbor" in m)["cbor"]["msg"]["data"]
            assert got["tag"] == 85
            assert struct.unpack("<2f", bytes.fromhex(got["value"]["bytes"])) == (1.5, -2.0)
    finally:
        pub.stop()


def test_a_big_image_in_each_encoding(bridge: tuple[Proc, str], rostools_master: str) -> None:
    import rostools

    pixels = bytes(range(256)) * 1200  # 300 KiB: past the size written without a copy
    image = {"height": 200, "width": 512, "encoding": "rgb8", "step": 1536, "data": pixels}
    _, url = bridge
    with rostools.Node("big_images", rostools_master) as node, rosbridge(url) as ws:
        node.publish("/image", image, "sensor_msgs/Image", latch=True)
        s = Session(ws)
        for compression in ("cbor-raw", "cbor", "none"):
            s.send({"op": "subscribe", "topic": "/image", "type": "sensor_msgs/Image",
                    "compression": compression})  # fmt: skip
            if compression == "none":
                got = s.until(lambda m: m.get("op") == "publish")["msg"]
                assert base64.b64decode(got["data"]) == pixels and got["width"] == 512
            else:
                msg = s.until(lambda m: "cbor" in m)["cbor"]["msg"]
                if compression == "cbor-raw":
                    assert bytes.fromhex(msg["bytes"]["bytes"]).endswith(pixels)
                else:
                    assert bytes.fromhex(msg["data"]["bytes"]) == pixels
            s.send({"op": "unsubscribe", "topic": "/image"})
            s.inbox.clear()


def test_a_publish_right_after_advertise_reaches_a_subscriber_already_waiting(
    rostools_master: str, bridge: tuple[Proc, str]
) -> None:
    # the defect: the subscriber connected after the one publish, which was lost (rosbridge
    # keeps a new publisher's first second of messages for subscribers still connecting)
    import queue

    import rostools

    _, url = bridge
    got: queue.Queue[str] = queue.Queue()
    with rostools.Node("early_listener", rostools_master) as node, rosbridge(url) as ws:
        node.subscribe("/early", lambda m: got.put(m.data), "std_msgs/String")
        wait_for(lambda: bool(subscribers(rostools_master, "/early")), 15, "the subscriber")
        s = Session(ws)
        s.send({"op": "advertise", "topic": "/early", "type": "std_msgs/String"})
        s.send({"op": "publish", "topic": "/early", "msg": {"data": "only once"}})
        assert got.get(timeout=scaled(20)) == "only once"
