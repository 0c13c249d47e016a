"""The command-line front end. ``main`` is the one place errors become exit codes."""

from __future__ import annotations

import os
import sys
from collections.abc import Sequence


def report(err: BaseException, debug: bool) -> int:
    """Print ``err`` as one line on stderr (a traceback with ``--debug``); its exit code."""
    from rostools.errors import RostoolsError

    if debug:
        import traceback

        traceback.print_exception(err)
    if isinstance(err, RostoolsError):
        hint = f" (hint: {err.hint})" if err.hint else ""
        sys.stderr.write(f"rostools: {err}{hint}\n")
        return err.exit_code
    sys.stderr.write(f"rostools: internal error: {type(err).__name__}: {err}\n")
    if not debug:
        sys.stderr.write("rostools: run again with --debug for the traceback\n")
    return 1


def main(argv: Sequence[str] | None = None) -> None:
    """Run the ``rostools`` command line and exit with its status."""
    args = list(sys.argv[1:] if argv is None else argv)
    try:
        from rostools.cli.fast import dispatch

        status = dispatch(args)
        if status is not None:
            sys.exit(status)
        from rostools.cli import app as root
        from rostools.names import split_remappings

        args, remappings = split_remappings(args)
        root.REMAPPINGS.update(remappings)
        root.app(args=args, prog_name="rostools")
    except SystemExit:
        raise
    except KeyboardInterrupt:
        sys.exit(130)
    except BrokenPipeError:
        # The reader went away (``| head``): stop quietly. Point stdout at /dev/null so the
        # interpreter's final flush does not raise again.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        sys.exit(0)
    except Exception as err:  # noqa: BLE001 - the one place every error is turned into an exit code
        sys.exit(report(err, "--debug" in args))
