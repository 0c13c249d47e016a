"""XML-RPC over HTTP, sans-IO."""

from __future__ import annotations

import pytest

from rostools.wire.xmlrpc import (
    MAX_BODY,
    SIMPLE_CALL_MAX,
    BadCall,
    HttpError,
    HttpParser,
    decode_call,
    format_request,
    format_response,
)
from rostools.wire.xmlvalues import (
    BadAnswer,
    DoctypeRefused,
    dumps_fault,
    dumps_response,
    loads_response,
)

ROSCPP_CALL = (
    b'<?xml version="1.0"?>\r\n<methodCall><methodName>registerPublisher</methodName>\r\n'
    b"<params><param><value>/rosout</value></param><param><value>/rosout_agg</value></param>"
    b"<param><value>rosgraph_msgs/Log</value></param><param><value><i4>7</i4></value></param>"
    b"<param><value></value></param></params></methodCall>\r\n"
)


def _request(body: bytes, extra: str = "", version: str = "HTTP/1.1") -> bytes:
    head = f"POST / {version}\r\nContent-length: {len(body)}\r\n{extra}\r\n"
    return head.encode() + body


def test_xmlrpcpp_untyped_strings_and_i4() -> None:
    method, params = decode_call(ROSCPP_CALL)
    assert method == "registerPublisher"
    assert params == ("/rosout", "/rosout_agg", "rosgraph_msgs/Log", 7, "")


def test_parser_splits_pipelined_requests_in_any_chunks() -> None:
    stream = _request(b"a" * 10) + _request(b"b" * 5, "Connection: close\r\n")
    parser = HttpParser()
    got = []
    for i in range(len(stream)):
        parser.feed(stream[i : i + 1])
        while (m := parser.next_message()) is not None:
            got.append((m.body, m.keep_alive))
    assert got == [(b"a" * 10, True), (b"b" * 5, False)]


def test_http10_closes_unless_asked() -> None:
    parser = HttpParser()
    parser.feed(_request(b"x", version="HTTP/1.0"))
    message = parser.next_message()
    assert message is not None and not message.keep_alive
    parser.feed(_request(b"x", "Connection: keep-alive\r\n", version="HTTP/1.0"))
    message = parser.next_message()
    assert message is not None and message.keep_alive


@pytest.mark.parametrize(
    ("data", "status"),
    [
        (f"POST / HTTP/1.1\r\nContent-Length: {MAX_BODY + 1}\r\n\r\n".encode(), 413),
        (b"POST / HTTP/1.1\r\nX: " + b"y" * 70000, 431),
        (b"POST / HTTP/1.1\r\nTransfer-Encoding: chunked\r\n\r\n", 411),
        (b"POST / HTTP/1.1\r\nContent-Length: x\r\n\r\n", 400),
        (b"POST / HTTP/1.1\r\nContent-Length: +5\r\n\r\nhello", 400),
        (b"POST / HTTP/1.1\r\nContent-Length: -1\r\n\r\n", 400),
        # RFC 9112 6.3: two lengths that differ leave the end of the body unknowable
        (b"POST / HTTP/1.1\r\nContent-Length: 5\r\nContent-Length: 50\r\n\r\nhello", 400),
    ],
)
def test_limits_and_bad_requests(data: bytes, status: int) -> None:
    parser = HttpParser()
    parser.feed(data)
    with pytest.raises(HttpError) as err:
        parser.next_message()
    assert err.value.status == status


def test_the_same_content_length_twice_is_one_length() -> None:
    parser = HttpParser()
    parser.feed(b"POST / HTTP/1.1\r\nContent-Length: 5\r\ncontent-length: 5\r\n\r\nhello")
    message = parser.next_message()
    assert message is not None and message.body == b"hello"


def test_bad_xml_is_rosmasters_fault_string() -> None:
    # rosmaster answers such a body with a fault whose string is exactly this
    with pytest.raises(BadCall) as err:
        decode_call(b"<methodCall><methodName>x</methodName><params><param>")
    assert str(err.value) == (
        "<class 'xml.parsers.expat.ExpatError'>:no element found: line 1, column 53"
    )
    with pytest.raises(BadCall) as err:
        decode_call(b"<?xml version='1.0'?><methodCall><params></params></methodCall>")
    assert str(err.value) == "<class 'Exception'>:method \"None\" is not supported"


def _with_entity(declaration: str, encoding: str = "utf-8") -> bytes:
    text = (
        f"<?xml version='1.0' encoding='{encoding}'?>\n<!DOCTYPE m [{declaration}]>\n"
        "<methodCall><methodName>getPid</methodName><params><param><value><string>&e;"
        "</string></value></param></params></methodCall>\n"
    )
    return text.encode(encoding)


LAUGHS = (
    "<!ENTITY l0 'lol'>"
    + "".join(f"<!ENTITY l{i} '{f'&l{i - 1};' * 10}'>" for i in range(1, 10))
    + "<!ENTITY e '&l9;'>"
)


