"""The conventions of ROS's XML-RPC APIs, shared by the master and every node's slave API.

Each method has an error value and one check per argument after ``caller_id``; a call that
fails a check is answered ``[-1, message, error value]`` with rosmaster's and rospy's exact
messages (``rosmaster.validators``, ``rospy.impl.masterslave.apivalidate``), and a handler
that raises is answered ``[0, "Internal failure: ..."]``, never with a traceback: with the
words of a ``Failure``, and for any other error, which is ours, the method and the error's
kind (Python's own text, such as "unpack_from requires a buffer of at least 1 bytes", is
no help to a peer, and is logged instead).
"""

from __future__ import annotations

import logging
from collections.abc import Callable, Mapping
from typing import Any
from urllib.parse import urlsplit

from rostools.errors import one_line
from rostools.names import ANYTYPE, GLOBAL_NS, resolve
from rostools.wire.codes import ERROR, FAILURE
from rostools.wire.xmlvalues import Fault

Triple = tuple[int, str, Any]
Check = Callable[[Any, str], Any]
#: method -> (handler taking caller_id and the checked arguments, error value, checks)
Methods = Mapping[str, tuple[Callable[..., Triple], Any, tuple[Check, ...]]]


log = logging.getLogger(__name__)


class ArgumentError(Exception):
    """An argument that fails its check; answered as ``[-1, message, error value]``."""


class Failure(ValueError):  # noqa: N818 - the answer's own word: "Internal failure"
    """A handler's failure, in words for the caller: ``[0, "Internal failure: WORDS"]``."""


def string(name: str, value: Any) -> str:
    """A non-empty string."""
    if not value or not isinstance(value, str):
        raise ArgumentError(f"ERROR: parameter [{name}] must be a non-empty string")
    return value


def _legal(name: str, value: Any) -> str:
    text = string(name, value)
    # rosmaster and rospy refuse these: the usual mistake is a URI where a name belongs
    if ":" in text or " " in text:
        raise ArgumentError(f"ERROR: parameter [{name}] contains illegal chars")
    return text


def graph_name(name: str) -> Check:
    """A topic or service name, resolved against the caller; not ``/`` itself."""

    def check(value: Any, caller_id: str) -> str:
        text = _legal(name, value)
        if text == GLOBAL_NS:
            raise ArgumentError(f"ERROR: parameter [{name}] cannot be the global namespace")
        return resolve(text, caller_id)

    return check


def node_name(name: str) -> Check:
    """A node name, resolved against the caller."""

    def check(value: Any, caller_id: str) -> str:
        return resolve(_legal(name, value), caller_id)

    return check


def global_name(name: str) -> Check:
    """A name that must already be global (rospy's ``paramUpdate`` key)."""

    def check(value: Any, caller_id: str) -> str:
        text = string(name, value)
        if not text.startswith("/"):
            raise ArgumentError(f"ERROR: parameter [{name}] must be a globally referenced name")
        return text

    return check


def non_empty(name: str) -> Check:
    """Anything but an empty or false value."""

    def check(value: Any, caller_id: str) -> Any:
        if not value:
            raise ArgumentError(f"ERROR: parameter [{name}] must be specified and non-empty")
        return value

    return check


def uri_list(name: str) -> Check:
    """A list of URIs with a scheme and a host (rospy's ``is_publishers_list``)."""

    def check(value: Any, caller_id: str) -> list[str]:
        if not isinstance(value, list):
            raise ArgumentError(f"ERROR: param [{name}] must be a list")
        for uri in value:
            if not isinstance(uri, str):
                raise ArgumentError(f"ERROR: param [{name}] must be a list of strings")
            parts = urlsplit(uri)
            if not parts.scheme or not parts.netloc:
                raise ArgumentError(f"ERROR: param [{name}] does not contain valid URLs [{uri}]")
        return value

    return check


