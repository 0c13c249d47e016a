"""How commands print: one result in text, JSON or YAML, or a stream of records as they come.

One-shot results (``render``/``emit``) are one document: indented JSON, or YAML. Streams
(``record``/``write``: echo's messages, hz/bw/delay's reports, ``node ping``'s replies, bag
progress, ``bag filter --print``, a running node's notices) read the same whichever command
made them:

- text: the command's own line (``text(data)``);
- ``--format yaml``: each record a YAML document that ends with ``---``, as ``rostopic echo``
  ends each message;
- ``--format json``: NDJSON, one compact object a line, always valid JSON (NaN and infinity,
  which JSON lacks, become the strings "nan", "inf" and "-inf", as in echo's messages).

Names, types and URIs that come from the master, a peer or a file are foreign: text output
passes each through ``one_line`` (``lines`` for a list), so that a newline, a terminal escape
or U+2028 in one cannot forge lines. JSON and YAML keep them raw; their encoders escape.
"""

from __future__ import annotations

import enum
import sys

from rostools.errors import one_line

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from collections.abc import Callable, Iterable
    from pathlib import Path
    from typing import Any


class Format(str, enum.Enum):
    """Output formats."""

    text = "text"
    json = "json"
    yaml = "yaml"


def lines(names: Iterable[str]) -> str:
    """Foreign names one a line, each escaped by ``one_line``."""
    return "\n".join(map(one_line, names))


def render(fmt: Format, data: Any, text: Callable[[Any], str] | None = None) -> str:
    """One result as text (``text(data)``), or as one JSON or YAML document."""
    if fmt is Format.json:
        import json  # json and yaml load when asked for: text is the common case

        return json.dumps(data, indent=2, ensure_ascii=False)
    if fmt is Format.yaml:
        import yaml

        text_ = str(yaml.safe_dump(data, sort_keys=False, allow_unicode=True))
        return text_.removesuffix("\n...\n").rstrip("\n")  # a scalar has no end-of-document mark
    return text(data) if text is not None else str(data)


def emit(fmt: Format, data: Any, text: Callable[[Any], str] | None = None) -> None:
    """Print one result (see ``render``) and a newline."""
    sys.stdout.write(render(fmt, data, text) + "\n")


def record(fmt: Format, data: Any, text: Callable[[Any], str] | None = None) -> str:
    """One record of a stream, with its line end (see the module's rules)."""
    if fmt is Format.json:
        from rostools.msgs.plain import dumps

        return dumps(data) + "\n"
    if fmt is Format.yaml:
        import yaml

        return str(yaml.safe_dump(data, sort_keys=False, allow_unicode=True)) + "---\n"
    return (text(data) if text is not None else str(data)) + "\n"


def write(fmt: Format, data: Any, text: Callable[[Any], str] | None = None) -> None:
    """Print one record now (a stream is read as it comes, so each is flushed)."""
    sys.stdout.write(record(fmt, data, text))
    sys.stdout.flush()


def put(text: str) -> None:
    """Write text that a command has laid out itself to stdout, as it is.

    Every byte a command prints on stdout goes through this module.
    """
    sys.stdout.write(text)


def line(text: str, flush: bool = False) -> None:
    """Write one line of text (``print``'s way); ``flush`` for a line a reader waits for."""
    sys.stdout.write(text + "\n")
    if flush:
        sys.stdout.flush()


def put_bytes(data: bytes | memoryview) -> None:
    """Write bytes to stdout as they are (``bag attachments --get`` into a pipe)."""
    sys.stdout.flush()
    sys.stdout.buffer.write(data)
    sys.stdout.buffer.flush()


def flush() -> None:
    """Hand what was written to stdout on now: the reader of a stream waits for it."""
    sys.stdout.flush()


def check_writable(path: Path) -> None:
    """Fail now, exit 2, when no file can be created where ``path`` goes.

    Tried, not guessed from permission bits, which root ignores. Every command that writes
    a file it was given checks this before it does the work.
    """
    import tempfile
    from pathlib import Path

    from rostools.errors import cannot_write

    folder = path.parent if str(path.parent) else Path(".")
    try:
        with tempfile.TemporaryFile(dir=folder):
            pass
    except OSError as err:
        why = "no such folder" if not folder.is_dir() else err.strerror or str(err)
        raise cannot_write(path, f"{folder}: {why}") from err
