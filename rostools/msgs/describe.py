"""Types described for people: ``rosmsg show`` text, structured data, and YAML templates."""

from __future__ import annotations

from typing import Any

from rostools.msgs.action import ActionSpec
from rostools.msgs.spec import BUILTIN_TYPES, Field, MsgSpec, SrvSpec
from rostools.msgs.store import TypeStore

_SCALAR_DEFAULTS = {"string": "''", "bool": "false", "float32": "0.0", "float64": "0.0"}


def _check(store: TypeStore, spec: MsgSpec) -> None:
    """Refuse a type that contains itself, or nests too deep, before expanding it.

    Each description below recurses once per level. A cycle through ``spec`` passes through
    one of its dependencies, so checking each of them finds it without recursing.
    """
    for dep in spec.dependencies:
        store.check(dep)


def show_text(store: TypeStore, spec: MsgSpec) -> str:
    """Rosmsg's expanded form: constants, then fields with nested types indented."""
    _check(store, spec)
    return _show_text(store, spec, "")


def _show_text(store: TypeStore, spec: MsgSpec, indent: str) -> str:
    lines: list[str] = []
    for c in spec.constants:
        lines.append(f"{indent}{c.type} {c.name}={c.text}\n")
    for f in spec.fields:
        lines.append(f"{indent}{f.type} {f.name}\n")
        if not f.is_builtin:
            lines.append(_show_text(store, store.msg(f.base), indent + "  "))
    return "".join(lines)


def show_srv_text(store: TypeStore, spec: SrvSpec) -> str:
    """Rossrv's expanded form: request, ``---``, response."""
    return show_text(store, spec.request) + "---\n" + show_text(store, spec.response)


def show_action_text(store: TypeStore, spec: ActionSpec) -> str:
    """An action as rossrv shows a service: goal, ``---``, result, ``---``, feedback."""
    return "---\n".join(show_text(store, s) for s in (spec.goal, spec.result, spec.feedback))


def structure(store: TypeStore, spec: MsgSpec) -> dict[str, Any]:
    """Constants and fields of a type, nested types expanded, as plain data."""
    _check(store, spec)

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


# A template value: a scalar's YAML text, a mapping of (name, value) pairs, or a sequence.
# The flag says whether the default style writes it inline, in brackets.
_Node = tuple[str, list[Any], bool]
_Value = str | _Node


class _Proto:
    """Builds a template tree of a type's default values, then writes it in one of three styles."""

    def __init__(self, store: TypeStore, empty_arrays: bool, exclude: frozenset[str]) -> None:
        self.store = store
        self.empty_arrays = empty_arrays
        self.exclude = exclude

    def message(self, spec: MsgSpec) -> _Node:
        items = [(f.name, self.field(f)) for f in spec.fields if f.name not in self.exclude]
        return ("map", items, False)

    def field(self, f: Field) -> _Value:
        if not f.is_array:
            return self.element(f.base)
        if self.empty_arrays and f.length is None:
            return ("seq", [], True)
        one = self.element(f.base)
        return ("seq", [one] * (f.length or 1), isinstance(one, str))

    def element(self, base: str) -> _Value:
        if base in ("time", "duration"):
            return ("map", [("secs", "0"), ("nsecs", "0")], True)
        if base in BUILTIN_TYPES:
            return _SCALAR_DEFAULTS.get(base, "0")
        return self.message(self.store.msg(base))


def _inline(value: _Value) -> str:
    if isinstance(value, str):
        return value
    kind, items, _ = value
    if kind == "seq":
        return "[" + ", ".join(_inline(v) for v in items) + "]"
    return "{" + ", ".join(f"{k}: {_inline(v)}" for k, v in items) + "}"


def _writes_inline(value: _Value, flow: bool | None) -> bool:
    if isinstance(value, str) or not value[1]:
        return True
    return value[2] if flow is None else flow


def _block(value: _Node, indent: str, flow: bool | None) -> list[str]:
    """Lines of a mapping or a sequence in block style; nested values by the chosen style."""
    kind, items, _ = value
    lines: list[str] = []
    for item in items:
        key, sub = item if kind == "map" else ("", item)
        lead = f"{indent}{key}:" if kind == "map" else f"{indent}-"
        if isinstance(sub, str) or _writes_inline(sub, flow):
            lines.append(f"{lead} {_inline(sub)}")
        elif kind == "seq":
            # a mapping in a sequence starts on the hyphen's line
            inner = _block(sub, indent + "  ", flow)
            lines += [f"{lead} {inner[0].lstrip()}", *inner[1:]]
        else:
            # YAML allows a sequence under a key at the key's own indent, as rosmsg writes it
            lines += [lead, *_block(sub, indent if sub[0] == "seq" else indent + "  ", flow)]
    return lines


def proto(
    store: TypeStore,
    spec: MsgSpec,
    *,
    flow: bool | None = None,
    empty_arrays: bool = False,
    exclude: frozenset[str] = frozenset(),
) -> str:
    """A YAML template of a message with default values, as rosmsg-proto prints it.

    ``flow`` True writes everything in brackets on one line, False never uses brackets, and
    None (the default) writes times and arrays of scalars in brackets, the rest as blocks.
    Fields named in ``exclude`` are left out at every depth.
    """
    _check(store, spec)
    tree = _Proto(store, empty_arrays, exclude).message(spec)
    if flow or not tree[1]:
        return _inline(tree)
    return "\n".join(_block(tree, "", flow))