def api_uri(name: str) -> Check:
    """An ``http://`` or ``rosrpc://`` URI."""

    def check(value: Any, caller_id: str) -> str:
        if not value or not isinstance(value, str):
            raise ArgumentError(f"ERROR: parameter [{name}] is not an XMLRPC URI")
        if not value.startswith(("http://", "rosrpc://")):
            raise ArgumentError(f"ERROR: parameter [{name}] is not an RPC URI")
        return value

    return check


def subgraph(value: Any, caller_id: str) -> str:
    """A namespace to list under, resolved; empty for all."""
    if not isinstance(value, str):
        raise ArgumentError("ERROR: parameter [subgraph] must be a string")
    return resolve(value, caller_id) if value else ""


def topic_type(value: Any, caller_id: str) -> str:
    """``pkg/Type``, or ``*``."""
    if value == ANYTYPE:
        return ANYTYPE
    text = string("topic_type", value)
    if len(text.split("/")) != 2:
        raise ArgumentError("ERROR: parameter [topic_type] is not a valid package resource name")
    return text


def param_key(value: Any, caller_id: str) -> str:
    """A parameter key (resolved by the handler, which knows its rules)."""
    if not value:
        raise ArgumentError("ERROR: parameter [key] must be specified and non-empty")
    if not isinstance(value, str):
        raise ArgumentError("ERROR: parameter [key] must be a string")
    return value


def anything(value: Any, caller_id: str) -> Any:
    """No check."""
    return value


def not_none(value: Any, caller_id: str) -> Any:
    """Any value but none."""
    if value is None:
        raise ArgumentError("ERROR: parameter [value] must be specified")
    return value


def unsupported(method: str) -> Fault:
    """The fault for a method the server does not have, as rosmaster words it."""
    return Fault(1, f"<class 'Exception'>:method \"{method}\" is not supported")


def checked(methods: Methods, method: str, params: tuple[Any, ...]) -> list[Any] | tuple[Any, ...]:
    """``[caller_id, *checked arguments]``, or the ``[-1, ...]`` answer for a bad call.

    Raises ``Fault`` for an unknown method.
    """
    entry = methods.get(method)
    if entry is None:
        raise unsupported(method)
    _, error_value, checks = entry
    if not params:
        return (ERROR, "missing required caller_id parameter", error_value)
    if len(params) != len(checks) + 1:
        return (ERROR, "Error: bad call arity", error_value)
    caller_id = params[0]
    if not isinstance(caller_id, str):
        return (ERROR, "caller_id must be a string", error_value)
    try:
        return [caller_id, *[c(v, caller_id) for c, v in zip(checks, params[1:], strict=True)]]
    except ArgumentError as err:
        return (ERROR, str(err), error_value)


def dispatch(methods: Methods, method: str, params: tuple[Any, ...]) -> list[Any]:
    """Check the arguments, run the handler, and answer a ROS triple."""
    args = checked(methods, method, params)
    if isinstance(args, tuple):
        return list(args)
    handler, error_value, _ = methods[method]
    try:
        code, message, value = handler(*args)
    except Failure as err:
        return [FAILURE, f"Internal failure: {err}", error_value]
    except Exception as err:  # noqa: BLE001 - rosmaster and rospy answer any failure this way
        kind = type(err).__qualname__
        if type(err).__module__ != "builtins":
            kind = f"{type(err).__module__}.{kind}"
        log.warning("%s failed: %s", method, one_line(f"{kind}: {err}"))
        return [FAILURE, f"Internal failure: {method} failed ({kind})", error_value]
    return [code, message, value]


def cache_key(methods: Methods, method: str, params: tuple[Any, ...]) -> tuple[Any, ...] | None:
    """The method and its checked, resolved arguments: what a cached answer is kept under.

    Resolved, because a relative name means something else to each caller. None when the
    call fails its checks (that answer is never cached) or an argument is not hashable.
    """
    if method not in methods:
        return None
    args = checked(methods, method, params)
    if isinstance(args, tuple):
        return None
    key = (method, *args[1:])
    try:
        hash(key)
    except TypeError:
        return None
    return key
