"""``action list`` without Typer (see ``rostools.cli.quick``)."""

from __future__ import annotations

from rostools.cli.output import emit, lines

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from rostools.cli.output import Format
    from rostools.cli.settings import Settings


def list_actions(s: Settings, show_types: bool, fmt: Format | str | None) -> None:
    """List the actions in the graph: names with all five topics of an action."""
    from rostools.action.graph import find_actions

    proxy = s.master("rostools")
    pubs, subs, _ = proxy.system_state()
    found = find_actions(proxy.topic_types(), pubs, subs)
    text = lines(f"{a.name} [{a.type}]" if show_types else a.name for a in found)
    emit(s.output_format(fmt), [a.as_dict() for a in found], lambda _: text)
