"""Parameters between the ROS master's parameter server and the Foxglove protocol.

ROS parameters are XML-RPC values; the protocol's are JSON values with a ``type`` where JSON
cannot tell (``float64``, ``byte_array`` as base64). A tree is one parameter whose value is
an object, as ``getParam`` gives it.
"""

from __future__ import annotations

import base64
import binascii
import math
from typing import Any

from rostools.wire.foxglove import ProtocolError


def to_client(name: str, value: Any) -> dict[str, Any]:
    """A parameter as the protocol carries it."""
    out: dict[str, Any] = {"name": name}
    if isinstance(value, bytes | bytearray):
        out["value"], out["type"] = base64.b64encode(value).decode(), "byte_array"
    elif isinstance(value, float):
        # JSON has no NaN or infinity: the protocol's clients read them as strings
        out["value"] = value if math.isfinite(value) else str(value)
        out["type"] = "float64"
    elif isinstance(value, list) and value and all(isinstance(v, float) for v in value):
        out["value"], out["type"] = [_plain(v) for v in value], "float64_array"
    else:
        out["value"] = _plain(value)
    return out


def _plain(value: Any) -> Any:
    """A value JSON can hold."""
    if isinstance(value, float) and not math.isfinite(value):
        return str(value)
    if isinstance(value, bytes | bytearray):
        return base64.b64encode(value).decode()
    if isinstance(value, list):
        return [_plain(v) for v in value]
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if value is None or isinstance(value, bool | int | float | str):
        return value
    return str(value)  # an XML-RPC date


def from_client(item: Any) -> tuple[str, Any]:
    """A client's ``{name, value, type}`` as a ROS name and an XML-RPC value."""
    if not isinstance(item, dict) or not isinstance(item.get("name"), str) or not item["name"]:
        raise ProtocolError("setParameters: a parameter without a name")
    name, value, kind = item["name"], item.get("value"), item.get("type")
    if not name.startswith("/"):
        name = "/" + name
    if kind == "byte_array":
        if not isinstance(value, str):
            raise ProtocolError(f"setParameters: {name}: a byte_array is a base64 string")
        try:
            return name, base64.b64decode(value, validate=True)
        except binascii.Error:
            raise ProtocolError(f"setParameters: {name}: not base64") from None
    if kind == "float64":
        if isinstance(value, bool) or not isinstance(value, int | float):
            raise ProtocolError(f"setParameters: {name}: a float64 is a number")
        return name, float(value)
    if kind == "float64_array":
        if not isinstance(value, list) or not all(
            isinstance(v, int | float) and not isinstance(v, bool) for v in value
        ):
            raise ProtocolError(f"setParameters: {name}: a float64_array is a list of numbers")
        return name, [float(v) for v in value]
    if value is None:
        raise ProtocolError(f"setParameters: {name}: no value (ROS cannot unset that way)")
    return name, value


def leaves(prefix: str, value: Any) -> list[tuple[str, Any]]:
    """Every parameter under ``prefix``, a tree taken apart (as ``rosparam list``)."""
    if isinstance(value, dict) and value:
        out: list[tuple[str, Any]] = []
        for key in sorted(value):
            out.extend(leaves(f"{prefix.rstrip('/')}/{key}", value[key]))
        return out
    return [(prefix, value)]
