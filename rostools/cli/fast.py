"""The hottest commands, answered without importing typer (about 40 ms of start-up).

Only argument lists with no options take this path; anything else goes through the Typer app,
which runs the same functions. ``tests/unit/test_fast_path.py`` checks both give the same
output.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence


def dispatch(argv: Sequence[str]) -> int | None:
    """Run ``argv`` if it is a fast command and return its exit status, else None."""
    if len(argv) == 3 and argv[0] == "msg" and argv[1] == "md5" and not argv[2].startswith("-"):
        from rostools.cli.lookup import md5_text, md5sums, read_type
        from rostools.msgs.store import TypeStore

        name = read_type(argv[2])
        sys.stdout.write(md5_text(name, md5sums(TypeStore.default(), name)))
        return 0
    return None
