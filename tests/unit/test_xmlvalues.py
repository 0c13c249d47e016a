"""``wire.xmlvalues``, the client-side XML-RPC marshalling, against ``xmlrpc.client``."""

from __future__ import annotations

import subprocess
import sys
import xmlrpc.client
from typing import Any

import pytest
from hypothesis import given, settings, strategies as st

from rostools.wire.xmlvalues import BadAnswer, Fault, dumps_call, loads_response

# What ROS sends: no None, 32-bit ints, strings without the characters XML cannot carry.
_TEXT = st.text(st.characters(blacklist_categories=("Cs", "Cc")) | st.sampled_from("\t\n"))
_SCALAR = (
    st.booleans()
    | st.integers(-(2**31), 2**31 - 1)
    | st.floats(allow_nan=False)
    | _TEXT
    | st.binary(max_size=20).map(xmlrpc.client.Binary)
)
VALUES = st.recursive(
    _SCALAR,
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(_TEXT, inner, max_size=4),
    max_leaves=20,
)


@settings(max_examples=300, deadline=None)
@given(VALUES)
def test_reads_what_xmlrpc_client_writes(value: Any) -> None:
    body = xmlrpc.client.dumps((value,), methodresponse=True, allow_none=False).encode()
    (expected,), _ = xmlrpc.client.loads(body, use_builtin_types=False)
    assert loads_response(body) == expected


@settings(max_examples=300, deadline=None)
@given(st.lists(VALUES, max_size=4), st.from_regex(r"[A-Za-z_.]{1,20}", fullmatch=True))
def test_writes_what_xmlrpc_client_reads(params: list[Any], method: str) -> None:
    assert xmlrpc.client.loads(dumps_call(method, tuple(params)), use_builtin_types=False) == (
        tuple(params),
        method,
    )


def test_xmlrpcpp_forms_faults_and_garbage() -> None:
    untyped = (
        b"<?xml version='1.0'?><methodResponse><params><param><value><array><data>"
        b"<value><i4>1</i4></value><value>text &amp; more</value><value></value>"
        b"<value><i8>-7</i8></value><value><nil/></value></data></array></value>"
        b"</param></params></methodResponse>"
    )
    assert loads_response(untyped) == [1, "text & more", "", -7, None]
    fault = xmlrpc.client.dumps(xmlrpc.client.Fault(3, "no such method"), methodresponse=True)
    with pytest.raises(Fault) as caught:
        loads_response(fault.encode())
    assert (caught.value.faultCode, caught.value.faultString) == (3, "no such method")
    for junk in (b"", b"<html>404</html>", b"<methodResponse><params>", b"\xff\xfe"):
        with pytest.raises(BadAnswer):
            loads_response(junk)
    with pytest.raises(OverflowError):
        dumps_call("setParam", (2**31,))
    with pytest.raises(TypeError):
        dumps_call("setParam", (None,))


def test_a_master_client_imports_no_xmlrpc_client() -> None:
    """The 30 ms of ``xmlrpc.client``, ``http.client`` and ``email`` are not paid by commands."""
    code = (
        "import sys, rostools.rosgraph.masterapi, rostools.cli.param.paramyaml\n"
        "print(sorted(m for m in ('xmlrpc.client', 'http.client', 'email.parser')"
        " if m in sys.modules))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"
