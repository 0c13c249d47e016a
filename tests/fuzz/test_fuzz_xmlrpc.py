"""Fuzz the XML-RPC side: the HTTP and XML parsers, every master and every slave method.

The invariant: a bad request is an ``HttpError`` (a 4xx answer), a body that is no call is a
``BadCall`` (rosmaster's fault), and nothing else is ever raised. Every answer is read back by
``xmlrpc.client`` and is what the call must get: a fault for an unknown method, a ROS triple
for a known one (-1 when its arity or caller_id is wrong), one answer per multicall entry. A
DTD is never read.
"""

from __future__ import annotations

import xmlrpc.client
from types import SimpleNamespace
from typing import Any

import pytest
from hypothesis import given, seed, strategies as st

from rostools.master.master_api import MasterAPI
from rostools.node.node import LiveNode
from rostools.node.rpc import encode_answer, run_call
from rostools.wire.xmlrpc import BadCall, HttpError, HttpParser, decode_call
from rostools.wire.xmlvalues import BadAnswer, DoctypeRefused, dumps_response, loads_response
from tests.fuzz.conftest import FUZZ, SEED

#: Names as peers send them: good, relative, private, empty, illegal, huge.
NAMES = st.sampled_from(
    ["/a", "a", "~p", "", "/", "a//b", "x y", "/s:1", "-x", "/" + "k/" * 300, "/\u00e9"]
) | st.text(max_size=20)
URIS = st.sampled_from(["http://h:1/", "rosrpc://h:2", "bad", "", "http://", "ftp://x"])
SCALARS = (
    st.none()
    | st.booleans()
    | st.integers(-(2**31), 2**31 - 1)
    | st.floats(allow_nan=True)
    | st.text(max_size=30)
    | NAMES
    | URIS
    | st.binary(max_size=20).map(xmlrpc.client.Binary)
)
VALUES = st.recursive(
    SCALARS,
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=8), inner, max_size=4)
    ),
    max_leaves=12,
)
#: A deep value: what recursion-based code trips on.
DEEP = st.integers(1, 400).map(lambda n: _nest(n))


def _nest(depth: int) -> Any:
    value: Any = 1
    for _ in range(depth):
        value = {"a": value} if depth % 2 else [value]
    return value


PARAMS = st.lists(VALUES | DEEP, max_size=5).map(tuple)

#: The Master API and the parameter server, from the ROS wiki: each method's arguments,
#: caller_id included. Any other method is a fault; a call of the wrong arity a -1 triple.
MASTER_ARITY = {
    "registerService": 4, "unregisterService": 3, "registerSubscriber": 4,
    "unregisterSubscriber": 3, "registerPublisher": 4, "unregisterPublisher": 3,
    "lookupNode": 2, "getPublishedTopics": 2, "getTopicTypes": 1, "getSystemState": 1,
    "getUri": 1, "lookupService": 2, "getPid": 1, "shutdown": 2,
    "deleteParam": 2, "setParam": 3, "getParam": 2, "searchParam": 2, "subscribeParam": 3,
    "unsubscribeParam": 3, "hasParam": 2, "getParamNames": 1,
}  # fmt: skip
#: The Slave API (the ROS wiki), and rospy's getUri and getName.
SLAVE_ARITY = {
    "getBusStats": 1, "getBusInfo": 1, "getMasterUri": 1, "shutdown": 2, "getPid": 1,
    "getSubscriptions": 1, "getPublications": 1, "paramUpdate": 3, "publisherUpdate": 3,
    "requestTopic": 3, "getUri": 1, "getName": 1,
}  # fmt: skip
MASTER_METHODS = [*sorted(MASTER_ARITY), "system.multicall", "nope"]


def test_the_tables_name_every_method() -> None:
    assert set(MasterAPI("http://m:1/").methods) == set(MASTER_ARITY)
    assert set(LiveNode("n", "http://m:1/", host="127.0.0.1")._methods) == set(SLAVE_ARITY)


