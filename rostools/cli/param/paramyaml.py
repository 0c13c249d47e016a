"""YAML for parameters, with rosparam's conventions (wiki.ros.org/rosparam).

YAML 1.1 (``1e3`` stays a string), ``!!binary`` as XML-RPC binary, ``!degrees``/``!radians``
and bare ``deg(...)``/``rad(...)`` as radians. Unlike rosparam, ``rad()`` expressions are
evaluated by a small arithmetic evaluator, never by ``eval``.
"""

from __future__ import annotations

import ast
import base64
import datetime
import math
import operator
import re
from collections.abc import Callable
from typing import TYPE_CHECKING, Any

import yaml

if TYPE_CHECKING:
    import xmlrpc.client

from rostools import yamlio
from rostools.errors import UsageError
from rostools.yamlio import SafeLoader

INT32_MIN, INT32_MAX = -(2**31), 2**31 - 1
_OPS: dict[type, Callable[..., float]] = {
    ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
    ast.Pow: operator.pow, ast.USub: operator.neg, ast.UAdd: operator.pos,
}  # fmt: skip


def _arith(text: str) -> float:
    """An arithmetic expression of numbers and ``pi``."""

    def value(node: ast.AST) -> float:
        if isinstance(node, ast.Expression):
            return value(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, int | float):
            return float(node.value)
        if isinstance(node, ast.Name) and node.id == "pi":
            return math.pi
        if isinstance(node, ast.BinOp) and type(node.op) in _OPS:
            return _OPS[type(node.op)](value(node.left), value(node.right))
        if isinstance(node, ast.UnaryOp) and type(node.op) in _OPS:
            return _OPS[type(node.op)](value(node.operand))
        raise ValueError(text)

    try:
        return value(ast.parse(text.strip(), mode="eval"))
    except (SyntaxError, ValueError, ZeroDivisionError, OverflowError):
        raise UsageError(f"invalid radian expression: {text}") from None


def _radians(loader: yaml.SafeLoader, node: yaml.Node) -> float:
    text = str(loader.construct_scalar(node)).strip()  # type: ignore[arg-type]
    if text.startswith("rad(") and text.endswith(")"):
        text = text[4:-1]
    return _arith(text)


def _degrees(loader: yaml.SafeLoader, node: yaml.Node) -> float:
    text = str(loader.construct_scalar(node)).strip()  # type: ignore[arg-type]
    if text.startswith("deg(") and text.endswith(")"):
        text = text[4:-1]
    return _arith(text) * math.pi / 180.0


def _binary(loader: yaml.SafeLoader, node: yaml.Node) -> xmlrpc.client.Binary:
    import xmlrpc.client  # only for a !!binary: commands never pay 30 ms for it otherwise

    return xmlrpc.client.Binary(loader.construct_yaml_binary(node))  # type: ignore[arg-type]


class ParamLoader(SafeLoader):  # type: ignore[misc,valid-type]
    """safe_load plus rosparam's tags."""


ParamLoader.add_constructor("tag:yaml.org,2002:binary", _binary)
ParamLoader.add_constructor("!radians", _radians)
ParamLoader.add_constructor("!degrees", _degrees)
ParamLoader.add_implicit_resolver("!degrees", re.compile(r"^deg\([^)]*\)$"), ["d"])
ParamLoader.add_implicit_resolver("!radians", re.compile(r"^rad\([^)]*\)$"), ["r"])


class ParamDumper(yaml.SafeDumper):
    """safe_dump plus ``!!binary`` for XML-RPC binaries and dates as text."""


def _xmlrpc_kind(value: Any) -> str | None:
    """``Binary`` or ``DateTime`` for ``xmlrpc.client``'s value types (without importing it)."""
    kind = type(value)
    return kind.__name__ if kind.__module__ == "xmlrpc.client" else None


def _represent_xmlrpc(dumper: yaml.SafeDumper, data: Any) -> yaml.Node:
    kind = _xmlrpc_kind(data)
    if kind == "Binary":
        text = base64.b64encode(data.data).decode()
        return dumper.represent_scalar("tag:yaml.org,2002:binary", text, style="|")
    if kind == "DateTime":
        return dumper.represent_str(str(data))
    return dumper.represent_undefined(data)


ParamDumper.add_multi_representer(object, _represent_xmlrpc)


#: Parameters go out as XML-RPC, which the master accepts up to 64 MiB: about a million values.
MAX_PARAM_VALUES = 1_000_000


def load(text: str, source: str = "the value") -> Any:
    """One YAML value."""
    return yamlio.load(text, source, ParamLoader, MAX_PARAM_VALUES)


def load_all(text: str, source: str) -> list[Any]:
    """Every document of a YAML stream."""
    return yamlio.load_all(text, source, ParamLoader, MAX_PARAM_VALUES)


class PrettyDumper(ParamDumper):
    """``get -p``: multi-line strings as literal blocks; still valid YAML, unlike rosparam's."""


def _represent_text(dumper: yaml.SafeDumper, data: str) -> yaml.Node:
    return dumper.represent_scalar(
        "tag:yaml.org,2002:str", data, style="|" if "\n" in data else None
    )


PrettyDumper.add_representer(str, _represent_text)


def dump(value: Any, *, pretty: bool = False) -> str:
    """Block-style YAML, keys sorted, as rosparam get/dump print it, without ``...``."""
    dumper = PrettyDumper if pretty else ParamDumper
    # -p prints text as it is, as rosparam's does (é, not "\xE9"); a plain dump escapes
    text = yaml.dump(value, Dumper=dumper, default_flow_style=False, allow_unicode=pretty)
    return text.removesuffix("\n...\n")


def check_value(value: Any, name: str) -> None:
    """Refuse what XML-RPC cannot carry: integers beyond 32 bits, null and timestamps."""
    if value is None:
        raise UsageError(
            f"{name}: null is not a parameter value", hint="quote it to set the string 'null'"
        )
    if isinstance(value, datetime.date):
        # rosparam fails on a date (a traceback, exit 0, nothing set) and stores a date and
        # time as an XML-RPC dateTime that it cannot print back as it was written
        raise UsageError(
            f"{name}: {value} is a YAML timestamp, not a parameter value",
            hint=f"quote it to set the string '{value}'",
        )
    if isinstance(value, bool):
        return
    if isinstance(value, int) and not INT32_MIN <= value <= INT32_MAX:
        raise UsageError(
            f"{name}: {value} does not fit in 32 bits; the parameter server only stores "
            f"integers from {INT32_MIN} to {INT32_MAX}",
            hint="write it as a float (append .0) or a string",
        )
    if isinstance(value, dict):
        for k, v in value.items():
            check_value(v, f"{name.rstrip('/')}/{k}")
    elif isinstance(value, list):
        for i, v in enumerate(value):
            check_value(v, f"{name}[{i}]")


def to_plain(value: Any) -> Any:
    """Parameters as JSON-able data: binaries as base64 text, dates as ISO text."""
    kind = _xmlrpc_kind(value)
    if kind == "Binary":
        return base64.b64encode(value.data).decode()
    if kind == "DateTime":
        return str(value)
    if isinstance(value, dict):
        return {k: to_plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [to_plain(v) for v in value]
    return value
