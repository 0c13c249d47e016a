"""Commands that only ask the master, runnable without Typer.

Each function here is the body of a Typer command, taking the invocation's ``Settings``
and the command's parameters by name. ``rostools.cli.launch`` parses the command line with
the grammar Typer itself wrote into ``quick.json`` and calls them directly, so a command
such as ``param get`` starts without importing Typer (50 ms); anything it does not
understand (help, a mistake, an unusual form) goes to Typer, which runs the same functions.
"""

from __future__ import annotations

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import Any, TypeVar

    F = TypeVar("F", bound=Callable[..., Any])


def runs(body: Callable[..., Any]) -> Callable[[F], F]:
    """Mark a Typer command as running ``body``: the launcher may call ``body`` itself."""

    def mark(command: F) -> F:
        command.__dict__["rostools_quick"] = f"{body.__module__}:{body.__name__}"
        return command

    return mark
