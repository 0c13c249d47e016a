"""The one exception hierarchy of rostools.

Library code raises these; ``rostools.cli`` turns them into a one-line message and the exit
code below. The table of exit codes in docs/scripting.md lists ``EXIT_CODES`` (a test checks).
"""

from __future__ import annotations

# Names and values quoted in a message may carry control characters or Unicode line
# breaks (NEL, U+2028); escape them so every line stays one line, on a terminal and in logs.
_ESCAPES = {c: repr(chr(c))[1:-1] for c in (*range(0x20), *range(0x7F, 0xA0), 0x2028, 0x2029)}


def one_line(text: object) -> str:
    """``text`` with newlines and other control characters escaped.

    Every name, type and URI that comes from a peer or a file goes through it before it is
    printed as text; JSON escapes them itself. Not a string (a master that answers a number
    for a name) is printed as ``str`` would print it.
    """
    text = text if type(text) is str else str(text)
    # Every escaped character is unprintable, so most names need only the cheaper test
    # (100,000 names: 214 ms through translate, 25 ms so).
    return text if text.isprintable() else text.translate(_ESCAPES)


class RostoolsError(Exception):
    """Base of every error rostools reports to a user: the operation failed."""

    exit_code = 1

    def __init__(self, message: str, *, hint: str | None = None) -> None:
        super().__init__(message)
        self.hint = hint


class UsageError(RostoolsError):
    """Bad arguments or values given by the user (a wrong field type, bad YAML, ...)."""

    exit_code = 2


class NotFoundError(RostoolsError):
    """A topic, type, service, parameter, node or file that does not exist."""

    exit_code = 3


class UnreachableError(RostoolsError):
    """The master or a peer node cannot be contacted."""

    exit_code = 4


class TimeoutExpired(RostoolsError):  # noqa: N818 - reads better than TimeoutError, a builtin
    """A wait ran past its ``--timeout``."""

    exit_code = 5


class DataLossError(RostoolsError):
    """Data was lost or could not be salvaged (recover, record drops)."""

    exit_code = 6


class ServiceError(RostoolsError):
    """A service answered a call with a failure; the message carries the server's text."""

    exit_code = 1


class InvalidDataError(RostoolsError):
    """Malformed input data: a bad definition, a corrupt file, garbage from a peer."""

    exit_code = 1


class GoalAborted(RostoolsError):  # noqa: N818 - named after the goal state, as actionlib's
    """An action server aborted the goal (``action send-goal``)."""

    exit_code = 7


class GoalRejected(RostoolsError):  # noqa: N818
    """An action server rejected the goal."""

    exit_code = 8


class GoalPreempted(RostoolsError):  # noqa: N818
    """The goal was canceled by someone else (PREEMPTED or RECALLED), or replaced."""

    exit_code = 9


class QuietExit(RostoolsError):  # noqa: N818 - not a failure of its own: an ending
    """A command that has already said all there is to say ends with ``exit_code``, no line.

    ``bag doctor`` with findings (1), ``msg proto -s`` (its error's code, silently),
    ``action send-goal``/``cancel`` on Ctrl-C once the goal is canceled (130).
    """

    def __init__(self, exit_code: int) -> None:
        super().__init__("")
        self.exit_code = exit_code


class MissingExtraError(UsageError):
    """An optional dependency a feature needs is not installed: exit 2, naming the extra.

    ``MissingExtraError("pyarrow", "arrow")`` reads "pyarrow is not installed: pip install
    'rostools[arrow]'". Code that needs an extra imports it inside a function and raises this
    on ``ImportError`` (``bag/tables/arrow.py``: pyarrow; duckdb likewise, extra ``sql``).
    """

    def __init__(self, module: str, extra: str, *, what: str = "") -> None:
        needs = f"{what} needs {module}" if what else f"{module} is not installed"
        super().__init__(f"{needs}: pip install 'rostools[{extra}]'")
        self.module = module
        self.extra = extra


def cannot_write(path: object, why: str) -> UsageError:
    """An output the user named that cannot be created: exit 2 in every command.

    The path is the user's argument, so a missing folder or one without write permission is
    the user's to fix, as a bad value is.
    """
    return UsageError(f"cannot write {path}: {why}")


#: Exit code, name and meaning, in the order docs/scripting.md lists them.
EXIT_CODES: tuple[tuple[int, str, str], ...] = (
    (
        0,
        "ok",
        "success; also Ctrl-C on a command that runs until stopped (echo, hz, pub, ...), "
        "or its reader closing the pipe (`| head`)",
    ),
    (
        1,
        "error",
        "the operation failed, or the input data is malformed (`bag info`: the bag is unindexed)",
    ),
    (2, "usage", "bad arguments or values: unknown option, wrong field type, bad YAML"),
    (3, "not found", "unknown topic, type, service, parameter, node or file"),
    (4, "unreachable", "the master or a peer node could not be contacted"),
    (5, "timeout", "a wait ran past its --timeout"),
    (6, "data loss", "data was lost: recovery could not salvage everything, or records dropped"),
    (7, "goal aborted", "action send-goal: the action server aborted the goal"),
    (8, "goal rejected", "action send-goal: the action server rejected the goal"),
    (9, "goal preempted", "action send-goal: the goal was canceled by another client, or replaced"),
    (130, "interrupted", "Ctrl-C during a command that was not meant to run until stopped"),
)
