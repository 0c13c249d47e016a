"""The wire at its edges: what mutation testing found unchecked (``python -m benchmarks.mutation``).

Expected values come from captures of rospy and roscpp (services, faults, roscpp's untyped
strings), from the standard
library (``xmlrpc.client``, ``http.client``, ``http.HTTPStatus``) and from the byte layout of a
connection header, written out here independently of ``wire/header.py``.
"""

from __future__ import annotations

import http.client
import io
import struct
import xmlrpc.client
from http import HTTPStatus
from typing import Any

import pytest

from rostools.wire import xmlrpc as wx, xmlvalues as xv
from rostools.wire.header import MAX_HEADER_LENGTH
from rostools.wire.tcpros import (
    Failed,
    FrameError,
    FrameReader,
    ResponseReader,
    SubscriberStream,
    check_subscription,
    error_header,
    frame_prefix,
    publisher_header,
    service_reply_header,
    service_request_header,
    subscriber_header,
)


def ros_header(fields: dict[str, str]) -> bytes:
    """A TCPROS connection header as §5.1 lays it out: u32 total, then u32-prefixed fields."""
    body = b""
    for key in sorted(fields):
        raw = f"{key}={fields[key]}".encode()
        body += struct.pack("<I", len(raw)) + raw
    return struct.pack("<I", len(body)) + body


# TCPROS headers ---------------------------------------------------------------------------


def test_a_service_probe_is_the_header_rosservice_sends() -> None:
    # §6.4: callerid, md5sum=*, probe=1, service, and nothing else
    assert service_request_header("/rosservice", "/add", "*", probe=True) == ros_header(
        {"callerid": "/rosservice", "md5sum": "*", "probe": "1", "service": "/add"}
    )
    assert service_request_header("/c", "/add", "abc", persistent=True) == ros_header(
        {"callerid": "/c", "md5sum": "abc", "persistent": "1", "service": "/add"}
    )
    # rospy sends persistent only when it is (§6.2)
    assert service_request_header("/c", "/add", "abc") == ros_header(
        {"callerid": "/c", "md5sum": "abc", "service": "/add"}
    )


def test_a_service_reply_has_roscpps_fields_and_rospys_service() -> None:
    # §14.5, roscpp's probe reply for /rosout/set_logger_level, plus rospy's service field
    md5 = "51da076440d78ca1684d36c868df61ea"
    reply = service_reply_header(
        "/rosout", "/rosout/set_logger_level", md5, "roscpp/SetLoggerLevel"
    )
    assert reply == ros_header(
        {
            "callerid": "/rosout",
            "md5sum": md5,
            "request_type": "roscpp/SetLoggerLevelRequest",
            "response_type": "roscpp/SetLoggerLevelResponse",
            "service": "/rosout/set_logger_level",
            "type": "roscpp/SetLoggerLevel",
        }
    )


def test_refusal_and_flags_as_ros_writes_them() -> None:
    assert error_header("no such topic") == ros_header({"error": "no such topic"})
    assert publisher_header("/p", "/t", "m", "a/B", "d", False) == ros_header(
        {"callerid": "/p", "latching": "0", "md5sum": "m", "message_definition": "d",
         "topic": "/t", "type": "a/B"}
    )  # fmt: skip
    assert subscriber_header("/s", "/t", "m", "a/B", "d", True) == ros_header(
        {"callerid": "/s", "md5sum": "m", "message_definition": "d", "tcp_nodelay": "1",
         "topic": "/t", "type": "a/B"}
    )  # fmt: skip
    assert frame_prefix(9) == b"\x09\x00\x00\x00"  # §14.3: the frame of "hello"


def test_a_subscriber_that_asks_for_any_type_is_accepted() -> None:
    fields = {"callerid": "/c", "topic": "/t", "md5sum": "992ce8a1687cec8c8bd883ec73ca41d1"}
    assert check_subscription(fields, "/t", "*", "std_msgs/String") is None


# the subscriber's side --------------------------------------------------------------------


def feed(sub: SubscriberStream, data: bytes) -> list[Any]:
    buf = sub.get_buffer()
    buf[: len(data)] = data
    return sub.buffer_updated(len(data))


@pytest.mark.parametrize("missing", ["md5sum", "type"])
def test_a_reply_without_md5sum_or_type_fails(missing: str) -> None:
    fields = {"callerid": "/p", "md5sum": "m", "type": "a/B"}
    del fields[missing]
    sub = SubscriberStream()
    assert feed(sub, ros_header(fields)) == [Failed("reply header lacks md5sum or type")]
    # nothing follows a failure
    assert feed(sub, struct.pack("<I", 1) + b"x") == []


