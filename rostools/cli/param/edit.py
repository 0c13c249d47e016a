"""``rostools param set|delete|load|dump``: change the parameter server, or save it."""

from __future__ import annotations

import sys
from pathlib import Path

from rostools.cli import output
from rostools.cli.declare import command
from rostools.cli.output import Format, render
from rostools.cli.param import paramyaml
from rostools.cli.param.shared import TOOL, say
from rostools.errors import NotFoundError, UsageError, cannot_write
from rostools.names import GLOBAL_NS, join, make_global_ns, script_resolve

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Annotated, Any

    import typer

    from rostools.cli.common import FormatOpt
    from rostools.cli.param.options import NameArg, VerboseOpt
    from rostools.cli.settings import Settings


def _print_params(params: Any, ns: str) -> None:
    """rosparam's -v listing of what load and dump carry: ``name=value`` per leaf."""
    if not isinstance(params, dict):
        output.put(f"{params}\n")
        return
    for key, value in params.items():
        if isinstance(value, dict):
            _print_params(value, join(ns, key))
        else:
            output.put(f"{join(ns, key)}={value}\n")


def _set_tree(proxy: Any, name: str, value: Any, verbose: bool) -> None:
    """Rosparam's set: a mapping updates key by key; anything else is set as it is."""
    if isinstance(value, dict):
        for key, item in value.items():
            if not isinstance(key, str):
                raise UsageError(f"parameter names must be strings, not {key!r} under {name}")
            _set_tree(proxy, join(name if name.endswith("/") else name + "/", key), item, verbose)
        return
    proxy.set_param(name, value)
    say(verbose, f"set parameter [{name}] to [{value}]")


@command(context_settings={"ignore_unknown_options": True})
def set(
    s: Settings,
    name: NameArg,
    value: Annotated[
        str | None,
        typer.Argument(
            help="A YAML value; a mapping updates the keys it names.", show_default=False
        ),
    ] = None,
    textfile: Annotated[
        Path | None, typer.Option("--textfile", "-t", help="Set to the text of this file.")
    ] = None,
    binfile: Annotated[
        Path | None, typer.Option("--binfile", "-b", help="Set to the bytes of this file.")
    ] = None,
    verbose: VerboseOpt = False,
) -> None:
    """Set a parameter from YAML (negative numbers need no '--')."""
    import xmlrpc.client

    key = script_resolve(name, TOOL)
    given = [v is not None for v in (value, textfile, binfile)]
    if sum(given) != 1:
        raise UsageError("give exactly one of a value, --textfile or --binfile")
    if textfile is not None:
        parsed: Any = _text(_read(textfile), str(textfile))
    elif binfile is not None:
        parsed = xmlrpc.client.Binary(_read(binfile))
    else:
        assert value is not None
        parsed = "" if value == "" else paramyaml.load(value)
    paramyaml.check_value(parsed, key)
    _set_tree(s.master(TOOL), key, parsed, verbose)


def _text(data: bytes, source: str) -> str:
    """``data`` as UTF-8; else a usage error (rosparam refuses it: XML-RPC strings are text)."""
    try:
        return data.decode()
    except UnicodeDecodeError as err:
        raise UsageError(f"{source} is not UTF-8 text (byte {err.start})") from None


def _read(path: Path) -> bytes:
    try:
        return path.read_bytes()
    except FileNotFoundError:
        raise NotFoundError(f"file {path} does not exist") from None
    except OSError as err:
        raise UsageError(f"cannot read {path}: {err.strerror}") from err


@command()
def delete(s: Settings, name: NameArg, verbose: VerboseOpt = False) -> None:
    """Delete a parameter or a namespace; '/' empties the whole server."""
    key = script_resolve(name, TOOL)
    proxy = s.master(TOOL)
    if key == GLOBAL_NS:
        proxy.set_param(GLOBAL_NS, {})
        say(verbose, "deleted ENTIRE parameter server")
    else:
        proxy.delete_param(key)
        say(verbose, f"deleted parameter [{key}]")


@command()
def load(
    s: Settings,
    file: Annotated[str, typer.Argument(help="A YAML file; - reads stdin.")],
    namespace: Annotated[str, typer.Argument(help="Load under this namespace.")] = "",
    verbose: VerboseOpt = False,
) -> None:
    """Load parameters from a YAML file (every document; a '_ns' key picks a namespace)."""
    source = "stdin" if file == "-" else file
    text = _text(sys.stdin.buffer.read() if file == "-" else _read(Path(file)), source)
    say(verbose, "reading parameters from " + ("stdin" if file == "-" else f"[{file}]"))
    base = script_resolve(namespace, TOOL)
    proxy = s.master(TOOL)
    loaded: list[tuple[Any, str]] = []
    for doc in paramyaml.load_all(text, source):
        if doc is None:
            continue
        ns = base
        if isinstance(doc, dict) and "_ns" in doc:
            ns = join(make_global_ns(base), str(doc.pop("_ns")))
            say(verbose, f"reading parameters into namespace [{ns}]")
        if ns == GLOBAL_NS and not isinstance(doc, dict):
            raise UsageError("a document loaded into / must be a mapping")
        paramyaml.check_value(doc, ns)
        loaded.append((doc, ns))
    for doc, ns in loaded:  # every document is read and checked before any is set
        if verbose:
            _print_params(doc, ns)
        _set_tree(proxy, ns, doc, False)


@command()
def dump(
    s: Settings,
    file: Annotated[
        str | None, typer.Argument(help="Write here; stdout when omitted or -.")
    ] = None,
    namespace: Annotated[str, typer.Argument(help="Only this namespace.")] = "",
    verbose: VerboseOpt = False,
    fmt: FormatOpt = None,
) -> None:
    """Write parameters as YAML, to a file or stdout."""
    key = script_resolve(namespace, TOOL)
    say(verbose, f"dumping namespace [{namespace}] to file [{file}]")  # as given
    value = s.master(TOOL).get_param(key)
    if verbose:
        _print_params(value, key)
    fmt = s.output_format(fmt)
    if fmt is Format.text:
        text = paramyaml.dump(value)
    else:
        text = render(fmt, paramyaml.to_plain(value)) + "\n"
    if file in (None, "-"):
        output.put(text)
        return
    try:
        Path(file).write_text(text)
    except OSError as err:  # it was an internal error: PermissionError
        raise cannot_write(file, err.strerror or str(err)) from err
