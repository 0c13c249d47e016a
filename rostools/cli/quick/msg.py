"""``msg md5`` without Typer (see ``rostools.cli.quick``)."""

from __future__ import annotations

import sys

from rostools.cli.lookup import md5_text, md5sums, read_type
from rostools.cli.output import Format, emit
from rostools.cli.settings import type_store

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from pathlib import Path

    from rostools.cli.settings import Settings


def md5(
    s: Settings, type_name: str | None, fmt: Format | str | None, msg_path: list[Path] | None
) -> None:
    """Print the md5sum of a message or service type (rosmsg/rossrv md5)."""
    name = read_type(type_name)
    found = md5sums(type_store(msg_path), name)
    out = s.output_format(fmt)
    if out is Format.text:
        sys.stdout.write(md5_text(name, found))
    else:
        data = [{"type": t, "md5sum": m} for t, m in found]
        emit(out, data[0] if "/" in name else data)
