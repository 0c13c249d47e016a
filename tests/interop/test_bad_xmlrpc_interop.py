"""Bodies that are no XML-RPC call get the same answers from our master as from rosmaster."""

from __future__ import annotations

import pytest

from tests.conftest import MasterInfo
from tests.integration.test_hostile_xmlrpc import LAUGHS, fault_of, post, send_long_line

pytestmark = pytest.mark.interop


@pytest.mark.parametrize(
    "body",
    [
        b"garbage",
        b"<methodCall><methodName>getPid</methodName><params><param>",
        b"<?xml version='1.0'?><methodCall><params></params></methodCall>",
    ],
    ids=["not-xml", "cut-short", "no-method"],
)
def test_a_body_that_is_no_call(any_master: MasterInfo, body: bytes) -> None:
    port = int(any_master.uri.rsplit(":", 1)[1])
    status, answer = post(port, body)
    fault = fault_of(answer)
    # rosmaster's SimpleXMLRPCServer answers every such body with this fault, HTTP 200
    assert status == b"HTTP/1.1 200 OK"
    assert fault.faultCode == 1
    assert fault.faultString.startswith(
        ("<class 'xml.parsers.expat.ExpatError'>:", "<class 'Exception'>:method \"None\"")
    )
    expected = {
        b"garbage": "syntax error: line 1, column 0",
        b"<methodCall><methodName>getPid</methodName><params><param>": "no element found",
    }.get(body, 'method "None" is not supported')
    assert expected in fault.faultString


def test_a_dtd_is_a_fault_on_both(any_master: MasterInfo) -> None:
    # rosmaster reads XML through defusedxml, which refuses entities with this fault
    port = int(any_master.uri.rsplit(":", 1)[1])
    status, answer = post(port, LAUGHS)
    fault = fault_of(answer)
    assert status == b"HTTP/1.1 200 OK" and fault.faultCode == 1
    assert ("needs no DTD" if any_master.kind == "rostools" else "EntitiesForbidden") in (
        fault.faultString
    )


@pytest.mark.parametrize(("where", "status"), [("header", b" 431 "), ("request", b" 414 ")])
def test_a_line_of_a_megabyte_is_answered_by_both(
    any_master: MasterInfo, where: str, status: bytes
) -> None:
    # rosmaster (BaseHTTPRequestHandler) answers "431 Line too long" to a header line over
    # 64 KiB and "414 Request-URI Too Long" to such a request line; ours reset the connection
    port = int(any_master.uri.rsplit(":", 1)[1])
    answer = send_long_line(port, where)
    assert answer.split(b"\r\n", 1)[0].startswith(b"HTTP/1.") and status in answer[:20], answer
