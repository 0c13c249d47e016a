"""What every command shares on the Typer side.

The common options, the settings of an invocation, and ``add``, which turns declared commands
(``rostools.cli.declare``) into a group's Typer commands.
"""

from __future__ import annotations

import ast
import functools
import inspect
import math
import sys
import typing
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, TypeVar

import typer

from rostools.cli import output
from rostools.cli.declare import declared
from rostools.cli.output import Format
from rostools.cli.settings import Settings

T = TypeVar("T")

if TYPE_CHECKING:
    from collections.abc import Awaitable, Callable

    from rostools.node.notice import Notice
    from rostools.rosgraph.masterapi import MasterProxy

try:
    from typer._click.types import FloatRange
except ImportError:  # pragma: no cover - older typer uses the click package
    from click.types import FloatRange  # type: ignore[no-redef,import-not-found,assignment,unused-ignore]


class FiniteFloat(FloatRange):  # type: ignore[misc,unused-ignore]
    """A float option: ``nan`` and ``inf`` are usage errors (exit 2), not crashes later."""

    def convert(self, value: Any, param: Any, ctx: Any) -> Any:
        """Click's float (in range, if one is given), finite."""
        number = super().convert(value, param, ctx)
        if not math.isfinite(number):
            self.fail(f"{value!r} is not a finite number", param, ctx)
        return number


#: Every float option's type (``typer.Option(..., click_type=FINITE)``); with bounds,
#: ``FiniteFloat(min=...)`` (typer ignores ``min=`` once a ``click_type`` is given).
FINITE = FiniteFloat()


def settings(ctx: typer.Context) -> Settings:
    """The global settings of this invocation."""
    root = ctx.find_root()
    if not isinstance(root.obj, Settings):
        root.obj = Settings()
    return root.obj


def add(app: typer.Typer, *commands: Callable[..., Any]) -> None:
    """Add declared commands (``rostools.cli.declare``) to a group's app, in ``--help`` order.

    A quick command is marked ``rostools_quick`` for ``quick.json``: the launcher may call
    the function itself.
    """
    for function in commands:
        found = declared(function)
        callback = _callback(function)
        if found.quick:
            callback.__dict__["rostools_quick"] = f"{function.__module__}:{function.__name__}"
        app.command(found.name, **found.settings)(callback)


def alias(app: typer.Typer, name: str, function: Callable[..., Any], help: str) -> None:
    """Add a declared command a second time, as ``name`` (``msg info`` is ``msg show``)."""
    app.command(name, help=help, **declared(function).settings)(_callback(function))


def _callback(function: Callable[..., Any]) -> Callable[..., Any]:
    """``function`` as Typer calls it.

    A ``Settings`` first parameter becomes Typer's context, and a parameter that is an
    options record (a dataclass of options that several commands take) becomes its fields,
    gathered into the record again for the call. Anything else is Typer's as it is.
    """
    first, *params = inspect.signature(function).parameters.values()
    try:
        hints = typing.get_type_hints(function, include_extras=True)
    except NameError:  # it names what its module imports for annotations only
        names = _annotation_names(function.__module__)
        hints = typing.get_type_hints(function, names, include_extras=True)
    wants_settings = hints[first.name] is Settings
    if not wants_settings and not any(_is_record(hints[p.name]) for p in params):
        return function
    flat: list[inspect.Parameter] = []
    gathered: dict[str, tuple[type[Any], list[str]]] = {}
    for p in params:
        if _is_record(hints[p.name]):
            kind = hints[p.name]
            fields = _record_fields(kind)
            gathered[p.name] = (kind, [f.name for f in fields])
            flat += fields
        else:  # Typer passes every value by name
            flat.append(p.replace(annotation=hints[p.name], kind=inspect.Parameter.KEYWORD_ONLY))

    def callback(ctx: typer.Context, **values: Any) -> Any:
        for name, (kind, members) in gathered.items():
            values[name] = kind(**{m: values.pop(m) for m in members})
        return function(settings(ctx) if wants_settings else ctx, **values)

    context = inspect.Parameter(
        "ctx", inspect.Parameter.POSITIONAL_OR_KEYWORD, annotation=typer.Context
    )
    callback.__signature__ = inspect.Signature([context, *flat])  # type: ignore[attr-defined]
    callback.__annotations__ = {"ctx": typer.Context} | {p.name: p.annotation for p in flat}
    for attribute in ("__name__", "__qualname__", "__module__", "__doc__"):
        setattr(callback, attribute, getattr(function, attribute))
    return callback