@pytest.mark.parametrize(
    "body",
    [
        _with_entity("<!ENTITY e 'x'>"),  # harmless, but XML-RPC never needs a DTD
        _with_entity(LAUGHS),  # 10^9 characters once expanded
        _with_entity(LAUGHS, "utf-16"),  # a byte search for "<!DOCTYPE" would miss it
        _with_entity("<!ENTITY e SYSTEM 'file:///etc/passwd'>"),
    ],
    ids=["one-entity", "billion-laughs", "utf-16", "external"],
)
def test_a_doctype_is_refused_before_it_is_read(body: bytes) -> None:
    with pytest.raises(BadCall, match="needs no DTD") as err:
        decode_call(body)
    assert isinstance(err.value.__cause__, DoctypeRefused)
    answer = body.replace(b"methodCall", b"methodResponse").replace(
        b"<methodName>getPid</methodName>", b""
    )
    with pytest.raises(BadAnswer, match="needs no DTD") as bad:
        loads_response(answer)
    assert isinstance(bad.value.__cause__, DoctypeRefused)


def test_a_big_call_is_read_as_loads_reads_it() -> None:
    import xmlrpc.client

    # multi-byte characters cross the slices expat is fed in
    value = "é€😀<&>" * (SIMPLE_CALL_MAX // 4)
    params = ("/caller", "/big", value, [1, 2.5, {"k": "v"}])
    body = xmlrpc.client.dumps(params, "setParam").encode()
    assert len(body) > 2 * SIMPLE_CALL_MAX
    assert decode_call(body) == ("setParam", params)
    assert decode_call(bytearray(body)) == ("setParam", params)


def test_a_big_body_is_handed_over_and_what_follows_it_kept() -> None:
    big, small = b"b" * (1 << 20), b"s" * 10
    parser = HttpParser()
    parser.feed(_request(big))
    message = parser.next_message()
    assert message is not None and message.body == big
    parser.feed(_request(big) + _request(small))
    first, second = parser.next_message(), parser.next_message()
    assert first is not None and first.body == big
    assert second is not None and second.body == small
    assert parser.next_message() is None and not parser.buffer


def test_big_ints_cannot_be_encoded() -> None:
    with pytest.raises(OverflowError):
        dumps_response([1, "", 2**40])


def test_response_and_request_format() -> None:
    assert format_response(b"<x/>", True).startswith(b"HTTP/1.1 200 OK\r\n")
    assert b"Content-Length: 4\r\n" in format_response(b"<x/>", True)
    request = format_request("h:1", "/", "getPid", ("/me",))
    assert request.startswith(b"POST / HTTP/1.1\r\nHost: h:1\r\n")


def test_a_peers_path_stays_in_the_request_line() -> None:
    # before: a CR LF in a URI's path ended the request line (the rest became a header) and
    # U+2028 raised UnicodeEncodeError, which echo reported as "does not speak XML-RPC"
    request = format_request("h:1", "/a\r\nX: y\u2028%", "getPid", ("/me",))
    assert request.startswith(b"POST /a%0D%0AX:%20y%E2%80%A8% HTTP/1.1\r\nHost: h:1\r\n")
    assert format_request("h:1", "", "getPid", ("/me",)).startswith(b"POST / HTTP/1.1\r\n")
    # the host too: it was a UnicodeEncodeError, an internal error for node info
    assert b"\r\nHost: h%E2%80%A8x:1\r\n" in format_request("h\u2028x:1", "/", "getPid", ())


def test_scalar_calls_are_read_without_xmlrpc_client(monkeypatch: pytest.MonkeyPatch) -> None:
    import xmlrpc.client

    rospy_call = xmlrpc.client.dumps(
        ("/talker", "/chatter", "std_msgs/String", "http://h:1/", 3, True, 1.5), "registerPublisher"
    ).encode()
    # xmlrpc.client.loads was 50 us of a 70 us register call: scalar calls skip it.
    monkeypatch.setattr(xmlrpc.client, "loads", None)
    assert decode_call(rospy_call) == (
        "registerPublisher",
        ("/talker", "/chatter", "std_msgs/String", "http://h:1/", 3, True, 1.5),
    )
    assert decode_call(ROSCPP_CALL) == (
        "registerPublisher",
        ("/rosout", "/rosout_agg", "rosgraph_msgs/Log", 7, ""),
    )


def test_plain_answers_are_written_without_xmlrpc_client(monkeypatch: pytest.MonkeyPatch) -> None:
    import xmlrpc.client

    answer = [1, "Registered [/a] as <publisher> & more", [["/t", ["/n"]], {"k": 1.5, "b": True}]]
    expected = xmlrpc.client.dumps((answer,), methodresponse=True).encode()
    monkeypatch.setattr(xmlrpc.client, "dumps", None)  # a third of encoding was its Marshaller
    assert dumps_response(answer) == expected


@pytest.mark.parametrize("message", ["", "no such method <&> here", "caf\u00e9\n\u2028"])
@pytest.mark.parametrize("code", [-1, 0, 1, 2**31 - 1])
def test_faults_are_written_as_xmlrpc_client_writes_them(code: int, message: str) -> None:
    # servers wrote faults with xmlrpc.client and answers with their own writer; one writes both
    import xmlrpc.client

    expected = xmlrpc.client.dumps(xmlrpc.client.Fault(code, message), methodresponse=True)
    assert dumps_fault(code, message) == expected.encode()
    with pytest.raises(xmlrpc.client.Fault) as caught:
        xmlrpc.client.loads(dumps_fault(code, message))
    assert (caught.value.faultCode, caught.value.faultString) == (code, message)
