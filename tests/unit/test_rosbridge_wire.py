"""rosbridge v2's bytes, sans-IO: CBOR out (checked with cbor2, which nobody here wrote),
rosbridge's values in, fragments both ways, statuses, and the PNG compression (read back
with zlib and the PNG layout)."""

from __future__ import annotations

import base64
import json
import struct
import zlib

import cbor2
import pytest

from rostools._api.messages import message, store
from rostools.msgs.codec import Codec
from rostools.msgs.rosbridge import RosbridgeFiller, RosbridgeValueError, cbor_values
from rostools.web.rbencode import png_text
from rostools.wire import cbor, rosbridge as rb


@pytest.mark.parametrize(
    "value",
    [0, 23, 24, 255, 256, 65535, 65536, 2**32, 2**64 - 1, -1, -25, -(2**64), 1.5, -0.0,
     float("inf"), "", "é" * 30, b"", b"\x00" * 300, [], [1, [2, "x"]], {"a": {"b": None}},
     True, False, None],
)  # fmt: skip
def test_cbor_reads_back_as_it_was_written(value: object) -> None:
    assert cbor2.loads(cbor.dumps(value)) == value


def test_cbor_tags_and_what_it_refuses() -> None:
    decoded = cbor2.loads(cbor.dumps(cbor.Tag(85, b"\x00\x00\x80?")))
    assert (decoded.tag, decoded.value) == (85, b"\x00\x00\x80?")
    with pytest.raises(TypeError, match="CBOR cannot hold a set"):
        cbor.dumps({1, 2})
    with pytest.raises(ValueError, match="does not fit"):
        cbor.dumps(2**64)


def test_a_message_in_cbor_as_rosbridge_writes_it() -> None:
    codec = Codec.of(store())
    msg = message("sensor_msgs/PointCloud2", {
        "header": {"stamp": {"secs": 3, "nsecs": 4}, "frame_id": "map"},
        "fields": [{"name": "x", "offset": 0, "datatype": 7, "count": 1}],
        "data": b"\x01\x02", "is_dense": True,
    })  # fmt: skip
    values = cbor2.loads(cbor.dumps(cbor_values(codec, "sensor_msgs/PointCloud2")(msg)))
    assert values["header"] == {"seq": 0, "stamp": {"secs": 3, "nsecs": 4}, "frame_id": "map"}
    assert values["fields"] == [{"name": "x", "offset": 0, "datatype": 7, "count": 1}]
    assert (values["data"], values["is_dense"]) == (b"\x01\x02", True)
    floats = message("std_msgs/Float32MultiArray", {"data": [1.0, -2.5]})
    tagged = cbor2.loads(cbor.dumps(cbor_values(codec, "std_msgs/Float32MultiArray")(floats)))
    assert tagged["data"].tag == 85  # RFC 8746 float32 little-endian, rosbridge's tag
    assert struct.unpack("<2f", tagged["data"].value) == (1.0, -2.5)


def test_values_in_fill_a_message_as_rosbridge_populates_one() -> None:
    filler = RosbridgeFiller(Codec.of(store()))
    image = filler.message("sensor_msgs/Image", {
        "data": base64.b64encode(b"\x00\xff").decode(), "height": 2,
        "header": {"stamp": {"secs": 7, "nsecs": 1}},
    })  # fmt: skip
    assert (image.data, image.height, image.header.stamp.secs, image.encoding) == (
        b"\x00\xff",
        2,
        7,
        "",
    )
    assert filler.message("std_msgs/ColorRGBA", [0.5, 1]).g == 1.0  # a list: field order
    assert filler.message("std_msgs/UInt8MultiArray", {"data": [1, 2]}).data == b"\x01\x02"