def _answer(result: Any) -> Any:
    """What a client gets: the body read by the standard library, a ``Fault`` or the value."""
    body = encode_answer(result)
    try:
        (value,), method = xmlrpc.client.loads(body)
    except xmlrpc.client.Fault as fault:
        return fault
    assert method is None  # a response, not a call
    return value


def _is_fault(answer: Any) -> bool:
    """A fault as a client reads it: raised (a call) or a struct (an entry of a multicall)."""
    if isinstance(answer, xmlrpc.client.Fault):
        return isinstance(answer.faultCode, int) and isinstance(answer.faultString, str)
    return (
        isinstance(answer, dict)
        and set(answer) == {"faultCode", "faultString"}
        and isinstance(answer["faultCode"], int)
        and isinstance(answer["faultString"], str)
    )


def _check_triple(answer: Any, args: Any, arity: int) -> None:
    """A ROS triple; -1 when the call cannot be right (rospy's and rosmaster's checks)."""
    assert isinstance(answer, list) and len(answer) == 3, answer
    code, message, _ = answer
    assert code in (-1, 0, 1) and isinstance(message, str), answer
    if len(args) != arity or not isinstance(args[0], str):
        assert code == -1, answer


def _check_call(answer: Any, method: Any, args: Any, arity: dict[str, int]) -> None:
    """``answer`` is what a call of ``method`` with ``args`` must get."""
    if method == "system.multicall":
        if len(args) != 1:
            assert isinstance(answer, xmlrpc.client.Fault), answer
        elif isinstance(args[0], list):
            assert isinstance(answer, list) and len(answer) == len(args[0]), answer
            for entry, got in zip(args[0], answer, strict=True):
                _check_entry(got, entry, arity)
        else:  # nothing to run: a fault, or a fault per entry it could make out
            assert _is_fault(answer) or all(_is_fault(a) for a in answer), answer
    elif isinstance(method, str) and method in arity:
        _check_triple(answer, args, arity[method])
    else:
        assert isinstance(answer, xmlrpc.client.Fault), answer
        assert answer.faultCode == 1 and "is not supported" in answer.faultString, answer


def _check_entry(got: Any, entry: Any, arity: dict[str, int]) -> None:
    """One answer of a multicall: ``[result]`` for a call that runs, else a fault struct."""
    if isinstance(entry, dict):
        method, params = entry.get("methodName"), entry.get("params", [])
        if isinstance(params, list) and isinstance(method, str) and method in arity:
            assert isinstance(got, list) and len(got) == 1, got
            _check_triple(got[0], params, arity[method])
            return
    assert _is_fault(got), got


@seed(SEED)
@FUZZ
@given(st.sampled_from(MASTER_METHODS), PARAMS, PARAMS)
def test_master_methods_answer_anything(method: str, before: tuple[Any, ...], params: Any) -> None:
    api = MasterAPI("http://m:1/")
    for args in (before, params):  # a call after another, as state changes the answers
        _check_call(_answer(run_call(api.call, method, args)), method, args, MASTER_ARITY)


@seed(SEED)
@FUZZ
@given(
    st.lists(
        st.tuples(st.sampled_from(MASTER_METHODS[:-2]), PARAMS | st.just(("/caller",))),
        max_size=6,
    )
)
def test_multicalls_of_anything(calls: list[tuple[str, tuple[Any, ...]]]) -> None:
    api = MasterAPI("http://m:1/")
    entries: list[Any] = [{"methodName": m, "params": list(p)} for m, p in calls]
    entries += [
        5,
        {"methodName": "getPid", "params": 5},
        {"params": []},
        {"methodName": "nope", "params": ["/c"]},
        {"methodName": "system.multicall", "params": [[]]},
        {"methodName": "getPid", "params": ["/c"]},
    ]
    answer = _answer(run_call(api.call, "system.multicall", (entries,)))
    _check_call(answer, "system.multicall", (entries,), MASTER_ARITY)
    assert answer[-1] == [[1, "", api.pid]]  # a call that runs among those that do not
    assert all(_is_fault(a) for a in answer[-6:-1])


