"""Python expressions over messages: ``--filter`` of echo, hz, bw and delay, and ``bag filter``.

One compiler for all of them. An expression sees ``topic``, ``m`` (the decoded message) and
``t`` (its time, with ``secs``, ``nsecs`` and ``to_sec()``), as ``rostopic echo --filter``
and ``rosbag filter`` let it; it is the user's own Python, evaluated as the ROS 1 tools do.
A bad one is an ``ExpressionError`` (a usage error, exit 2), whether it does not parse or
raises on a message; the error names the expression and, for the latter, the topic.
"""

from __future__ import annotations

import ast
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from rostools.errors import UsageError


class ExpressionError(UsageError):
    """An expression that does not compile, or raised on a message."""


@dataclass(frozen=True)
class Expression:
    """A compiled expression; call it with ``(topic, m, t)``."""

    source: str
    fn: Callable[[str, Any, Any], Any]
    #: Whether it reads ``m``: callers that can decide without decoding skip the decode.
    needs_message: bool

    def __call__(self, topic: str, m: Any, t: Any = None) -> Any:
        """The expression's value for one message."""
        try:
            return self.fn(topic, m, t)
        except Exception as err:  # the user's expression may raise anything
            raise ExpressionError(
                f"{self.source!r} failed on {topic}: {type(err).__name__}: {err}"
            ) from err


def compile_expression(source: str, what: str = "--filter") -> Expression:
    """Compile ``source``; ``what`` names the option in the error for one that does not parse."""
    text = source.strip()
    try:
        tree = ast.parse(text, mode="eval")
        code = compile(f"lambda topic, m, t: ({text})", "<expression>", "eval")
    except SyntaxError as err:
        raise ExpressionError(f"{what} {source!r} is not a Python expression: {err.msg}") from err
    needs = any(isinstance(n, ast.Name) and n.id == "m" for n in ast.walk(tree))
    return Expression(source, eval(code, {"__builtins__": __builtins__}), needs)  # noqa: S307
