"""The command-line front end. ``main`` is the one place errors become exit codes."""

from __future__ import annotations

import os
import sys

from rostools.errors import one_line

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from collections.abc import Sequence
    from typing import Any


def report(err: BaseException, debug: bool) -> int:
    """Print ``err`` as one line on stderr (a traceback with ``--debug``); its exit code."""
    from rostools.errors import QuietExit, RostoolsError

    if isinstance(err, QuietExit):
        return err.exit_code
    if debug:
        import traceback

        traceback.print_exception(err)
    if isinstance(err, RostoolsError):
        hint = f" (hint: {err.hint})" if err.hint else ""
        sys.stderr.write(one_line(f"rostools: {err}{hint}") + "\n")
        return err.exit_code
    sys.stderr.write(one_line(f"rostools: internal error: {type(err).__name__}: {err}") + "\n")
    if not debug:
        sys.stderr.write("rostools: run again with --debug for the traceback\n")
    return 1


def click_exceptions() -> Any:
    """Click's exception module (typer vendors click from 0.27 on)."""
    try:
        from typer._click import exceptions
    except ImportError:  # pragma: no cover - older typer uses the click package
        from click import exceptions  # type: ignore[no-redef,import-not-found,unused-ignore]
    return exceptions


def report_usage(err: Any) -> int:
    """A command-line mistake as one line (no-arguments help is printed whole)."""
    if type(err).__name__ == "NoArgsIsHelpError":
        err.show()
        return int(err.exit_code)
    ctx = getattr(err, "ctx", None)
    path = ctx.command_path if ctx is not None else ""
    where = f"{path.partition(' ')[2]}: " if " " in path else ""
    hint = f" (see '{path} -h')" if path else ""
    message = " ".join(err.format_message().split())
    sys.stderr.write(f"rostools: {where}{message}{hint}\n")
    return int(err.exit_code)


def main(argv: Sequence[str] | None = None) -> None:
    """Run the ``rostools`` command line and exit with its status."""
    args = list(sys.argv[1:] if argv is None else argv)
    try:
        from rostools.cli.launch import dispatch

        status = dispatch(args)
        if status is not None:
            sys.exit(status)
        from rostools.cli import app as root
        from rostools.names import split_remappings, use_command_namespace

        args, remappings = split_remappings(args)
        use_command_namespace(remappings)
        root.REMAPPINGS.update(remappings)
        status = root.app(args=args, prog_name="rostools", standalone_mode=False)
        sys.exit(status if isinstance(status, int) else 0)
    except SystemExit as done:
        # Typer, as click, turns any EPIPE into a silent exit 1, a closed reader's too
        if isinstance(done.__context__, BrokenPipeError) and _reader_gone():
            _quiet_exit()
        raise
    except click_exceptions().ClickException as err:
        sys.exit(report_usage(err))
    except KeyboardInterrupt:
        sys.exit(130)
    except BrokenPipeError as err:
        if _reader_gone():
            _quiet_exit()
        sys.exit(report(err, _debug(args)))  # a socket's, not our reader's
    except Exception as err:  # noqa: BLE001 - the one place every error is turned into an exit code
        sys.exit(report(err, _debug(args)))


def _debug(args: list[str]) -> bool:
    """Whether ``--debug`` was given as the root option: before the group name.

    After it, ``--debug`` is a command's value (``param set /x --debug``), not a request for
    tracebacks.
    """
    values = iter(args)
    for arg in values:
        if arg == "--debug":
            return True
        if arg in ("--master-uri", "--format"):  # the root options that take a value
            next(values, None)
        elif not arg.startswith("-"):
            return False  # the group's name
    return False


def _reader_gone() -> bool:
    """Whether stdout is a pipe whose reader went away (``| head``): poll says POLLERR."""
    import select

    try:
        poll = select.poll()
        poll.register(1, select.POLLOUT)
        return any(events & select.POLLERR for _, events in poll.poll(0))
    except (OSError, ValueError):
        return False


def _quiet_exit() -> None:
    """Exit 0, as rostopic does when its reader goes away: that is how ``| head`` ends it."""
    # stdout goes to /dev/null, so that the interpreter's final flush does not fail again
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, 1)
    sys.exit(0)