@pytest.mark.parametrize(
    ("type_name", "values", "said"),
    [
        ("std_srvs/SetBoolRequest", {"dta": True},
         "Message type std_srvs/SetBoolRequest does not have a field dta"),
        ("geometry_msgs/PoseStamped", {"pose": {"position": {"q": 1}}},
         "Message type geometry_msgs/Point does not have a field pose.position.q"),
        ("std_msgs/String", {"data": 5},
         "std_msgs/String message requires a string for field data, but got a <class 'int'>"),
        ("std_msgs/Header", {"stamp": "now"},
         "std_msgs/Header message requires a time for field stamp, but got a <class 'str'>"),
        ("sensor_msgs/Image", {"data": "not base64!"},
         "sensor_msgs/Image message requires a uint8[] for field data, but got a <class 'str'>"),
    ],
)  # fmt: skip
def test_values_that_do_not_fit_are_named_as_rosbridge_names_them(
    type_name: str, values: dict[str, object], said: str
) -> None:
    types = store()
    types.srv("std_srvs/SetBool")  # its request's type is known once the service's is read
    with pytest.raises(RosbridgeValueError) as err:
        RosbridgeFiller(Codec.of(types)).message(type_name, values)
    assert str(err.value) == said


def test_a_client_message_must_be_an_object_with_an_op() -> None:
    assert rb.parse('{"op": "publish", "id": 3}') == {"op": "publish", "id": 3}
    for text, said in [
        ('{"op": "x"', "not a JSON message"),
        ("[1]", "must be a JSON object, not list"),
        ('{"id": "a"}', "a message without an op"),
        ('{"op": 5}', "op must be a string"),
        ('{"op": "subscribe", "id": ["a"]}', "id must be a string or a number"),
    ]:
        with pytest.raises(rb.ProtocolError, match=said):
            rb.parse(text)
    with pytest.raises(rb.ProtocolError, match="subscribe: expected a topic field") as err:
        rb.need({"op": "subscribe", "id": "s1"}, "topic", str)
    assert err.value.ident == "s1"
    with pytest.raises(rb.ProtocolError, match="throttle_rate must be an integer, not true"):
        rb.need({"op": "subscribe", "throttle_rate": True}, "throttle_rate", int)


def test_status_levels() -> None:
    assert rb.status("error", "no", "id1") == {"op": "status", "id": "id1", "level": "error",
                                               "msg": "no"}  # fmt: skip
    assert rb.heard("error", "warning") and not rb.heard("info", "warning")
    assert not rb.heard("error", "none")


def test_fragments_cut_and_put_together_again() -> None:
    text = json.dumps({"op": "publish", "topic": "/a", "msg": {"data": "x" * 100}})
    parts = [json.loads(p) for p in rb.fragments(text, 30, 7)]
    assert [p["num"] for p in parts] == list(range(len(parts)))
    assert {p["total"] for p in parts} == {len(parts)} and {p["id"] for p in parts} == {7}
    assert "".join(p["data"] for p in parts) == text
    whole = rb.Fragments()
    got = [whole.add({"op": "fragment", **p}) for p in reversed(parts)]  # any order
    assert got[:-1] == [None] * (len(parts) - 1) and got[-1] == text


def test_fragment_sets_are_bounded() -> None:
    frags = rb.Fragments()
    big = "x" * (1 << 20)
    with pytest.raises(rb.ProtocolError, match="over 16 MiB: dropped"):
        for n in range(17):
            frags.add({"op": "fragment", "id": "a", "data": big, "num": n, "total": 100})
    for n in range(rb.MAX_FRAGMENT_SETS):
        frags.add({"op": "fragment", "id": n, "data": "x", "num": 0, "total": 2})
    with pytest.raises(rb.ProtocolError, match="more than 16 fragmented messages"):
        frags.add({"op": "fragment", "id": "late", "data": "x", "num": 0, "total": 2})
    with pytest.raises(rb.ProtocolError, match="num 5 is not within total 2"):
        frags.add({"op": "fragment", "id": 0, "data": "x", "num": 5, "total": 2})