SLAVE_METHODS = [*sorted(SLAVE_ARITY), "system.multicall", "nope"]


@seed(SEED)
@FUZZ
@given(st.sampled_from(SLAVE_METHODS), PARAMS)
def test_slave_methods_answer_anything(method: str, params: tuple[Any, ...]) -> None:
    node = LiveNode("fuzzed", "http://m:1/", host="127.0.0.1")
    node._xmlrpc = SimpleNamespace(port=1)  # type: ignore[assignment]  # no sockets here
    _check_call(_answer(run_call(node._dispatch, method, params)), method, params, SLAVE_ARITY)


@seed(SEED)
@FUZZ
@given(st.binary(max_size=400), st.lists(st.integers(1, 64), max_size=8))
def test_http_parser_takes_any_bytes(data: bytes, cuts: list[int]) -> None:
    parser = HttpParser()
    pos = 0
    try:
        for cut in [*cuts, len(data)]:
            parser.feed(data[pos : pos + cut])
            pos += cut
            while (message := parser.next_message()) is not None:
                try:
                    decode_call(message.body)
                except BadCall as bad:
                    assert str(bad).startswith("<class '")
    except HttpError as err:
        assert 400 <= err.status < 500


@seed(SEED)
@FUZZ
@given(st.sampled_from(MASTER_METHODS), PARAMS, st.integers(0, 400), st.binary(max_size=8))
def test_mangled_xml_is_a_fault(method: str, params: Any, at: int, junk: bytes) -> None:
    try:
        body = xmlrpc.client.dumps(params, method, allow_none=True).encode()
    except (TypeError, OverflowError, RecursionError):
        return  # not a request a client could write
    mangled = body[:at] + junk + body[at + len(junk) :]
    try:
        decode_call(mangled)
    except BadCall as err:
        assert str(err).startswith("<class '")


#: Scalars as they reach the master: text with markup, control characters, CR, non-ASCII.
CALL_SCALARS = (
    st.booleans()
    | st.integers(-(2**31), 2**31 - 1)
    | st.floats()
    | st.text(max_size=12)
    | st.text("ab <>&\r\n\t\x01\ufffe\u00e9", max_size=8)
    | NAMES
)
#: How a value is written: as xmlrpc.client does, untyped as XmlRpc++ does, or hand-made.
STYLES = st.sampled_from(["dumps", "untyped", "int", "double", "boolean", "spaced"])


def _write(value: Any, style: str) -> bytes:
    text = str(value).encode("utf-8", "surrogatepass")
    if style == "untyped":
        return b"<value>" + text + b"</value>"
    if style in ("int", "double", "boolean"):
        return b"<value><%s>%s</%s></value>" % (style.encode(), text, style.encode())
    if style == "spaced":
        return b"<value>\n <string>" + text + b"</string> \r\n</value>"
    return xmlrpc.client.dumps((value,)).encode().split(b"<param>\n", 1)[1].split(b"\n</param>")[0]


