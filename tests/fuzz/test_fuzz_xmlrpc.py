"""Fuzz the XML-RPC side: the HTTP and XML parsers, every master and every slave method.

The invariant: a bad request is an ``HttpError`` (a 4xx answer), a body that is no call is a
``BadCall`` (rosmaster's fault), a bad call is a ROS triple or a fault, and any answer encodes;
nothing else is ever raised. A DTD is never read.
"""

from __future__ import annotations

import xmlrpc.client
from types import SimpleNamespace
from typing import Any

import pytest
from hypothesis import given, seed
from hypothesis import strategies as st

from rostools.master.master_api import MasterAPI
from rostools.node.node import Node
from rostools.node.xmlrpc import encode_answer, run_call
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
MASTER_METHODS = [*sorted(MasterAPI("http://m:1/").methods), "system.multicall", "nope"]


def _answer_ok(result: Any) -> None:
    body = encode_answer(result)
    assert body.startswith(b"<?xml")


@seed(SEED)
@FUZZ
@given(st.sampled_from(MASTER_METHODS), PARAMS, PARAMS)
def test_master_methods_answer_anything(method: str, before: tuple[Any, ...], params: Any) -> None:
    api = MasterAPI("http://m:1/")
    for args in (before, params):  # a call after another, as state changes the answers
        result = run_call(api.call, method, args)
        if method == "system.multicall" and args and isinstance(args[0], list):
            assert isinstance(result, list)
        _answer_ok(result)
        if not isinstance(result, list) or method == "system.multicall":
            continue
        code, message, _ = result
        assert code in (-1, 0, 1) and isinstance(message, str)


@seed(SEED)
@FUZZ
@given(st.lists(st.tuples(st.sampled_from(MASTER_METHODS[:-2]), PARAMS), max_size=6))
def test_multicalls_of_anything(calls: list[tuple[str, tuple[Any, ...]]]) -> None:
    api = MasterAPI("http://m:1/")
    entries: list[Any] = [{"methodName": m, "params": list(p)} for m, p in calls]
    entries += [5, {"methodName": "getPid", "params": 5}, {"params": []}]
    result = run_call(api.call, "system.multicall", (entries,))
    assert isinstance(result, list) and len(result) == len(entries)
    _answer_ok(result)


SLAVE_METHODS = [
    "getBusStats", "getBusInfo", "getMasterUri", "shutdown", "getPid", "getSubscriptions",
    "getPublications", "paramUpdate", "publisherUpdate", "requestTopic", "getUri", "getName",
    "system.multicall", "nope",
]  # fmt: skip


@seed(SEED)
@FUZZ
@given(st.sampled_from(SLAVE_METHODS), PARAMS)
def test_slave_methods_answer_anything(method: str, params: tuple[Any, ...]) -> None:
    node = Node("fuzzed", "http://m:1/", host="127.0.0.1")
    node._xmlrpc = SimpleNamespace(port=1)  # type: ignore[assignment]  # no sockets here
    result = run_call(node._dispatch, method, params)
    _answer_ok(result)


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