def options_record(kind: type[T]) -> type[T]:
    """Mark a dataclass of options as a record that commands take as one parameter.

    Its fields are ``Annotated`` options, each declared once for every command that takes
    the record (``bag record`` and ``bag snapshot`` share what to record and where).
    """
    kind.rostools_options = True  # type: ignore[attr-defined]
    return kind


def _is_record(hint: object) -> bool:
    """Whether a parameter's type is an options record (``options_record``)."""
    return isinstance(hint, type) and getattr(hint, "rostools_options", False) is True


def _record_fields(kind: type[Any]) -> list[inspect.Parameter]:
    """The fields of an options record, as keyword parameters with their options."""
    import dataclasses

    hints = typing.get_type_hints(kind, include_extras=True)
    return [
        inspect.Parameter(
            f.name, inspect.Parameter.KEYWORD_ONLY, annotation=hints[f.name], default=f.default
        )
        for f in dataclasses.fields(kind)
    ]


@functools.cache
def _annotation_names(module_name: str) -> dict[str, Any]:
    """The names a module's annotations may use.

    Its own, and those it imports under ``if TYPE_CHECKING:`` (Typer and the option aliases,
    kept off the quick path), imported now.
    """
    module = sys.modules[module_name]
    names = dict(vars(module))
    for statement in ast.parse(inspect.getsource(module)).body:
        if isinstance(statement, ast.If) and ast.unparse(statement.test) == "TYPE_CHECKING":
            code = compile(ast.Module(statement.body, []), module.__name__, "exec")
            exec(code, names)  # noqa: S102 - the module's own import statements
    return names


def output_format(ctx: typer.Context, local: Format | None) -> Format:
    """A command's ``--format`` wins over the global one."""
    return settings(ctx).output_format(local)


def master(ctx: typer.Context, tool: str) -> MasterProxy:
    """A master client for this invocation, named like rospy tools name themselves."""
    return settings(ctx).master(tool)


def node_session(
    ctx: typer.Context,
    main: Callable[[Any, Any], Awaitable[T]],
    name: str,
    fmt: Format = Format.text,
) -> T:
    """Run ``main(node, stop)`` as an anonymous node named after ``name``.

    The command line's remapping arguments (``__name:=``, ``a:=b``, ...) apply to it. The
    node's notices go to stderr; a stream printed with ``fmt`` json also carries them as
    ``{"event": ...}`` objects.
    """
    from rostools.node.notice import to_stderr
    from rostools.node.session import run_node

    def notify(notice: Notice) -> None:
        to_stderr(notice)
        if fmt is not Format.text:  # in the stream, a record among the others
            output.write(fmt, notice.as_json())

    s = settings(ctx)
    return run_node(main, s.resolved_master_uri(), name, remappings=s.remappings, notify=notify)


FormatOpt = Annotated[
    Format | None,
    typer.Option(
        "--format", "-F", help="Output format (overrides the global --format).", show_default=False
    ),
]
MsgPathOpt = Annotated[
    list[Path] | None,
    typer.Option(
        "--msg-path",
        help="A folder of ROS packages with msg/ and srv/ folders (repeatable; also "
        "ROSTOOLS_MSG_PATH).",
        show_default=False,
    ),
]
