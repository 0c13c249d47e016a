"""XML-RPC calls and answers to and from bytes, without ``xmlrpc.client``.

``xmlrpc.client`` imports ``http.client``, ``email`` and ``ssl``: 30 ms at every start of a
command that only asks the master. This is the part a client needs, on ``pyexpat`` alone.
It reads what ``xmlrpc.client.loads`` reads, including XmlRpc++'s untyped ``<value>text``
strings, ``<i4>``/``<i8>`` and ``<nil/>``; ``base64`` and ``dateTime.iso8601`` values come back
as ``xmlrpc.client``'s ``Binary`` and ``DateTime`` (imported only when one arrives).
"""

from __future__ import annotations

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Any

#: XML-RPC integers are 32-bit; ``xmlrpc.client`` refuses larger ones the same way.
_INT_MAX = 2**31 - 1
_INT_MIN = -(2**31)
_ESCAPE = str.maketrans({"&": "&amp;", "<": "&lt;", ">": "&gt;"})


class Fault(Exception):  # noqa: N818 - the XML-RPC name, as xmlrpc.client.Fault
    """An XML-RPC fault answer."""

    def __init__(self, code: int, message: str) -> None:
        super().__init__(f"<Fault {code}: {message!r}>")
        self.faultCode = code
        self.faultString = message


class BadAnswer(ValueError):  # noqa: N818 - reads as what it is
    """Bytes that are not an XML-RPC method response."""


class DoctypeRefused(ValueError):  # noqa: N818 - reads as what it is
    """An XML document with a DOCTYPE.

    XML-RPC never needs a DTD, and the entities a DTD declares can take seconds of CPU to
    expand (a 700-byte "billion laughs"), so the declaration is refused before it is read.
    """


def _refuse_doctype(name: str, *_: object) -> None:
    raise DoctypeRefused(f"XML-RPC needs no DTD: refused the DOCTYPE {name!r} unread")


def expat_parser() -> Any:
    """A pyexpat parser that stops at a DOCTYPE.

    Every XML-RPC body we parse goes through one: the answers our clients read, and the calls
    our servers read (``wire.xmlrpc``). It reads the encoding a body declares (UTF-8 if none),
    as ``xmlrpc.client`` does.
    """
    from xml.parsers import expat

    parser = expat.ParserCreate()
    parser.StartDoctypeDeclHandler = _refuse_doctype
    return parser


def _value(out: list[str], value: Any) -> None:
    """``value`` as ``xmlrpc.client``'s Marshaller writes it, with the same refusals.

    The one XML-RPC writer: calls (``dumps_call``), answers (``dumps_response``) and faults
    (``dumps_fault``). The exact types all the ROS APIs carry come first, by identity, which
    is a third of the cost of ``isinstance`` chains on a master's answers.
    """
    kind = type(value)
    if kind is str:
        out.append(f"<value><string>{value.translate(_ESCAPE)}</string></value>\n")
    elif kind is int:
        if not _INT_MIN <= value <= _INT_MAX:
            raise OverflowError("int exceeds XML-RPC limits")
        out.append(f"<value><int>{value}</int></value>\n")
    elif kind is list or kind is tuple:
        out.append("<value><array><data>\n")
        for item in value:
            _value(out, item)
        out.append("</data></array></value>\n")
    elif kind is bool:
        out.append(f"<value><boolean>{int(value)}</boolean></value>\n")
    elif kind is float:
        out.append(f"<value><double>{value!r}</double></value>\n")
    elif kind is dict:
        out.append("<value><struct>\n")
        for key, item in value.items():
            if type(key) is not str:
                raise TypeError("dictionary key must be string")
            out.append(f"<member>\n<name>{key.translate(_ESCAPE)}</name>\n")
            _value(out, item)
            out.append("</member>\n")
        out.append("</struct></value>\n")
    else:
        _rare(out, value)


def _rare(out: list[str], value: Any) -> None:
    """Binaries, dates and subclasses of the plain types: rare in ROS, kept off the fast path.

    ``bool`` has no subclasses, so every bool took the fast path.
    """
    if isinstance(value, int):
        _value(out, int(value))
    elif isinstance(value, str):
        _value(out, str(value))
    elif isinstance(value, float):
        _value(out, float(value))
    elif isinstance(value, list | tuple):
        _value(out, list(value))
    elif isinstance(value, dict):
        _value(out, dict(value))
    elif isinstance(value, bytes | bytearray):
        import base64  # binaries are rare in ROS: commands do not pay for base64 otherwise

        out.append(f"<value><base64>\n{base64.encodebytes(value).decode()}</base64></value>\n")
    elif type(value).__name__ == "Binary" and hasattr(value, "data"):  # xmlrpc.client's
        _rare(out, bytes(value.data))
    elif type(value).__name__ == "DateTime" and hasattr(value, "value"):
        out.append(f"<value><dateTime.iso8601>{value.value}</dateTime.iso8601></value>\n")
    elif value is None:
        raise TypeError("cannot marshal None unless allow_none is enabled")
    else:
        raise TypeError(f"cannot marshal {type(value)} objects")


