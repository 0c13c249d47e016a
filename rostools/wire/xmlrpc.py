"""XML-RPC over HTTP/1.1 as ROS speaks it, sans-IO: parsers fed with bytes, bytes out.

Both ends are here: a request parser and response formatter for servers (master, slave
API), and a request formatter and response parser for clients. Servers marshal with the
standard library, but read a call of scalars (most of what ROS sends) with one regular
expression; clients use ``xmlvalues``, which spares every command the 30 ms import of
``xmlrpc.client`` (it pulls in ``http.client``, ``email`` and ``ssl``).
"""

from __future__ import annotations

from rostools.wire import xmlvalues

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Any

#: The largest request or response body we buffer. rosmaster has no limit; a parameter tree
#: with a big URDF is a few MB, so 64 MiB leaves room and still bounds a hostile peer.
MAX_BODY = 64 * 1024 * 1024
#: The largest HTTP header block: real clients send about 150 bytes.
MAX_HEADERS = 64 * 1024
#: Bodies bigger than this are handed over in the parser's own buffer, not copied.
_HAND_OVER = 64 * 1024
#: Calls up to this size are first tried against one regular expression, which holds the GIL
#: for the whole match (0.4 s for 60 MiB); bigger ones go to expat at once.
SIMPLE_CALL_MAX = 256 * 1024
#: expat reads a call in slices this big, so that a big body parsed in a thread leaves the
#: event loop's thread a turn between them.
PARSE_SLICE = 256 * 1024


class BadCall(ValueError):  # noqa: N818 - reads as what it is
    """A request body that is not an XML-RPC call; servers answer with a fault, as rosmaster.

    The message has the form of rosmaster's fault string, ``<class 'ExceptionType'>:what went
    wrong``: expat's words where XML does not parse (rosmaster's too), ours where a value does
    not read as its tag says (Python's, such as "Incorrect padding", name no place).
    """


class HttpError(Exception):
    """A request or response that is not acceptable HTTP; ``status`` is the reply to send."""

    def __init__(self, status: int, reason: str) -> None:
        super().__init__(f"{status} {reason}")
        self.status = status
        self.reason = reason


class HttpMessage:
    """A parsed HTTP request or response.

    Plain classes here: commands import this module, and ``dataclasses`` costs them 15 ms.
    """

    __slots__ = ("body", "headers", "keep_alive", "start_line")

    def __init__(
        self, start_line: str, headers: dict[str, str], body: bytes | bytearray, keep_alive: bool
    ) -> None:
        self.start_line = start_line
        self.headers = headers
        self.body = body
        self.keep_alive = keep_alive


class HttpParser:
    """Splits a byte stream into HTTP messages with a ``Content-Length`` body.

    Feed it whatever arrives; ``messages()`` returns the complete ones. One parser serves a
    whole keep-alive connection.
    """

    def __init__(self) -> None:
        self.buffer = bytearray()
        #: The declared body length of a message whose headers are in and whose body is not.
        self.pending = 0

    def feed(self, data: bytes | memoryview) -> None:
        """Add received bytes."""
        self.buffer += data

    def next_message(self) -> HttpMessage | None:
        """The next complete message, or None until more bytes arrive."""
        end = self.buffer.find(b"\r\n\r\n")
        if end < 0 and len(self.buffer) <= MAX_HEADERS:
            return None
        if end < 0 or end > MAX_HEADERS:  # however many reads it came in
            eol = self.buffer.find(b"\r\n", 0, MAX_HEADERS + 2)
            if eol < 0 or eol > MAX_HEADERS:  # rosmaster's words for each
                raise HttpError(414, "Request-URI Too Long")
            raise HttpError(431, "Request Header Fields Too Large")
        head = self.buffer[:end].decode("latin-1")
        lines = head.split("\r\n")
        headers: dict[str, str] = {}
        for line in lines[1:]:
            name, sep, value = line.partition(":")
            if not sep:
                raise HttpError(400, "Bad Request")
            name, value = name.strip().lower(), value.strip()
            if name == "content-length" and headers.get(name, value) != value:
                # RFC 9112 6.3: differing lengths make the message's end unknowable
                raise HttpError(400, "Bad Request: two Content-Length headers")
            headers[name] = value
        if "chunked" in headers.get("transfer-encoding", "").lower():
            raise HttpError(411, "Length Required")
        declared = headers.get("content-length", "0")
        if not (declared.isascii() and declared.isdigit()):
            raise HttpError(400, "Bad Request: Content-Length is not a number")
        length = int(declared)
        if length > MAX_BODY:
            raise HttpError(413, "Payload Too Large")
        total = end + 4 + length
        if len(self.buffer) < total:
            self.pending = length
            return None
        self.pending = 0
        if len(self.buffer) == total and length > _HAND_OVER:
            # A big body is the whole buffer: hand it over rather than copy it on the loop
            # (deleting a bytearray's head is O(1) in CPython).
            del self.buffer[: end + 4]
            body: bytes | bytearray = self.buffer
            self.buffer = bytearray()
        else:
            body = bytes(self.buffer[end + 4 : total])
            del self.buffer[:total]
        start = lines[0]
        connection = headers.get("connection", "").lower()
        http10 = start.endswith("HTTP/1.0") or start.startswith("HTTP/1.0")
        keep_alive = connection == "keep-alive" if http10 else connection != "close"
        return HttpMessage(start, headers, body, keep_alive)


