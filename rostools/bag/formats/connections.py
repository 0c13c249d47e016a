"""The connections (topic, type, md5sum, definition) recorded in a ``.bag`` or MCAP file.

Kept for ``msg show --bag``; the readers behind it are in ``rostools.bag.formats.access``.
"""

from __future__ import annotations

from pathlib import Path

from rostools.bag.formats.access import detect_format, open_bag
from rostools.bag.formats.model import BagFormatError, Connection

__all__ = ["BagFormatError", "Connection", "detect_format", "read_connections"]


def read_connections(path: Path) -> list[Connection]:
    """Every connection of a ``.bag`` or MCAP file, in id order."""
    with open_bag(path) as reader:
        return sorted(reader.connections, key=lambda c: c.id)
