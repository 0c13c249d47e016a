"""What a running node tells its user once, in one line: a peer it cannot reach, a restart.

A node hands each ``Notice`` to its ``notify`` callback. Commands print them on stderr; the
streaming commands also put them in their ``--format json`` stream as ``{"event": ...}``.
"""

from __future__ import annotations

import sys
from dataclasses import dataclass, field
from typing import Any

from rostools.errors import one_line


@dataclass(frozen=True)
class Notice:
    """One event: its kind (``peer_unreachable``, ``master_lost``, ...) and one line for people."""

    event: str
    message: str
    fields: dict[str, Any] = field(default_factory=dict)

    def as_json(self) -> dict[str, Any]:
        """The NDJSON event: ``{"event": ..., "message": ..., **fields}``."""
        return {"event": self.event, "message": self.message, **self.fields}


def to_stderr(notice: Notice) -> None:
    """The default ``notify``: one line on stderr."""
    sys.stderr.write(f"rostools: {one_line(notice.message)}\n")
    sys.stderr.flush()