_WS = rb"[ \t\r\n]*"
#: Character data that XML passes through as it is: no markup, no references, no characters
#: XML forbids, and no carriage return (XML turns CR LF into LF).
_TEXT = rb"([^<>&\r\x00-\x08\x0b\x0c\x0e-\x1f]*)"
_CALL_HEAD = (
    rb"(?:<\?xml[ \t\r\n]+version=(?:'1\.0'|\"1\.0\")"
    rb"(?:[ \t\r\n]+encoding=(?:'(?i:utf-8)'|\"(?i:utf-8)\"))?[ \t\r\n]*\?>)?"
    + _WS
    + rb"<methodCall>"
    + _WS
    + rb"<methodName>([A-Za-z0-9_.:/-]+)</methodName>"
    + _WS
)
#: Calls with up to this many scalar parameters are read without ``xmlrpc.client``.
_SIMPLE_PARAMS = 8
_BOOLEANS = {b"0": False, b"1": True}
#: One pattern per number of parameters, compiled when a server first decodes a call.
_simple_calls: list[Any] = []


def _simple_call_pattern(count: int) -> Any:
    """The whole of a call with ``count`` scalar parameters, as one pattern.

    Three groups per parameter: an untyped value (XmlRpc++ writes strings so), or a type and
    its text. One match is one pass in C, where a pattern per parameter cost twice as much.
    """
    import re

    params = b"".join(
        _WS
        + rb"<param>"
        + _WS
        + rb"<value>(?:"
        + _TEXT
        + rb"</value>|"
        + _WS
        + rb"<(?P<t%d>string|int|i4|i8|boolean|double)>" % i
        + _TEXT
        + rb"</(?P=t%d)>" % i
        + _WS
        + rb"</value>)"
        + _WS
        + rb"</param>"
        for i in range(count)
    )
    if count:
        params = rb"<params>" + params + _WS + rb"</params>" + _WS
    else:
        params = rb"(?:<params>" + _WS + rb"</params>" + _WS + rb")?"
    return re.compile(_CALL_HEAD + params + rb"</methodCall>" + _WS)


def _decode_simple_call(body: bytes | bytearray) -> tuple[str, tuple[Any, ...]] | None:
    """A call whose parameters are plain scalars, as ROS nodes send them; None for others.

    ``xmlrpc.client.loads`` runs a Python callback per element: 50 us of a register call's
    70, against 6 us here. Every body this accepts, it reads as ``loads`` does (a property
    test compares them); entities, containers, other encodings and anything malformed are
    left to ``loads``.
    """
    count = body.count(b"<param>")
    if count > _SIMPLE_PARAMS or b"\xef\xbf" in body:
        return None  # U+FFFE and U+FFFF are not XML characters: loads says so
    if not _simple_calls:
        _simple_calls.extend(_simple_call_pattern(n) for n in range(_SIMPLE_PARAMS + 1))
    match = _simple_calls[count].fullmatch(body)
    if match is None:
        return None
    groups = match.groups()
    params: list[Any] = []
    try:
        for i in range(1, len(groups), 3):
            untyped, tag, text = groups[i : i + 3]
            if untyped is not None:
                params.append(untyped.decode())
            elif tag == b"string":
                params.append(text.decode())
            elif tag == b"boolean":
                params.append(_BOOLEANS[text])
            elif tag == b"double":
                params.append(float(text))
            else:
                params.append(int(text))
    except (ValueError, KeyError):  # not UTF-8, not a number: loads says what is wrong
        return None
    return groups[0].decode(), tuple(params)


