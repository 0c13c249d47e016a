"""``~get_loggers`` and ``~set_logger_level``: a node's loggers, as rospy and roscpp serve them.

The loggers are the Python ``logging`` loggers rostools uses (``rostools`` and those under
it), so ``log set NODE rostools.node DEBUG`` changes what that node says. The bytes of
``roscpp/GetLoggers`` and ``roscpp/SetLoggerLevel`` are read and written here with ``struct``
alone: the quick ``log`` commands use the same functions, and load no type store.
"""

from __future__ import annotations

import struct

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Any, Protocol

    class _Serves(Protocol):
        """What ``serve_loggers`` needs of a node (not ``LiveNode``: it imports this)."""

        async def advertise_service(
            self, name: str, srv_type: Any, handler: Any, *, quiet: bool = False
        ) -> Any: ...


#: The md5sums of the two service types (``tests/integration/test_cli_log.py`` checks them).
GET_LOGGERS = ("roscpp/GetLoggers", "32e97e85527d4678a8f9279894bb64b0")
SET_LOGGER_LEVEL = ("roscpp/SetLoggerLevel", "51da076440d78ca1684d36c868df61ea")
#: The levels a logger may be set to, by increasing severity, as rosconsole names them.
LEVELS = ("debug", "info", "warn", "error", "fatal")
#: The root of the loggers a rostools node lists.
ROOT = "rostools"
#: rospy's names for Python's levels (``rospy.client._logging_level_names``); the numbers are
#: ``logging``'s, written out: the quick commands import this module, and not ``logging``.
_NAMES = {10: "DEBUG", 20: "INFO", 30: "WARN", 40: "ERROR", 50: "FATAL"}
_PYTHON_LEVELS = {name: level for level, name in _NAMES.items()}


class LoggerBytesError(ValueError):
    """Bytes that are not a ``roscpp/GetLoggers`` response or a ``SetLoggerLevel`` request."""


def _string(text: str) -> bytes:
    data = text.encode()
    return struct.pack("<I", len(data)) + data


def _read_string(data: bytes, at: int) -> tuple[str, int]:
    if at + 4 > len(data):
        raise LoggerBytesError("cut short")
    (size,) = struct.unpack_from("<I", data, at)
    at += 4
    if at + size > len(data):
        raise LoggerBytesError("a string runs past the end")
    return data[at : at + size].decode("utf-8", "replace"), at + size


def encode_loggers(loggers: list[tuple[str, str]]) -> bytes:
    """A ``GetLoggers`` response: ``(name, level)`` pairs."""
    body = b"".join(_string(name) + _string(level) for name, level in loggers)
    return struct.pack("<I", len(loggers)) + body


def decode_loggers(data: bytes) -> list[tuple[str, str]]:
    """The ``(name, level)`` pairs of a ``GetLoggers`` response."""
    if len(data) < 4:
        raise LoggerBytesError("cut short")
    (count,) = struct.unpack_from("<I", data, 0)
    if count * 8 > len(data) - 4:  # each logger takes at least two lengths: checked first
        raise LoggerBytesError(f"{count} loggers in {len(data)} bytes")
    at, found = 4, []
    for _ in range(count):
        name, at = _read_string(data, at)
        level, at = _read_string(data, at)
        found.append((name, level))
    return found


def encode_set(logger: str, level: str) -> bytes:
    """A ``SetLoggerLevel`` request."""
    return _string(logger) + _string(level)


def decode_set(data: bytes) -> tuple[str, str]:
    """The logger and level of a ``SetLoggerLevel`` request."""
    logger, at = _read_string(data, 0)
    level, _ = _read_string(data, at)
    return logger, level


def our_loggers() -> list[tuple[str, str]]:
    """rostools' loggers that exist in this process, with their effective levels."""
    import logging

    known = logging.Logger.manager.loggerDict.items()
    ours = (
        n for n, found in known if n.startswith(ROOT + ".") and isinstance(found, logging.Logger)
    )
    names = [ROOT, *sorted(ours)]
    return [(name, _level_name(logging.getLogger(name).getEffectiveLevel())) for name in names]


def _level_name(level: int) -> str:
    # a level between the named ones reads as the next named one below it
    named = [n for n in sorted(_NAMES) if n <= level]
    return _NAMES[named[-1]] if named else "DEBUG"


def set_level(request: bytes) -> bytes:
    """Serve ``~set_logger_level``: one of our loggers to a rosconsole level.

    A logger we do not list, or a level that is not one of ``LEVELS``, is a failure (roscpp
    answers false; rospy logs and ignores it). Creating loggers on a peer's word would let it
    fill our memory.
    """
    import logging

    from rostools.errors import ServiceError

    logger, level = decode_set(request)
    if logger not in dict(our_loggers()):
        raise ServiceError(f"no logger {logger}")
    if level.upper() not in _PYTHON_LEVELS:
        raise ServiceError(f"bad level {level} (one of {', '.join(LEVELS)})")
    logging.getLogger(logger).setLevel(_PYTHON_LEVELS[level.upper()])
    return b""


def get_loggers(request: bytes) -> bytes:
    """Serve ``~get_loggers``."""
    return encode_loggers(our_loggers())


async def serve_loggers(node: _Serves) -> None:
    """Offer ``~get_loggers`` and ``~set_logger_level`` on ``node``, as every rospy node does."""
    from rostools.msgs.topictype import ServiceType

    # quiet: a slow master is said for what the user asked, not for these
    await node.advertise_service("~get_loggers", ServiceType(*GET_LOGGERS), get_loggers, quiet=True)
    await node.advertise_service(
        "~set_logger_level", ServiceType(*SET_LOGGER_LEVEL), set_level, quiet=True
    )
