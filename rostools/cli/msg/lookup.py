"""Finding types by the names users type, shared by the msg commands (Typer-free)."""

from __future__ import annotations

import sys
from typing import Literal

from rostools.errors import NotFoundError, UsageError
from rostools.msgs.store import TypeStore

Kind = Literal["msg", "srv", "action"]


def read_type(name: str | None) -> str:
    """The type argument, or the first line of stdin; ``.msg``/``.srv``/``.action`` dropped."""
    if name is None:
        if sys.stdin.isatty():
            raise UsageError("give a type, or pipe one on stdin")
        name = next((line.strip() for line in sys.stdin if line.strip()), "")
        if not name:
            raise UsageError("no type given on stdin")
    for suffix in (".msg", ".srv", ".action"):
        name = name.removesuffix(suffix)
    if "::" in name or "." in name:
        raise UsageError(f"invalid type {name!r}", hint="write types as pkg/Type")
    return name


def matches(store: TypeStore, name: str) -> list[tuple[Kind, str]]:
    """The (kind, pkg/Type) pairs a name refers to; bare names search every package.

    ``pkg/NameAction`` is the action when its messages are all there (``pkg/msg/NameAction``
    is the message); ``pkg/action/Name`` always is, and ``pkg/Name`` is when no message or
    service has that name.
    """
    from rostools.msgs.action import action_name

    parts = name.strip("/").split("/")
    if len(parts) == 3 and parts[1] in ("msg", "srv", "action"):
        if parts[1] == "action":
            return [("action", action_name(name))]
        kind: Kind = "msg" if parts[1] == "msg" else "srv"
        return [(kind, f"{parts[0]}/{parts[2]}")]
    if len(parts) == 2:
        if name.endswith("Action") and store.has_action(name):
            return [("action", name)]
        if store.has_msg(name):
            return [("msg", name)]
        try:
            store.srv(name)
        except NotFoundError:
            if store.has_action(name):
                return [("action", action_name(name))]
            raise NotFoundError(
                f"unknown type {name}",
                hint="no such message, service or action; see 'rostools msg list'",
            ) from None
        return [("srv", name)]
    found: list[tuple[Kind, str]] = [
        ("action" if t.endswith("Action") and store.has_action(t) else "msg", t)
        for t in store.find("msg", name)
    ]
    found += [("srv", t) for t in store.find("srv", name)]
    if not found:
        raise NotFoundError(f"no message or service named {name} in any package")
    return found


def md5sums(store: TypeStore, name: str) -> list[tuple[str, str]]:
    """(pkg/Type, md5sum) of every type the name refers to."""
    return [
        (full, store.srv_md5(full) if kind == "srv" else store.md5(full))
        for kind, full in matches(store, name)
    ]


def md5_text(name: str, found: list[tuple[str, str]]) -> str:
    """Rosmsg md5's output: the bare sum for pkg/Type, ``[pkg/Type]: sum`` lines otherwise."""
    if "/" in name:
        return found[0][1] + "\n"
    return "".join(f"[{t}]: {m}\n" for t, m in found)
