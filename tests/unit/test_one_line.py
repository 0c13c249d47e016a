"""``errors.one_line`` and ``output.lines``: a foreign name printed as text stays on its line."""

from __future__ import annotations

import re
import sys

from rostools.cli.output import lines
from rostools.errors import one_line


def test_no_code_point_breaks_a_line_or_reaches_the_terminal_as_a_control() -> None:
    every = "".join(chr(c) for c in range(sys.maxunicode + 1) if not 0xD800 <= c <= 0xDFFF)
    shown = one_line(every)
    assert len(shown.splitlines()) == 1
    assert not re.search(r"[\x00-\x1f\x7f-\x9f]", shown)
    # one_line returns a printable name untouched: so no character it escapes may be printable
    # (after a NUL, the name is not printable, and each character meets the escape table)
    assert all(one_line("\0" + ch) == "\\x00" + ch for ch in every if ch.isprintable())


def test_escapes_read_as_python_writes_them() -> None:
    assert one_line("/x\n/y\r\x1b[31m\x85\u2028") == "/x\\n/y\\r\\x1b[31m\\x85\\u2028"
    assert one_line("/plain_name") == "/plain_name"
    assert one_line(42) == "42"  # a master that answers a number for a name


def test_lines_is_one_line_per_name() -> None:
    assert lines(["/a\n/b", "/c"]) == "/a\\n/b\n/c"
    assert lines([]) == ""