def dumps_call(method: str, params: tuple[Any, ...]) -> bytes:
    """The body of a call of ``method`` with ``params``, as ``xmlrpc.client.dumps`` writes it."""
    out = ["<?xml version='1.0'?>\n<methodCall>\n<methodName>", method.translate(_ESCAPE)]
    out.append("</methodName>\n<params>\n")
    for param in params:
        out.append("<param>\n")
        _value(out, param)
        out.append("</param>\n")
    out.append("</params>\n</methodCall>\n")
    return "".join(out).encode()


def dumps_response(value: Any) -> bytes:
    """A method response carrying ``value``, byte for byte as ``xmlrpc.client.dumps`` writes it.

    Raises ``OverflowError`` and ``TypeError`` where it does, ``RecursionError`` for a cycle.
    """
    out = ["<?xml version='1.0'?>\n<methodResponse>\n<params>\n<param>\n"]
    _value(out, value)
    out.append("</param>\n</params>\n</methodResponse>\n")
    return "".join(out).encode()


def dumps_fault(code: int, message: str) -> bytes:
    """A fault response, byte for byte as ``xmlrpc.client.dumps(Fault(...))`` writes it."""
    out = ["<?xml version='1.0'?>\n<methodResponse>\n<fault>\n"]
    _value(out, {"faultCode": code, "faultString": message})
    out.append("</fault>\n</methodResponse>\n")
    return "".join(out).encode()


_SCALARS = {"string", "i4", "i8", "int", "boolean", "double", "base64", "dateTime.iso8601", "nil"}


def _scalar(tag: str, text: str) -> Any:
    if tag == "string":
        return text
    if tag in ("i4", "i8", "int"):
        return int(text)
    if tag == "boolean":
        if text not in ("0", "1"):
            raise BadAnswer(f"bad boolean value {text!r}")
        return text == "1"
    if tag == "double":
        return float(text)
    if tag == "nil":
        return None
    import base64
    import xmlrpc.client  # rare in ROS: only then pay for the module

    if tag == "base64":
        return xmlrpc.client.Binary(base64.b64decode(text))
    return xmlrpc.client.DateTime(text)


class _Reader:
    """Builds the values of a method response from pyexpat's events."""

    def __init__(self) -> None:
        self.stack: list[Any] = []  # open arrays (lists) and structs (dicts)
        self.names: list[str | None] = []  # the member name pending in each open struct
        self.values: list[Any] = []  # the params (or the fault struct)
        self.text: list[str] = []
        self.typed = False  # the current <value> had a type element
        self.fault = False

    def start(self, tag: str, attrs: dict[str, str]) -> None:
        self.text = []
        if tag == "value":
            self.typed = False
        elif tag == "array":
            self.typed = True
            self.stack.append([])
            self.names.append(None)
        elif tag == "struct":
            self.typed = True
            self.stack.append({})
            self.names.append(None)
        elif tag in _SCALARS:
            self.typed = True
        elif tag == "fault":
            self.fault = True

    def end(self, tag: str) -> None:
        text = "".join(self.text)
        self.text = []
        if tag in _SCALARS:
            self._add(_scalar(tag, text))
        elif tag == "value" and not self.typed:
            self._add(text)  # XmlRpc++ writes strings without a type
        elif tag in ("array", "struct"):
            self.names.pop()
            self._add(self.stack.pop())
        elif tag == "name":
            self.names[-1] = text
        if tag == "value":
            self.typed = True  # text after a closed value belongs to no value

    def _add(self, value: Any) -> None:
        if not self.stack:
            self.values.append(value)
        elif isinstance(self.stack[-1], list):
            self.stack[-1].append(value)
        else:
            name = self.names[-1]
            if name is None:
                raise BadAnswer("a struct member without a name")
            self.stack[-1][name] = value
            self.names[-1] = None

    def chars(self, data: str) -> None:
        self.text.append(data)


def loads_response(body: bytes | bytearray) -> Any:
    """The value of a method response; ``Fault`` for a fault, ``BadAnswer`` for anything else."""
    from xml.parsers import expat

    reader = _Reader()
    parser = expat_parser()
    parser.StartElementHandler = reader.start
    parser.EndElementHandler = reader.end
    parser.CharacterDataHandler = reader.chars
    try:
        parser.Parse(body, True)
    except (expat.ExpatError, ValueError) as err:
        raise BadAnswer(f"malformed XML-RPC answer: {err}") from err
    if reader.fault:
        fault = reader.values[0] if reader.values else {}
        if not isinstance(fault, dict):
            raise BadAnswer("a fault that is not a struct")
        raise Fault(fault.get("faultCode", 0), str(fault.get("faultString", "")))
    if len(reader.values) != 1:
        raise BadAnswer(f"an answer with {len(reader.values)} values, not 1")
    return reader.values[0]
