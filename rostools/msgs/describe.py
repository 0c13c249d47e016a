"""Types described for people: ``rosmsg show`` text, structured data, and YAML templates."""

from __future__ import annotations

from typing import Any

from rostools.msgs.spec import BUILTIN_TYPES, Field, MsgSpec, SrvSpec
from rostools.msgs.store import TypeStore

_SCALAR_DEFAULTS = {"string": "''", "bool": "false", "float32": "0.0", "float64": "0.0"}
_TIME_DEFAULT = "{secs: 0, nsecs: 0}"


def show_text(store: TypeStore, spec: MsgSpec, indent: str = "") -> str:
    """Rosmsg's expanded form: constants, then fields with nested types indented."""
    lines: list[str] = []
    for c in spec.constants:
        lines.append(f"{indent}{c.type} {c.name}={c.text}\n")
    for f in spec.fields:
        lines.append(f"{indent}{f.type} {f.name}\n")
        if not f.is_builtin:
            lines.append(show_text(store, store.msg(f.base), indent + "  "))
    return "".join(lines)


def show_srv_text(store: TypeStore, spec: SrvSpec) -> str:
    """Rossrv's expanded form: request, ``---``, response."""
    return show_text(store, spec.request) + "---\n" + show_text(store, spec.response)


def structure(store: TypeStore, spec: MsgSpec) -> dict[str, Any]:
    """Constants and fields of a type, nested types expanded, as plain data."""

    def fields(s: MsgSpec) -> list[dict[str, Any]]:
        out: list[dict[str, Any]] = []
        for f in s.fields:
            item: dict[str, Any] = {"name": f.name, "type": f.type}
            if not f.is_builtin:
                item["fields"] = fields(store.msg(f.base))
            out.append(item)
        return out

    return {
        "constants": [{"type": c.type, "name": c.name, "value": c.value} for c in spec.constants],
        "fields": fields(spec),
    }


def _scalar_default(base: str) -> str:
    if base in ("time", "duration"):
        return _TIME_DEFAULT
    return _SCALAR_DEFAULTS.get(base, "0")


class _Proto:
    def __init__(self, store: TypeStore, empty_arrays: bool) -> None:
        self.store = store
        self.empty_arrays = empty_arrays

    def flow(self, f: Field) -> str:
        if f.is_array:
            if self.empty_arrays and f.length is None:
                return "[]"
            one = self.flow(Field(f.name, f.base, f.base, False, None))
            return "[" + ", ".join([one] * (f.length or 1)) + "]"
        if f.base in BUILTIN_TYPES:
            return _scalar_default(f.base)
        spec = self.store.msg(f.base)
        return "{" + ", ".join(f"{g.name}: {self.flow(g)}" for g in spec.fields) + "}"

    def block(self, spec: MsgSpec, indent: str) -> list[str]:
        lines: list[str] = []
        for f in spec.fields:
            nested = not f.is_builtin and (
                not f.is_array or not (self.empty_arrays and f.length is None)
            )
            sub = self.store.msg(f.base) if nested else None
            if sub is None or not sub.fields:
                lines.append(f"{indent}{f.name}: {self.flow(f)}")
            elif not f.is_array:
                lines.append(f"{indent}{f.name}:")
                lines += self.block(sub, indent + "  ")
            else:
                lines.append(f"{indent}{f.name}:")
                item = self.block(sub, indent + "  ")
                for _ in range(f.length or 1):
                    lines.append(f"{indent}- {item[0][len(indent) + 2 :]}")
                    lines += item[1:]
        return lines


def proto(
    store: TypeStore, spec: MsgSpec, *, flow: bool = False, empty_arrays: bool = False
) -> str:
    """A YAML template of a message with default values, as rosmsg-proto prints it."""
    gen = _Proto(store, empty_arrays)
    if flow or not spec.fields:
        return gen.flow(Field("", spec.name, spec.name, False, None))
    return "\n".join(gen.block(spec, ""))
