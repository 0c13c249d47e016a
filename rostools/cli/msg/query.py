"""``rostools msg md5``, Typer-free (``rostools.cli.declare``): the launcher runs it."""

from __future__ import annotations

from rostools.cli import output
from rostools.cli.declare import command
from rostools.cli.msg.lookup import md5_text, md5sums, read_type
from rostools.cli.output import Format, emit
from rostools.cli.settings import type_store

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from rostools.cli.common import FormatOpt, MsgPathOpt
    from rostools.cli.msg.options import TypeArg
    from rostools.cli.settings import Settings


@command(quick=True)
def md5(
    s: Settings, type_name: TypeArg = None, fmt: FormatOpt = None, msg_path: MsgPathOpt = None
) -> None:
    """Print the md5sum of a message or service type (rosmsg/rossrv md5)."""
    name = read_type(type_name)
    found = md5sums(type_store(msg_path), name)
    out = s.output_format(fmt)
    if out is Format.text:
        output.put(md5_text(name, found))
    else:
        data = [{"type": t, "md5sum": m} for t, m in found]
        emit(out, data[0] if "/" in name else data)
