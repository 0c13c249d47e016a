"""Declared commands (``rostools.cli.declare``) made Typer's: a group's ``group.py`` adds them.

A command's function is Typer's as it is, unless it takes the invocation's ``Settings`` first
or an options record: then a callback with Typer's context first and the record's fields
flattened into its signature calls it. Annotations that name what the command's module
imports for annotations only are resolved with those imports, made now.
"""

from __future__ import annotations

import ast
import functools
import inspect
import sys
from collections.abc import Callable
from typing import Any

import typer

from rostools.cli.common import settings
from rostools.cli.declare import declared, is_record
from rostools.cli.settings import Settings


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
    hints = {p.name: _resolved(p.annotation, function.__module__) for p in (first, *params)}
    wants_settings = hints[first.name] is Settings
    if not wants_settings and not any(is_record(hints[p.name]) for p in params):
        return function
    flat: list[inspect.Parameter] = []
    gathered: dict[str, tuple[type[Any], list[str]]] = {}
    for p in params:
        if is_record(hints[p.name]):
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


def _record_fields(kind: type[Any]) -> list[inspect.Parameter]:
    """The fields of an options record, as keyword parameters with their options."""
    import dataclasses

    hints = {name: _resolved(a, kind.__module__) for name, a in kind.__annotations__.items()}
    return [
        inspect.Parameter(
            f.name, inspect.Parameter.KEYWORD_ONLY, annotation=hints[f.name], default=f.default
        )
        for f in dataclasses.fields(kind)
    ]


def _resolved(annotation: Any, module_name: str) -> Any:
    """An annotation as an object, evaluated where it was written.

    Not ``typing.get_type_hints``: before Python 3.11 it wraps the annotation of a parameter
    that defaults to None in ``Optional``, which hides the ``Annotated`` option from Typer.
    """
    if not isinstance(annotation, str):
        return annotation
    try:
        return eval(annotation, vars(sys.modules[module_name]))  # noqa: S307 - our own source
    except NameError:  # it names what its module imports for annotations only
        return eval(annotation, _annotation_names(module_name))  # noqa: S307


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