def test_a_reply_header_over_its_limit_fails() -> None:
    sub = SubscriberStream()
    events = feed(sub, struct.pack("<I", MAX_HEADER_LENGTH + 1))
    assert len(events) == 1 and isinstance(events[0], Failed)
    assert "exceeds the limit" in events[0].reason


def test_a_frame_of_exactly_the_limit_passes_one_byte_more_does_not() -> None:
    reader = FrameReader(max_frame=100)
    buf = reader.get_buffer()
    data = struct.pack("<I", 100) + b"a" * 100
    buf[: len(data)] = data
    assert reader.buffer_updated(len(data)) == [b"a" * 100]
    buf = reader.get_buffer()
    buf[:4] = struct.pack("<I", 101)
    with pytest.raises(FrameError, match="frame of 101 bytes exceeds the limit of 100"):
        reader.buffer_updated(4)


def test_after_a_failure_a_subscription_takes_nothing_more() -> None:
    sub = SubscriberStream(max_frame=10)
    header = ros_header({"callerid": "/p", "md5sum": "m", "type": "a/B"})
    events = feed(sub, header + struct.pack("<I", 11))
    assert isinstance(events[-1], Failed)
    assert feed(sub, struct.pack("<I", 1) + b"x") == []
    assert sub.failed


# service responses ------------------------------------------------------------------------

REPLY = ros_header({"callerid": "/rosout", "md5sum": "51da076440d78ca1684d36c868df61ea",
                    "type": "roscpp/SetLoggerLevel"})  # fmt: skip
#: §14.5, captured: success (empty message), roscpp's false, rospy's ServiceException.
RESPONSES = [
    (b"\x01\x00\x00\x00\x00", (True, b"")),
    (b"\x00\x00\x00\x00\x00", (False, b"")),
    (b"\x00\x2a\x00\x00\x00service cannot process request: bad logger",
     (False, b"service cannot process request: bad logger")),
]  # fmt: skip


@pytest.mark.parametrize(("raw", "response"), RESPONSES)
def test_captured_responses_in_one_read_and_byte_by_byte(
    raw: bytes, response: tuple[bool, bytes]
) -> None:
    whole = ResponseReader()
    assert whole.feed(REPLY) == []
    assert whole.header is not None and whole.header["callerid"] == "/rosout"
    assert whole.feed(raw) == [response]
    trickle = ResponseReader()
    got = [r for byte in REPLY + raw for r in trickle.feed(bytes([byte]))]
    assert got == [response]
    together = ResponseReader()
    assert together.feed(REPLY + raw + raw) == [response, response]


def test_a_response_split_after_its_status_and_length() -> None:
    reader = ResponseReader()
    reader.feed(REPLY)
    raw = RESPONSES[2][0]
    assert reader.feed(raw[:5]) == []
    assert reader.feed(raw[5:]) == [RESPONSES[2][1]]


def test_a_bad_status_byte_is_refused_even_in_one_read() -> None:
    reader = ResponseReader()
    reader.feed(REPLY)
    with pytest.raises(FrameError, match="bad service response status byte 2"):
        reader.feed(b"\x02\x00\x00\x00\x00")


def test_service_limits_are_inclusive() -> None:
    limit = len(REPLY) - 4  # the reply header is exactly at the limit
    reader = ResponseReader(max_frame=limit)
    assert reader.feed(REPLY) == []
    assert reader.header is not None
    payload = b"p" * limit
    assert reader.feed(b"\x01" + struct.pack("<I", limit) + payload) == [(True, payload)]
    with pytest.raises(FrameError, match=f"service response of {limit + 1} bytes exceeds"):
        reader.feed(b"\x01" + struct.pack("<I", limit + 1))
    small = ResponseReader(max_frame=limit - 1)
    with pytest.raises(FrameError, match=f"reply header of {limit} bytes exceeds the limit"):
        small.feed(REPLY)


# XML-RPC ----------------------------------------------------------------------------------


def test_a_fault_is_a_fault_to_xmlrpc_client() -> None:
    body = xv.dumps_fault(1, "<class 'Exception'>:method \"nope\" is not supported")
    with pytest.raises(xmlrpc.client.Fault) as caught:
        xmlrpc.client.loads(body)
    assert caught.value.faultCode == 1
    assert caught.value.faultString == "<class 'Exception'>:method \"nope\" is not supported"


