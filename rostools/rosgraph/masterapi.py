"""A blocking client of the Master and Parameter APIs, for commands.

Commands like ``topic list`` and ``param get`` need neither asyncio nor ``xmlrpc.client``
(with ``http.client``, 30 ms of imports): calls go over one kept-alive socket, marshalled by
``wire.xmlvalues``. Every call has a timeout, and a master that cannot be reached is one
``UnreachableError`` with the URI in it.
"""

from __future__ import annotations

import _socket  # the C module: ``socket`` adds 4 ms of enums and wrappers a client never uses
import os

from rostools.errors import NotFoundError, RostoolsError, TimeoutExpired, UnreachableError
from rostools.wire import codes
from rostools.wire.xmlrpc import HttpError, HttpMessage, HttpParser, answer_value, format_request
from rostools.wire.xmlvalues import BadAnswer, Fault

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Any

#: Seconds to wait for the master before giving up; ``ROSTOOLS_MASTER_TIMEOUT`` changes it.
DEFAULT_TIMEOUT = 3.0
#: Seconds to wait for a node's answer; rosnode's ping uses 3 s (and 5 s for info).
NODE_TIMEOUT = 3.0
#: Seconds a service call may take, connecting included, unless the caller says otherwise
#: (the Python API; ``service call`` waits as long as rosservice does: without a limit).
SERVICE_TIMEOUT = 10.0
#: Seconds to connect to a service and read its header: rosservice's probe allows 5 s.
PROBE_TIMEOUT = 5.0
#: A wait without a limit says what it waits for once it has lasted this long (s).
WAIT_NOTICE = 3.0


def master_timeout() -> float:
    """The timeout for master calls from the environment, else the default."""
    try:
        return float(os.environ.get("ROSTOOLS_MASTER_TIMEOUT", DEFAULT_TIMEOUT))
    except ValueError:
        return DEFAULT_TIMEOUT


def within(deadline: float | None) -> float:
    """The limit of a master call made by a command that must be done by ``deadline``.

    ``master_timeout()``, or what is left before ``deadline`` (``time.monotonic()``) if that is
    less, so that a slow master cannot make a command overrun its ``--timeout``.
    """
    limit = master_timeout()
    if deadline is None:
        return limit
    import time  # the quick path never gets here

    return max(min(limit, deadline - time.monotonic()), 0.001)


def connect(host: str, port: int, timeout: float) -> _socket.socket:
    """A TCP connection to the first address of ``host`` that accepts.

    As ``socket.create_connection``: each address in turn, and the first one's error if none
    accepts.
    """
    # An ASCII host goes as bytes: getaddrinfo encodes a str with idna (2 ms of imports).
    name = host.encode() if host.isascii() else host
    try:
        found = _socket.getaddrinfo(name, port, 0, _socket.SOCK_STREAM)
    except UnicodeError as err:  # a peer's URI with U+2028 in its host: no name to look up
        raise _socket.gaierror(_socket.EAI_NONAME, f"{host!r} is not a host name") from err
    errors: list[OSError] = []
    for family, kind, proto, _, address in found:
        sock = _socket.socket(family, kind, proto)
        try:
            sock.settimeout(timeout)
            sock.connect(address)
        except OSError as err:
            sock.close()
            errors.append(err)
        else:
            return sock
    raise errors[0] if errors else OSError(f"no address for {host}")