def _png_pixels(data: bytes) -> tuple[int, int, bytes]:
    assert data[:8] == b"\x89PNG\r\n\x1a\n"
    pos, chunks = 8, {}
    while pos < len(data):
        (length,), kind = struct.unpack(">I", data[pos : pos + 4]), data[pos + 4 : pos + 8]
        body = data[pos + 8 : pos + 8 + length]
        assert struct.unpack(">I", data[pos + 8 + length : pos + 12 + length])[0] == zlib.crc32(
            kind + body
        )
        chunks[kind] = body
        pos += 12 + length
    width, height, depth, color = struct.unpack(">IIBB", chunks[b"IHDR"][:10])
    assert (depth, color) == (8, 2)
    rows = zlib.decompress(chunks[b"IDAT"])
    row = 1 + width * 3
    assert all(rows[y * row] == 0 for y in range(height))  # no filter
    return width, height, b"".join(rows[y * row + 1 : (y + 1) * row] for y in range(height))


def test_png_compression_holds_the_text_padded_with_newlines() -> None:
    text = json.dumps({"op": "publish", "topic": "/a", "msg": {"data": "é" * 50}})
    width, _, pixels = _png_pixels(base64.b64decode(png_text(text)))
    assert width == int((len(text.encode()) / 3) ** 0.5)
    assert pixels.rstrip(b"\n").decode() == text
    assert _png_pixels(base64.b64decode(png_text("a")))[2] == b"a\n\n"


def test_cbor_raw_is_a_head_and_the_frame_as_it_came() -> None:
    from rostools.web.rbencode import Encoders

    frame = memoryview(b"\x02\x00\x00\x00hi" * 40_000)
    head, same = Encoders(store()).encode("/t", None, "cbor-raw", 3 * 10**9 + 7, frame)
    assert same is frame  # not copied: the socket writes it after the head
    assert cbor2.loads(head + bytes(frame)) == {
        "op": "publish", "topic": "/t", "msg": {"secs": 3, "nsecs": 7, "bytes": bytes(frame)},
    }  # fmt: skip


def test_an_op_that_fails_unforeseen_is_a_status_and_the_client_goes_on() -> None:
    import asyncio
    from types import SimpleNamespace
    from typing import Any

    from rostools.web.rbclient import RosbridgeClient
    from rostools.web.rosbridge import RosbridgeOps

    class Quick:
        def __init__(self) -> None:
            self.sent: list[str | bytes] = []

        async def send(self, message: str | bytes) -> None:
            self.sent.append(message)

    async def scenario() -> list[str | bytes]:
        events: list[dict[str, Any]] = []
        bridge = SimpleNamespace(node=None, store=store(), event=lambda k, **f: events.append(f))
        services = SimpleNamespace(
            op_call_service=None, op_service_response=None, op_advertise_service=None,
            op_unadvertise_service=None,
        )  # fmt: skip
        ops = RosbridgeOps(bridge, services)  # type: ignore[arg-type]

        async def broken(client: RosbridgeClient, request: dict[str, Any]) -> None:
            raise KeyError("nothing foresaw this")

        ops.handlers["subscribe"] = broken
        socket = Quick()
        client = RosbridgeClient(socket, "c", lambda c: None)
        await ops.handle(client, json.dumps({"op": "subscribe", "id": "s1", "topic": "/t"}))
        await ops.handle(client, json.dumps({"op": "no_such_op", "id": "s2"}))
        await asyncio.sleep(0)  # the writer's turn
        client.close()
        assert events[0]["reason"].startswith("the op failed: KeyError")
        return socket.sent

    sent = [json.loads(m) for m in asyncio.run(scenario())]
    assert [(m["id"], m["level"]) for m in sent] == [("s1", "error"), ("s2", "error")]
    assert sent[0]["msg"] == "the op failed: KeyError: 'nothing foresaw this'"
