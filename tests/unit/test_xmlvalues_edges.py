"""``wire/xmlvalues.py`` beside the standard library's ``xmlrpc.client``, byte for byte."""

from __future__ import annotations

import re
import xmlrpc.client
from collections import OrderedDict, namedtuple
from enum import IntEnum
from typing import Any

import pytest

from rostools.wire import xmlvalues

NESTED: list[tuple[Any, ...]] = [
    ({"a": [1, "s"], "b": {"c": True}},),
    ([[]], [], {}),
    ("x<&>", -1.5, False, [1, [2, [3]]]),
    (xmlrpc.client.DateTime("20261125T04:00:00"),),
]


@pytest.mark.parametrize("params", NESTED)
def test_calls_are_written_as_xmlrpc_client_writes_them(params: tuple[Any, ...]) -> None:
    assert xmlvalues.dumps_call("m", params) == xmlrpc.client.dumps(params, "m").encode()


def test_binaries_read_back_as_xmlrpc_client_reads_them() -> None:
    # the standard library wraps base64 text in newlines; the value is what counts
    body = xmlvalues.dumps_call("m", (b"ab", xmlrpc.client.Binary(b"cd")))
    params, method = xmlrpc.client.loads(body)
    assert method == "m"
    assert [p.data for p in params] == [b"ab", b"cd"]


class _Level(IntEnum):
    WARN = 4


class _Name(str):
    pass


class _Ratio(float):
    pass


_Pair = namedtuple("_Pair", "a b")


#: Subclasses of the plain types (an IntEnum, a namedtuple, an OrderedDict) and the plain
#: value each is written as; xmlrpc.client refuses subclasses, rospy never sends them.
SUBCLASSES: list[tuple[Any, Any]] = [
    (_Level.WARN, 4),
    (_Name("a<b"), "a<b"),
    (_Ratio(0.5), 0.5),
    (_Pair(1, "x"), [1, "x"]),
    (OrderedDict(k=[_Level.WARN]), {"k": [4]}),
]


@pytest.mark.parametrize(("value", "plain"), SUBCLASSES)
def test_subclasses_are_written_as_their_plain_type(value: Any, plain: Any) -> None:
    assert xmlvalues.dumps_call("m", (value,)) == xmlrpc.client.dumps((plain,), "m").encode()


class _LooksLikeBinary:
    __slots__ = ("data",)

    def __init__(self) -> None:
        self.data = b"x"


class _LooksLikeDateTime:
    __slots__ = ("value",)

    def __init__(self) -> None:
        self.value = "20261125T04:00:00"


@pytest.mark.parametrize(
    "value",
    [2**31, -(2**31) - 1, {1: 2}, object(), None, _LooksLikeBinary(), _LooksLikeDateTime()],
)
def test_what_cannot_be_written_fails_as_in_xmlrpc_client(value: Any) -> None:
    with pytest.raises((OverflowError, TypeError)) as theirs:
        xmlrpc.client.dumps((value,), "m")
    with pytest.raises(type(theirs.value)) as ours:
        xmlvalues.dumps_call("m", (value,))
    assert str(ours.value) == str(theirs.value)


ANSWERS = [
    # XmlRpc++ style: untyped strings, whitespace between values that belongs to no value
    b"<?xml version='1.0'?><methodResponse><params><param><value><array><data>\n  "
    b"<value>x</value>\n  <value><i4>1</i4></value>\n  <value></value>\n</data></array>"
    b"</value></param></params></methodResponse>",
    b"<methodResponse><params><param><value><struct><member><name>a</name>"
    b"<value><dateTime.iso8601>20261125T04:00:00</dateTime.iso8601></value></member>"
    b"<member><name>b</name><value><base64>YWI=</base64></value></member>"
    b"<member><name>c</name><value><string>s</string></value></member>"
    b"</struct></value></param></params></methodResponse>",
]


ANSWERS += [
    # a declared encoding is read (xmlrpc.client reads it; forcing UTF-8 refused this)
    "<?xml version='1.0' encoding='iso-8859-1'?>\n<methodResponse><params><param><value>"
    "<string>caf\xe9</string></value></param></params></methodResponse>".encode("latin-1"),
    # a value inside a value: the inner one is the value
    b"<methodResponse><params><param><value><value>x</value></value></param></params>"
    b"</methodResponse>",
    b"<methodResponse><params><param><value><array><data><value><double>1</double></value>"
    b"<value><boolean>1</boolean></value><value><string>1</string></value></data></array>"
    b"</value></param></params></methodResponse>",
]


def _typed(value: Any) -> Any:
    """``value`` with the type of each part beside it: DateTime("s") == "s", 1 == 1.0."""
    if isinstance(value, list):
        return [_typed(v) for v in value]
    if isinstance(value, dict):
        return {k: _typed(v) for k, v in value.items()}
    return type(value), value


@pytest.mark.parametrize("body", ANSWERS)
def test_answers_read_as_xmlrpc_client_reads_them(body: bytes) -> None:
    (theirs,), _ = xmlrpc.client.loads(body)
    assert _typed(xmlvalues.loads_response(body)) == _typed(theirs)


def test_a_fault_reads_as_xmlrpc_client_reads_it() -> None:
    body = xmlrpc.client.dumps(xmlrpc.client.Fault(3, "no"), methodresponse=True).encode()
    with pytest.raises(xmlvalues.Fault) as caught:
        xmlvalues.loads_response(body)
    assert (caught.value.faultCode, caught.value.faultString) == (3, "no")
    assert str(caught.value) == str(xmlrpc.client.Fault(3, "no"))


NO_NAME = "malformed XML-RPC answer: a struct member without a name"


@pytest.mark.parametrize(
    ("body", "why"),
    [
        (b"<methodResponse><fault><value><string>x</string></value></fault></methodResponse>",
         "a fault that is not a struct"),
        (b"<methodResponse><params><param><value><struct><value><int>1</int></value></struct>"
         b"</value></param></params></methodResponse>", NO_NAME),
        (b"<methodResponse><params><param><value><struct><member><name>a</name><value>1</value>"
         b"</member><member><value>2</value></member></struct></value></param></params>"
         b"</methodResponse>", NO_NAME),
        (b"<methodResponse><params></params></methodResponse>", "an answer with 0 values, not 1"),
        (b"<methodResponse><params><param><value><boolean>2</boolean></value></param></params>"
         b"</methodResponse>", "malformed XML-RPC answer: bad boolean value '2'"),
        (b"<methodResponse><params><param><value><int>1</int>", "malformed XML-RPC answer"),
    ],
)  # fmt: skip
def test_what_is_not_an_answer_says_why(body: bytes, why: str) -> None:
    with pytest.raises(xmlvalues.BadAnswer, match=f"^{re.escape(why)}"):
        xmlvalues.loads_response(body)


@pytest.mark.parametrize(
    "fault",
    [b"<fault></fault>", b"<fault><value><struct></struct></value></fault>"],
)
def test_a_fault_without_its_members_is_fault_0_without_words(fault: bytes) -> None:
    with pytest.raises(xmlvalues.Fault) as caught:
        xmlvalues.loads_response(b"<methodResponse>" + fault + b"</methodResponse>")
    assert (caught.value.faultCode, caught.value.faultString) == (0, "")