#: §14.6: roscpp's registerPublisher, untyped strings.
ROSCPP_CALL = (
    b'<?xml version="1.0"?>\r\n<methodCall><methodName>registerPublisher</methodName>\r\n'
    b"<params><param><value>/rosout</value></param><param><value>/rosout_agg</value></param>"
    b"<param><value>rosgraph_msgs/Log</value></param><param><value>http://127.0.0.1:39915/"
    b"</value></param></params></methodCall>\r\n"
)
SCALARS: list[Any] = ["/a", "", "a b", 7, -(2**31), 2**31 - 1, True, False, 1.5, -0.25]


@pytest.mark.parametrize("count", range(9))
def test_calls_of_scalars_take_the_fast_path_and_read_as_loads(
    count: int, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.setattr(wx, "_simple_calls", [])  # the patterns, built afresh by this call
    params = tuple(SCALARS[i % len(SCALARS)] for i in range(count))
    body = xmlrpc.client.dumps(params, "someMethod").encode()
    fast = wx._decode_simple_call(body)
    assert fast is not None
    loaded, method = xmlrpc.client.loads(body)
    assert fast == (method, loaded)
    assert [type(v) for v in fast[1]] == [type(v) for v in loaded]


def test_the_captured_roscpp_call_takes_the_fast_path(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(wx, "_simple_calls", [])
    expected = xmlrpc.client.loads(ROSCPP_CALL)
    assert wx._decode_simple_call(ROSCPP_CALL) == (expected[1], expected[0])
    typed = ROSCPP_CALL.replace(b"<value>/rosout</value>", b"<value><i4>5</i4></value>")
    assert wx._decode_simple_call(typed) == ("registerPublisher", (5, *expected[0][1:]))


def test_what_the_fast_path_leaves_to_loads() -> None:
    nine = xmlrpc.client.dumps(tuple(range(9)), "m").encode()
    assert wx._decode_simple_call(nine) is None
    assert wx.decode_call(nine) == ("m", tuple(range(9)))
    odd = xmlrpc.client.dumps(("\uffff",), "m").encode()
    assert wx._decode_simple_call(odd) is None
    with pytest.raises(wx.BadCall):
        wx.decode_call(odd)  # not an XML character: loads says so


def test_answers_that_do_not_fit_32_bits_are_refused_as_dumps_refuses_them() -> None:
    for value in (2**31 - 1, -(2**31)):
        assert (
            xv.dumps_response(value) == xmlrpc.client.dumps((value,), methodresponse=True).encode()
        )
    for value in (2**31, -(2**31) - 1):
        with pytest.raises(OverflowError):
            xv.dumps_response(value)
    odd = object()
    with pytest.raises(TypeError):
        xv.dumps_response(odd)


def test_multicall_as_the_python_server_answers() -> None:
    def dispatch(method: str, params: tuple[Any, ...]) -> Any:
        if method == "boom":
            raise xv.Fault(7, "boom")
        return [method, list(params)]

    with pytest.raises(xv.Fault) as none:
        wx.multicall(dispatch, ())
    assert none.value.faultCode == 1
    assert none.value.faultString == (
        "<class 'TypeError'>:system_multicall() missing 1 required positional argument: 'call_list'"
    )
    with pytest.raises(xv.Fault) as two:
        wx.multicall(dispatch, ([], []))
    assert two.value.faultString == (
        "<class 'TypeError'>:system_multicall() takes 2 positional arguments but 3 were given"
    )
    assert wx.multicall(dispatch, ("x",)) == [
        {"faultCode": 1, "faultString": "system.multicall expects a list"}
    ]
    calls = [
        {"methodName": "getPid", "params": ["/a"]},
        {"methodName": "getUri"},
        "nope",
        {"methodName": "system.multicall", "params": [[]]},
        {"methodName": "getPid", "params": "/a"},
        {"methodName": "boom", "params": []},
    ]
    assert wx.multicall(dispatch, (calls,)) == [
        [["getPid", ["/a"]]],
        [["getUri", []]],
        {"faultCode": 1, "faultString": "multicall entries must be structs"},
        {"faultCode": 1, "faultString": "recursive system.multicall forbidden"},
        {"faultCode": 1, "faultString": "multicall params must be an array"},
        {"faultCode": 7, "faultString": "boom"},
    ]


# HTTP -------------------------------------------------------------------------------------


class _Sock:
    def __init__(self, data: bytes) -> None:
        self.data = data

    def makefile(self, mode: str) -> io.BytesIO:
        return io.BytesIO(self.data)


def read_response(raw: bytes) -> http.client.HTTPResponse:
    response = http.client.HTTPResponse(_Sock(raw))  # type: ignore[arg-type]
    response.begin()
    return response


@pytest.mark.parametrize("keep_alive", [True, False])
def test_responses_read_back_with_http_client(keep_alive: bool) -> None:
    raw = wx.format_response(b"<x/>", keep_alive, date="Tue, 25 Nov 2026 04:00:00 GMT")
    response = read_response(raw)
    assert response.status == 200 and response.reason == "OK"
    assert response.getheader("Connection") == ("keep-alive" if keep_alive else "close")
    assert response.getheader("Date") == "Tue, 25 Nov 2026 04:00:00 GMT"
    assert response.getheader("Content-Type") == "text/xml"
    assert response.read() == b"<x/>"
    assert wx.format_response(b"", True) == (
        b"HTTP/1.1 200 OK\r\nServer: rostools\r\nContent-Type: text/xml\r\n"
        b"Content-Length: 0\r\nConnection: keep-alive\r\n\r\n"
    )  # no date: no Date header
    assert raw.startswith(b"HTTP/1.1 200 OK\r\n")  # XmlRpc++ keeps the socket only then (§1.1)


def test_a_request_names_its_agent() -> None:
    raw = wx.format_request("h:1", "/", "getPid", ("/a",))
    head = raw.split(b"\r\n\r\n")[0].split(b"\r\n")
    assert head[0] == b"POST / HTTP/1.1"
    assert b"User-Agent: rostools" in head
    assert xmlrpc.client.loads(raw.split(b"\r\n\r\n", 1)[1]) == (("/a",), "getPid")


def test_printable_paths_stay_as_they_are() -> None:
    assert wx.request_path("/!~") == "/!~"
    assert wx.request_path("/!a b~") == "/!a%20b~"  # RFC 3986 keeps ! and ~ as they are
    assert wx.request_path("/a b") == "/a%20b"
    assert wx.request_path("/\x7f") == "/%7F"


def parse(data: bytes) -> wx.HttpMessage | None:
    parser = wx.HttpParser()
    parser.feed(data)
    return parser.next_message()


@pytest.mark.parametrize(
    ("data", "status", "detail"),
    [
        (b"POST / HTTP/1.1\r\nbad header\r\n\r\n", 400, ""),
        (b"POST / HTTP/1.1\r\nContent-Length: 1\r\nContent-Length: 2\r\n\r\n", 400,
         ": two Content-Length headers"),
        (b"POST / HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\n", 411, ""),
        (b"POST / HTTP/1.1\r\nContent-Length: x\r\n\r\n", 400,
         ": Content-Length is not a number"),
        (b"POST / HTTP/1.1\r\nContent-Length: %d\r\n\r\n" % (wx.MAX_BODY + 1), 413, ""),
        (b"x" * (wx.MAX_HEADERS + 1), 414, ""),  # the request line alone: rosmaster's 414
        (b"POST / HTTP/1.1\r\nX: " + b"x" * wx.MAX_HEADERS, 431, ""),
        (b"POST / HTTP/1.1\r\nX: " + b"x" * wx.MAX_HEADERS + b"\r\n\r\n", 431, ""),  # one read
    ],
)  # fmt: skip
def test_http_errors_carry_the_standard_reason(data: bytes, status: int, detail: str) -> None:
    with pytest.raises(wx.HttpError) as caught:
        parse(data)
    # RFC 7231's reason phrases; Python's own names for 413 and 414 changed with each RFC
    phrase = {413: "Payload Too Large", 414: "Request-URI Too Long"}.get(
        status, HTTPStatus(status).phrase
    )
    assert caught.value.status == status
    assert caught.value.reason == phrase + detail
    assert str(caught.value) == f"{status} {phrase}{detail}"


def test_nothing_is_pending_before_a_head_or_after_a_message() -> None:
    parser = wx.HttpParser()
    assert parser.pending == 0
    parser.feed(b"POST / HTTP/1.1\r\nContent-Length: 3\r\n\r\nab")
    assert parser.next_message() is None and parser.pending == 3


@pytest.mark.parametrize(
    ("start_line", "why"),
    [
        ("HTTP/1.1 500 Internal Server Error", "HTTP 500 Internal Server Error"),
        ("HTTP/1.1 404", "HTTP 404"),
        ("HTTP/1.1", "HTTP answer without a status"),
        ("HTTP/1.1 2000 OK", "HTTP 2000 OK"),
    ],
)
def test_an_answer_other_than_200_is_a_bad_answer(start_line: str, why: str) -> None:
    message = wx.HttpMessage(start_line, {}, xv.dumps_response(1), True)
    with pytest.raises(xv.BadAnswer) as caught:
        wx.answer_value(message)
    assert str(caught.value) == why


def test_the_value_of_an_answer() -> None:
    body = xv.dumps_response({"a": [1.5]})
    assert wx.answer_value(wx.HttpMessage("HTTP/1.1 200 OK", {}, body, True)) == {"a": [1.5]}
    assert wx.answer_value(wx.HttpMessage("HTTP/1.0 200 Fine", {}, body, False)) == {"a": [1.5]}
    # no reason phrase: http.client reads it as 200 too
    assert wx.answer_value(wx.HttpMessage("HTTP/1.1 200", {}, body, True)) == {"a": [1.5]}


@pytest.mark.parametrize(
    "params",
    [(1.0, True, "1"), (xmlrpc.client.Binary(b"ab"), xmlrpc.client.DateTime("20261125T04:00:00"))],
)
def test_calls_are_read_with_the_types_xmlrpc_client_reads(params: tuple[Any, ...]) -> None:
    body = xmlrpc.client.dumps(params, "m").encode()
    theirs, _ = xmlrpc.client.loads(body)  # as rosmaster's SimpleXMLRPCServer reads them
    method, ours = wx.decode_call(body)
    assert method == "m"
    assert [(type(v), v) for v in ours] == [(type(v), v) for v in theirs]


def test_a_double_written_as_an_integer_is_a_float() -> None:
    body = (
        b"<methodCall><methodName>m</methodName><params><param><value><double>1</double>"
        b"</value></param></params></methodCall>"
    )
    [value] = wx.decode_call(body)[1]
    assert (type(value), value) == (float, xmlrpc.client.loads(body)[0][0])


def test_http_limits_are_inclusive() -> None:
    head = b"POST / HTTP/1.1\r\nContent-Length: %d\r\n\r\n" % wx.MAX_BODY
    parser = wx.HttpParser()
    parser.feed(head)
    assert parser.next_message() is None
    assert parser.pending == wx.MAX_BODY
    assert parse(b"x" * wx.MAX_HEADERS) is None


def test_a_message_keeps_its_start_line_and_headers() -> None:
    message = parse(b"POST /RPC2 HTTP/1.1\r\nHost: a:1\r\nX-A: b:c\r\n\r\n")
    assert message is not None
    assert message.start_line == "POST /RPC2 HTTP/1.1"
    assert message.headers == {"host": "a:1", "x-a": "b:c"}
    assert message.body == b""
    assert message.keep_alive
    old = parse(b"HTTP/1.0 200 OK\r\nContent-Length: 0\r\n\r\n")
    assert old is not None and not old.keep_alive


def test_a_body_of_the_hand_over_size_is_copied_and_one_over_handed_over() -> None:
    for size in (wx._HAND_OVER, wx._HAND_OVER + 1):
        parser = wx.HttpParser()
        parser.feed(b"POST / HTTP/1.1\r\nContent-Length: %d\r\n\r\n" % size + b"a" * size)
        message = parser.next_message()
        assert message is not None and message.body == b"a" * size
        assert isinstance(message.body, bytes if size == wx._HAND_OVER else bytearray)
        assert parser.pending == 0


def test_big_frames_keep_their_own_buffers_unless_reuse_is_asked() -> None:
    # record and echo keep frames after the call: a reader must not reuse a buffer by default
    from rostools.wire.tcpros import BIG_FRAME

    payloads = [b"a" * (2 * BIG_FRAME), b"b" * (2 * BIG_FRAME)]
    reader = FrameReader()
    data = b"".join(struct.pack("<I", len(p)) + p for p in payloads)
    kept: list[bytes | memoryview] = []
    pos = 0
    while pos < len(data):
        buf = reader.get_buffer()
        n = min(48 * 1024, len(buf), len(data) - pos)
        buf[:n] = data[pos : pos + n]
        pos += n
        kept += reader.buffer_updated(n)
    assert [bytes(f) for f in kept] == payloads  # the first is still "a"s after the second
