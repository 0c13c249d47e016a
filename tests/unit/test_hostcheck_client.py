"""``rostools doctor`` calls through the one client, and reads its answers as every call does.

``rosgraph/hostcheck.py`` was a third HTTP client with its own reading of answers (issue 37):
now ``masterapi.XmlRpcNode`` makes its calls, ``answer_value`` and ``ros_value`` read them,
and the HTTP answer's ``Date`` header comes back with the value.
"""

from __future__ import annotations

import ast
import email.utils
import time
from typing import Any

import pytest

from rostools.rosgraph import hostcheck
from rostools.rosgraph.masterapi import HttpConnection
from rostools.wire.xmlrpc import HttpMessage
from rostools.wire.xmlvalues import dumps_response
from tests.support.env import ROOT

#: What a client of its own would import: HTTP, sockets for HTTP, XML-RPC's writer and reader.
CLIENT_MODULES = {"http", "http.client", "xmlrpc", "xmlrpc.client", "urllib", "urllib.parse"}
CLIENT_NAMES = {
    "rostools.wire.xmlrpc",
    "rostools.wire.xmlvalues",
    "rostools.wire.codes",
    "rostools.rosgraph.masterapi.HttpConnection",
    "rostools.rosgraph.masterapi.connect",
}


def imported(path: str) -> set[str]:
    """Every module a file imports, and every ``module.name`` it imports from one."""
    tree = ast.parse((ROOT / path).read_text(), path)
    found: set[str] = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found |= {a.name for a in node.names}
        elif isinstance(node, ast.ImportFrom) and node.module:
            found |= {node.module} | {f"{node.module}.{a.name}" for a in node.names}
    return found


def test_hostcheck_has_no_http_or_xmlrpc_code_of_its_own() -> None:
    names = imported("rostools/rosgraph/hostcheck.py")
    assert not names & CLIENT_MODULES, names & CLIENT_MODULES
    assert not names & CLIENT_NAMES, names & CLIENT_NAMES
    assert "rostools.rosgraph.masterapi.XmlRpcNode" in names
    assert "rostools.rosgraph.masterapi.ros_value" in names  # the one reading of a triple


def answering(monkeypatch: pytest.MonkeyPatch, body: bytes, headers: dict[str, str]) -> list[bytes]:
    """Make every ``HttpConnection.post`` answer ``body`` with ``headers``; the requests sent."""
    sent: list[bytes] = []

    def post(self: HttpConnection, request: bytes) -> HttpMessage:
        sent.append(request)
        return HttpMessage("HTTP/1.1 200 OK", headers, body, keep_alive=False)

    monkeypatch.setattr(HttpConnection, "post", post)
    return sent


def test_the_date_header_comes_back_with_the_answer(monkeypatch: pytest.MonkeyPatch) -> None:
    ahead = email.utils.formatdate(time.time() + 30, usegmt=True)
    body = dumps_response([1, "", 4242])
    sent = answering(monkeypatch, body, {"date": ahead, "content-length": str(len(body))})
    answer = hostcheck.ask("http://127.0.0.1:11311/", "getPid", ("/doctor",), 1.0)
    assert answer.value == [1, "", 4242]
    assert answer.skew is not None and 28 < answer.skew < 32
    assert sent[0].startswith(b"POST / HTTP/1.1\r\n") and b"<methodName>getPid<" in sent[0]


def test_a_failure_code_is_read_as_every_call_reads_it(monkeypatch: pytest.MonkeyPatch) -> None:
    answering(monkeypatch, dumps_response([-1, "no such parameter", 0]), {})
    doctor = hostcheck.Doctor("http://127.0.0.1:11311/", 1.0, env={"ROS_IP": "127.0.0.1"})
    check = doctor.check_sim_time()  # getParam's failure: not set, so wall-clock time
    assert check.verdict == "/use_sim_time is not set: wall-clock time"


@pytest.mark.parametrize(
    ("body", "reason"),
    [
        (b"<html>no</html>", "it does not speak the ROS XML-RPC API (BadAnswer)"),
        (dumps_response(17), "it does not speak the ROS XML-RPC API (RostoolsError)"),
    ],
)
def test_an_answer_that_is_not_ros_fails_the_master_check(
    monkeypatch: pytest.MonkeyPatch, body: bytes, reason: str
) -> None:
    answering(monkeypatch, body, {})
    monkeypatch.setattr(hostcheck, "_resolve", lambda name: ["127.0.0.1"])
    check = hostcheck.Doctor("http://127.0.0.1:11311/", 1.0).check_master()
    assert (check.status, check.exit_code) == ("fail", 4)
    assert check.verdict == f"cannot reach the master at http://127.0.0.1:11311/: {reason}"


def test_a_fault_is_the_clients_error_with_the_fault_under_it(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    from rostools.wire.xmlvalues import dumps_fault

    answering(monkeypatch, dumps_fault(1, "no such method"), {})
    with pytest.raises(Exception) as caught:
        hostcheck.ask("http://127.0.0.1:11311/", "getPid", ("/doctor",), 1.0)
    failure: Any = hostcheck._failure(caught.value, "127.0.0.1")
    assert failure.reason == "it does not speak the ROS XML-RPC API (Fault)"