@seed(SEED)
@FUZZ
@given(
    st.sampled_from(["getPid", "registerPublisher", "a.b", "x y", ""]),
    st.lists(st.tuples(CALL_SCALARS, STYLES), max_size=9),
    st.sampled_from(["<?xml version='1.0'?>\n", '<?xml version="1.0" encoding="UTF-8"?>', "", " "]),
    st.integers(0, 600),
    st.binary(max_size=3),
)
def test_calls_read_as_xmlrpc_client_reads_them(
    method: str, values: list[tuple[Any, str]], prolog: str, at: int, junk: bytes
) -> None:
    # The fast reader of scalar calls must agree with xmlrpc.client on every body: the same
    # method and parameters, or a fault where xmlrpc.client fails.
    params = b"".join(b"<param>" + _write(v, style) + b"</param>\n" for v, style in values)
    body = (
        f"{prolog}<methodCall>\n<methodName>{method}</methodName>\n<params>\n".encode()
        + params
        + b"</params>\n</methodCall>\n"
    )
    for candidate in (body, body[:at] + junk + body[at + len(junk) :]):
        try:
            expected: Any = xmlrpc.client.loads(candidate, use_builtin_types=False)
        except Exception:  # noqa: BLE001 - whatever loads refuses must be a fault
            expected = None
        try:
            got: Any = decode_call(candidate)
        except BadCall:
            got = None
        if expected is not None and expected[1] is None:
            expected = None  # no methodName: a fault, as rosmaster answers
        if expected is None:
            assert got is None
        else:
            assert repr(got) == repr((expected[1], expected[0]))


@seed(SEED)
@FUZZ
@given(VALUES | DEEP | st.integers() | st.recursive(st.integers(), lambda v: st.lists(v)))
def test_answers_are_written_as_xmlrpc_client_writes_them(value: Any) -> None:
    try:
        expected: Any = xmlrpc.client.dumps((value,), methodresponse=True).encode()
    except Exception as err:  # noqa: BLE001 - dumps_response must refuse it the same way
        expected = type(err)
    try:
        got: Any = dumps_response(value)
    except Exception as err:  # noqa: BLE001
        got = type(err)
    assert got == expected


#: What a hostile DTD declares: entities of any name and text, parameter entities, external
#: ones, and markup that is not a declaration at all.
DECLARATIONS = st.lists(
    st.builds(
        lambda name, text, kind: {
            "general": f"<!ENTITY {name} '{text}'>",
            "parameter": f"<!ENTITY % {name} '{text}'>",
            "external": f"<!ENTITY {name} SYSTEM 'file:///{text}'>",
            "element": f"<!ELEMENT {name} ANY>",
        }[kind],
        st.from_regex(r"[a-z][a-z0-9]{0,6}", fullmatch=True),
        st.text(st.characters(blacklist_characters="'%&<\x00", codec="utf-8"), max_size=20),
        st.sampled_from(["general", "parameter", "external", "element"]),
    ),
    max_size=4,
)


@seed(SEED)
@FUZZ
@given(
    st.sampled_from(MASTER_METHODS),
    PARAMS,
    DECLARATIONS,
    st.sampled_from([("utf-8", "utf-8"), ("UTF-16", "utf-16"), ("UTF-16LE", "utf-16-le")]),
    st.sampled_from(["methodCall", "lolz", "x"]),
)
def test_a_dtd_is_never_read(
    method: str, params: Any, declarations: list[str], encoding: tuple[str, str], root: str
) -> None:
    # Any DOCTYPE, declaring anything, in any encoding expat reads, is refused as it starts:
    # by a server reading a call and by a client reading an answer.
    try:
        call = xmlrpc.client.dumps(params, method, allow_none=True)
        answer = xmlrpc.client.dumps((params,), methodresponse=True, allow_none=True)
    except (TypeError, OverflowError, RecursionError):
        return  # not a request a client could write
    doctype = (
        f"<!DOCTYPE {root} [{''.join(declarations)}]>\n"
        if declarations
        else (f"<!DOCTYPE {root}>\n")
    )
    declared, codec = encoding
    prolog = f"<?xml version='1.0' encoding='{declared}'?>\n{doctype}"
    for text, read, error in (
        (call, decode_call, BadCall),
        (answer, loads_response, BadAnswer),
    ):
        body = (prolog + text.split("?>", 1)[1]).encode(codec, "surrogatepass")
        with pytest.raises(error) as err:
            read(body)
        assert isinstance(err.value.__cause__, DoctypeRefused), err.value
