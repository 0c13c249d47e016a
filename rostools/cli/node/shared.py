"""What the node commands share, without Typer: names, the graph, failures, warnings."""

from __future__ import annotations

import sys

from rostools.errors import NotFoundError, RostoolsError, TimeoutExpired, UnreachableError, one_line
from rostools.names import script_resolve

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from rostools.cli.settings import Settings
    from rostools.rosgraph.nodeapi import Graph

TOOL = "rosnode"


def graph(s: Settings, timeout: float | None = None) -> Graph:
    """The graph as a node command sees it: the master, and nodes asked with ``timeout``.

    By default rosnode's ``NODE_TIMEOUT``.
    """
    from rostools.rosgraph.masterapi import NODE_TIMEOUT
    from rostools.rosgraph.nodeapi import Graph

    return Graph(s.master(TOOL), NODE_TIMEOUT if timeout is None else timeout)


def resolve_node(name: str) -> str:
    """A node name from the command line, resolved as rosnode does."""
    return script_resolve(name, TOOL)


def failure_class(errors: list[RostoolsError]) -> type[RostoolsError]:
    """The error class (so the exit code) for several nodes' failures.

    Each kind alone keeps its own code (not found 3, timeout 5); a mix is "unreachable" (4),
    the code for a node that cannot be talked to.
    """
    for kind in (NotFoundError, TimeoutExpired):
        if all(isinstance(e, kind) for e in errors):
            return kind
    return UnreachableError


def worst(errors: list[RostoolsError], what: str) -> RostoolsError:
    """One error for several failures: the first's, or a summary with the right exit code."""
    if len(errors) == 1:
        return errors[0]
    return failure_class(errors)(
        f"{what} {len(errors)} nodes: " + "; ".join(str(e) for e in errors)
    )


def warn(text: str) -> None:
    """One line on stderr that does not stop the command (names in it escaped)."""
    sys.stderr.write(f"rostools: {one_line(text)}\n")
