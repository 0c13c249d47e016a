"""A command declared once, without Typer: its name, and whether the launcher may run it.

A command is one function. Its signature is the command line: each parameter's annotation is
``Annotated[type, typer.Option(...)]`` (or an alias such as ``FormatOpt``), and its docstring
is the help. Modules of commands import Typer and their option aliases for annotations only
(``if TYPE_CHECKING:``); with ``from __future__ import annotations`` the annotations stay
text, so a module of commands imports no Typer. ``rostools.cli.register.add`` reads them when
a group's Typer app (``group.py``) is built, and ``python -m rostools.cli.completion`` writes
the grammar of each ``quick`` command into ``quick.json`` for ``rostools.cli.launch``.

A command whose first parameter is ``s: Settings`` gets the invocation's settings; one whose
first parameter is ``ctx: typer.Context`` gets Typer's context.
"""

from __future__ import annotations

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from collections.abc import Callable
    from typing import Any, TypeVar

    F = TypeVar("F", bound=Callable[..., Any])
    T = TypeVar("T")

#: The attribute of a declared function that holds its ``Declared``.
ATTRIBUTE = "rostools_command"


class Declared:
    """What ``command`` says of a function: its name, quickness and Typer's extra settings.

    A plain class: ``dataclasses`` costs 15 ms of start-up.
    """

    def __init__(self, name: str, quick: bool, settings: dict[str, Any]) -> None:
        self.name = name
        self.quick = quick
        #: Keyword arguments for ``typer.Typer.command`` (``context_settings``, ``hidden``).
        self.settings = settings


def command(name: str | None = None, *, quick: bool = False, **settings: Any) -> Callable[[F], F]:
    """Declare a function as a command named ``name`` (by default its own name, ``_`` as ``-``).

    ``quick``: the launcher may run it without Typer; its module must then import neither
    Typer nor anything heavy at the top (``tests/unit/test_launch.py``).
    """

    def mark(function: F) -> F:
        label = name or function.__name__.strip("_").replace("_", "-")
        function.__dict__[ATTRIBUTE] = Declared(label, quick, settings)
        return function

    return mark


def declared(function: Callable[..., Any]) -> Declared:
    """The declaration of ``function``; a function never declared is a programming error."""
    found = function.__dict__.get(ATTRIBUTE)
    if not isinstance(found, Declared):
        raise TypeError(f"{function.__qualname__} is not declared with rostools.cli.declare")
    return found


def options_record(kind: type[T]) -> type[T]:
    """Mark a dataclass of options as a record that commands take as one parameter.

    Its fields are ``Annotated`` options, each declared once for every command that takes
    the record (``bag record`` and ``bag snapshot`` share what to record and where).
    """
    kind.rostools_options = True  # type: ignore[attr-defined]
    return kind


def is_record(hint: object) -> bool:
    """Whether a parameter's type is an options record (``options_record``)."""
    return isinstance(hint, type) and getattr(hint, "rostools_options", False) is True