def decode_call(body: bytes | bytearray) -> tuple[str, tuple[Any, ...]]:
    """The method name and parameters of an XML-RPC request body.

    Raises ``BadCall`` for anything else. A DOCTYPE is refused before it is read
    (``xmlvalues.expat_parser``), and a big body is read in slices (``PARSE_SLICE``).
    """
    if len(body) <= SIMPLE_CALL_MAX:
        simple = _decode_simple_call(body)
        if simple is not None:
            return simple
    import xmlrpc.client  # servers only: commands never pay for it

    # xmlrpc.client.loads, fed in slices by a parser that refuses a DTD
    target = xmlrpc.client.Unmarshaller(use_builtin_types=False)
    target.xml(None, None)  # type: ignore[arg-type]  # as ExpatParser: expat gives str
    parser = xmlvalues.expat_parser()

    def end(tag: str) -> None:
        try:
            target.end(tag)
        except Exception as err:  # named in words: Python's are no help to a peer
            where = f"line {parser.CurrentLineNumber}, column {parser.CurrentColumnNumber}"
            raise BadCall(f"{type(err)}:not a valid <{tag}>: {where}") from err

    parser.StartElementHandler = target.start
    parser.EndElementHandler = end
    parser.CharacterDataHandler = target.data
    view = memoryview(body)
    try:
        for start in range(0, len(view), PARSE_SLICE):
            parser.Parse(view[start : start + PARSE_SLICE], False)
        parser.Parse(b"", True)
    except BadCall:
        raise
    except Exception as err:  # expat's own texts (rosmaster's too) say what is wrong, and where
        raise BadCall(f"{type(err)}:{err}") from err
    try:
        params = target.close()
    except xmlrpc.client.ResponseError as err:  # its text is empty: "ResponseError()"
        raise BadCall(f"{type(err)}:the body is no complete XML-RPC call") from err
    method = target.getmethodname()
    if method is None:
        raise BadCall("<class 'Exception'>:method \"None\" is not supported")
    return method, params


def format_response(
    body: bytes, keep_alive: bool, status: str = "200 OK", date: str | None = None
) -> bytes:
    """A complete HTTP response. XmlRpc++ keeps the connection only after ``HTTP/1.1 200 OK``.

    ``date`` (an RFC 7231 date) goes in a ``Date`` header, as rosmaster's Python server sends
    one: a client can tell how far our clock is from its own.
    """
    connection = "keep-alive" if keep_alive else "close"
    dated = f"Date: {date}\r\n" if date else ""
    head = (
        f"HTTP/1.1 {status}\r\nServer: rostools\r\n{dated}Content-Type: text/xml\r\n"
        f"Content-Length: {len(body)}\r\nConnection: {connection}\r\n\r\n"
    )
    return head.encode("latin-1") + body


def format_request(host: str, path: str, method: str, params: tuple[Any, ...]) -> bytes:
    """A complete HTTP POST of an XML-RPC call.

    ``host`` and ``path`` come from a peer's URI: both go as ``request_path`` writes them.
    """
    body = xmlvalues.dumps_call(method, params)
    head = (
        f"POST {request_path(path)} HTTP/1.1\r\nHost: {request_path(host)}\r\n"
        "User-Agent: rostools\r\n"
        f"Content-Type: text/xml\r\nContent-Length: {len(body)}\r\n\r\n"
    )
    return head.encode("latin-1") + body


def request_path(path: str) -> str:
    """A URI's path as a request line carries it: percent-encoded beyond printable ASCII.

    The path comes from a peer's URI: a line break in it must not end the request line, and
    U+2028 must not fail to encode (Python's http.client, under rospy, refuses both).
    """
    if path.isascii() and path.isprintable() and " " not in path:
        return path or "/"
    return "".join(c if "!" <= c <= "~" else _percent(c) for c in path)


def _percent(char: str) -> str:
    return "".join(f"%{byte:02X}" for byte in char.encode())


def answer_value(message: HttpMessage) -> Any:
    """The value an HTTP answer to an XML-RPC call carries: the one reading of an answer.

    Raises ``xmlvalues.Fault`` for a fault and ``xmlvalues.BadAnswer`` for a status other
    than 200 or a body that is not a method response.
    """
    status = message.start_line.split(" ", 2)
    if len(status) < 2 or status[1] != "200":
        raise xmlvalues.BadAnswer(f"HTTP {' '.join(status[1:]) or 'answer without a status'}")
    return xmlvalues.loads_response(message.body)


def multicall(dispatch: Any, params: tuple[Any, ...]) -> list[Any]:
    """Run a ``system.multicall``'s list of calls through ``dispatch(method, params)``.

    Each result is wrapped in a one-element list; a failing call becomes a fault struct.
    Other than one parameter is a fault, with the words of rosmaster's Python server.
    """
    if len(params) != 1:
        why = (
            "missing 1 required positional argument: 'call_list'"
            if not params
            else f"takes 2 positional arguments but {len(params) + 1} were given"
        )
        raise xmlvalues.Fault(1, f"<class 'TypeError'>:system_multicall() {why}")
    calls = params[0]
    if not isinstance(calls, list):
        return [{"faultCode": 1, "faultString": "system.multicall expects a list"}]
    results: list[Any] = []
    for call in calls:
        try:
            if not isinstance(call, dict):
                raise xmlvalues.Fault(1, "multicall entries must be structs")
            method, args = call.get("methodName"), call.get("params", [])
            if method == "system.multicall":
                raise xmlvalues.Fault(1, "recursive system.multicall forbidden")
            if not isinstance(args, list):
                raise xmlvalues.Fault(1, "multicall params must be an array")
            results.append([dispatch(method, tuple(args))])
        except xmlvalues.Fault as fault:
            results.append({"faultCode": fault.faultCode, "faultString": fault.faultString})
    return results
