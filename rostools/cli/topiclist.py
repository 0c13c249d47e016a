"""rostopic list's output, shared by ``topic list`` and its typer-free fast path."""

from __future__ import annotations

from rostools.errors import one_line

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Any


def list_text(
    table: dict[str, Any], verbose: bool, pubs_only: bool, subs_only: bool, indent: str = ""
) -> str:
    """rostopic list's text: names, or with ``verbose`` the published/subscribed blocks."""
    infos = list(table.values())
    if not verbose:
        if pubs_only:
            names = [i.name for i in infos if i.publishers]
        elif subs_only:
            names = [i.name for i in infos if i.subscribers]
        else:
            names = [i.name for i in infos]
        return "\n".join(indent + one_line(n) for n in sorted(names))
    lines: list[str] = []
    if not subs_only:
        lines += ["", f"{indent}Published topics:"]
        for i in infos:
            if i.publishers:
                n = len(i.publishers)
                lines.append(f"{indent} * {_named(i)} {n} publisher{'s' if n > 1 else ''}")
    if not pubs_only:
        lines += [indent, f"{indent}Subscribed topics:"]
        for i in infos:
            if i.subscribers:
                n = len(i.subscribers)
                lines.append(f"{indent} * {_named(i)} {n} subscriber{'s' if n > 1 else ''}")
    lines.append("")
    return "\n".join(lines)


def _named(info: Any) -> str:
    """``/name [pkg/Type]``, escaped: both are the peers'."""
    return f"{one_line(info.name)} [{one_line(info.type)}]"