class HttpConnection:
    """Blocking HTTP/1.1 POSTs to one server over one kept-alive socket.

    A request that meets a kept-alive connection the server has since closed is sent once
    more on a new one, unless ``retry`` is off (a request that must not be sent twice).
    """

    def __init__(self, uri: str, timeout: float) -> None:
        self.netloc, _, path = uri.partition("://")[2].partition("/")
        self.path = "/" + path
        host, port = self.netloc, "80"
        if host.startswith("["):  # [IPv6]:port
            host, _, tail = host[1:].partition("]")
            port = tail.removeprefix(":") or port
        elif ":" in host:
            host, _, port = host.rpartition(":")
        if not port.isdigit():
            raise UnreachableError(f"cannot reach {uri}: the port is not a number")
        self.host, self.port = host or "localhost", int(port)
        self.timeout = timeout
        self.retry = True
        self.sock: _socket.socket | None = None

    def post(self, request: bytes) -> HttpMessage:
        """Send a whole request and read the response (one retry on a connection gone stale)."""
        reused = self.sock is not None
        try:
            return self._exchange(request)
        except (ConnectionError, EOFError):
            self.close()
            if not (reused and self.retry):
                raise
            return self._exchange(request)

    def _exchange(self, request: bytes) -> HttpMessage:
        if self.sock is None:
            self.sock = connect(self.host, self.port, self.timeout)
        self.sock.sendall(request)
        parser = HttpParser()
        while (message := parser.next_message()) is None:
            data = self.sock.recv(65536)
            if not data:
                raise EOFError("the server closed the connection")
            parser.feed(data)
        if not message.keep_alive:
            self.close()
        return message

    def close(self) -> None:
        """Close the socket, if open."""
        if self.sock is not None:
            self.sock.close()
            self.sock = None


class MasterError(RostoolsError):
    """The master (or a node) answered a call with a failure code."""

    def __init__(self, method: str, code: int, message: str) -> None:
        super().__init__(message or f"{method} failed")
        self.method = method
        self.code = code


# One policy for every call to a master or a node, blocking or async: a server that accepts
# the connection and does not answer is a timeout (exit 5), one that cannot be connected to
# is unreachable (exit 4), and a ROS failure code is a MasterError. Callers raise what these
# return ``from`` the original error, so ``--debug`` shows the cause.


def no_answer(uri: str, what: str, method: str, timeout: float) -> TimeoutExpired:
    """The server at ``uri`` did not answer ``method`` in time."""
    return TimeoutExpired(f"the {what} at {uri} did not answer {method} within {timeout:g} s")


def unreachable(err: BaseException, uri: str, what: str) -> UnreachableError:
    """The server at ``uri`` could not be reached (``err``: the transport's error)."""
    if what == "master":  # the reasons the multi-host notices give (imported on failure only)
        from rostools.rosgraph.network import explain, uri_host

        reason = explain(err, uri_host(uri), peer=False).reason
    else:
        reason = getattr(err, "strerror", None) or str(err) or type(err).__name__
    hint = "is roscore (or 'rostools core') running? check ROS_MASTER_URI or --master-uri"
    return UnreachableError(
        f"cannot reach the {what} at {uri}: {reason}", hint=hint if what == "master" else None
    )


def faulted(fault: Any, uri: str, what: str, method: str) -> RostoolsError:
    """The server answered with an XML-RPC fault (not a ROS failure code)."""
    return RostoolsError(f"the {what} at {uri} failed {method}: {fault.faultString}")


def call_error(
    err: BaseException, uri: str, what: str, method: str, timeout: float
) -> RostoolsError | None:
    """The one answer policy: what a failed XML-RPC call of ``method`` at ``uri`` is to a user.

    Every client of a master or a node, blocking or async, turns its failures into errors
    here: no answer in time, no connection, a fault, a bad answer (a status other than 200,
    XML that is no answer, a broken HTTP message), a value XML-RPC cannot carry. ``None``
    for anything else, which is not the peer's doing.
    """
    if isinstance(err, TimeoutError):
        return no_answer(uri, what, method, timeout)
    if isinstance(err, OSError | EOFError):
        return unreachable(err, uri, what)
    if isinstance(err, Fault):
        return faulted(err, uri, what, method)
    if isinstance(err, OverflowError):
        return RostoolsError("integers must fit in 32 bits (XML-RPC has no larger type)")
    if isinstance(err, BadAnswer | HttpError):
        return RostoolsError(f"bad answer from the {what} at {uri}: {err}")
    return None


#: The master's methods whose ERROR code means "no such thing", and how to say it of the
#: name asked for: every client, blocking or async, says it so.
MISSING = {
    "getParam": "parameter {} is not set",
    "deleteParam": "parameter {} is not set",
    "lookupNode": "unknown node {}",
    "lookupService": "unknown service {}",
}


def ros_value(answer: Any, method: str, what: str, args: tuple[Any, ...] = ()) -> Any:
    """The value of a ROS API answer ``[code, message, value]``: the one reading of a triple.

    A failure code is a ``MasterError``, or a ``NotFoundError`` (raised from it) where
    ``MISSING`` says the code means the name in ``args[0]`` does not exist.
    """
    if not isinstance(answer, list | tuple) or len(answer) != 3:
        raise RostoolsError(f"bad answer from the {what} to {method}: {answer!r}")
    code, message, value = answer
    if code != codes.SUCCESS:
        failure = MasterError(method, code, message)
        if code == codes.ERROR and method in MISSING and args and what == "master":
            raise NotFoundError(MISSING[method].format(args[0])) from failure
        raise failure
    return value


class XmlRpcNode:
    """Calls to one XML-RPC server (a master or a node) on behalf of ``caller_id``."""

    def __init__(
        self, uri: str, caller_id: str, timeout: float | None = None, what: str = "master"
    ):
        self.uri = uri
        self.caller_id = caller_id
        self.what = what
        self.timeout = master_timeout() if timeout is None else timeout
        self.http = HttpConnection(uri, self.timeout)

    def raw(self, method: str, *args: Any) -> Any:
        """Call ``method(caller_id, *args)`` and return the whole answer."""
        return self.answered(method, *args)[0]

    def answered(self, method: str, *args: Any) -> tuple[Any, HttpMessage]:
        """``raw``'s answer, and the HTTP message it came in (``doctor`` reads its ``Date``)."""
        try:
            request = format_request(
                self.http.netloc, self.http.path, method, (self.caller_id, *args)
            )
            message = self.http.post(request)
            return answer_value(message), message
        except Exception as err:
            error = call_error(err, self.uri, self.what, method, self.timeout)
            if error is None:
                raise
            if not isinstance(err, Fault | OverflowError):
                self.http.close()  # the connection is in no state to carry another call
            raise error from err

    def limit(self, seconds: float) -> None:
        """Give each call from now on at most ``seconds`` (``within`` a command's deadline)."""
        self.timeout = self.http.timeout = seconds
        if self.http.sock is not None:
            self.http.sock.settimeout(seconds)

    def call(self, method: str, *args: Any) -> Any:
        """Call a ROS API method and return its value (``ros_value`` reads the answer)."""
        return ros_value(self.raw(method, *args), method, self.what, args)


class MasterProxy(XmlRpcNode):
    """The master's graph and parameter calls, with ROS errors turned into ours."""

    def __init__(self, uri: str, caller_id: str, timeout: float | None = None) -> None:
        super().__init__(uri, caller_id, timeout, "master")

    def get_param(self, key: str) -> Any:
        """A parameter's value; NotFoundError when unset."""
        return self.call("getParam", key)

    def set_param(self, key: str, value: Any) -> None:
        """Set a parameter."""
        self.call("setParam", key, value)

    def delete_param(self, key: str) -> None:
        """Delete a parameter; NotFoundError when unset."""
        self.call("deleteParam", key)

    def param_names(self) -> list[str]:
        """Every parameter name."""
        names: list[str] = self.call("getParamNames")
        return names

    def system_state(self) -> tuple[list[Any], list[Any], list[Any]]:
        """Publishers, subscribers and services."""
        pubs, subs, srvs = self.call("getSystemState")
        return pubs, subs, srvs

    def topic_types(self) -> dict[str, str]:
        """Topic -> type, for every topic the master has seen typed."""
        return dict(self.call("getTopicTypes"))

    def lookup_node(self, name: str) -> str:
        """A node's XML-RPC URI; NotFoundError for an unknown node."""
        uri: str = self.call("lookupNode", name)
        return uri

    def lookup_service(self, name: str) -> str:
        """A service's rosrpc URI; NotFoundError for an unknown service."""
        uri: str = self.call("lookupService", name)
        return uri


def master_answers(uri: str, timeout: float = 1.0) -> bool:
    """Whether an XML-RPC server (a master) answers at ``uri``."""
    try:
        XmlRpcNode(uri, "/rostools_probe", timeout).raw("getPid")
    except (UnreachableError, TimeoutExpired):
        return False
    except RostoolsError:
        return True  # something answered, if oddly
    return True
