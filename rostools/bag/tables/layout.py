"""Where ``bag export`` puts each table: the dataset's directories, and their names.

``OUT/topic=<topic key>/bag=<bag key>/part-0.<format>``, partitioned hive-style, so DuckDB,
Polars, pyarrow.dataset and Spark read ``topic`` and ``bag`` as columns.

A key is a name every engine keeps as it is (no ``%``, which pyarrow decodes, and no ``/``):

- a topic drops its leading ``/`` and writes each further ``/`` as ``.``: ``/imu/data`` is
  ``imu.data``. A ROS name has no ``.``, so this is reversed by ``topic_of_key``;
- every character but ASCII letters, digits, ``_`` and ``-`` (and ``.`` for ``/``) is ``~`` and the
  two lower-case hex digits of each of its UTF-8 bytes: ``/a.b`` is ``a~2eb``, a space ``~20``;
- a topic without a leading ``/`` (never in a ROS 1 bag) starts with ``~-``;
- a bag's key is its file name without the suffix, escaped the same way (``/`` never occurs);
- a topic whose definition changes between the bags (more than one md5sum) has one table per
  definition, its key followed by ``@`` and the md5sum's first 8 hex digits: ``imu.data@6a62c6da``.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Final

#: Characters a key keeps as they are; ``.`` stands for ``/`` in a topic.
_PLAIN: Final = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_-")
_ESCAPED: Final = re.compile(r"~([0-9a-f]{2})")
#: Hex digits of the md5sum a split topic's key carries.
MD5_DIGITS: Final = 8
#: The one file of a table in one bag: more parts are for a later, bigger writer.
PART: Final = "part-0"


def _escape(text: str, slash: str | None) -> str:
    out = []
    for char in text:
        if char in _PLAIN:
            out.append(char)
        elif char == "/" and slash is not None:
            out.append(slash)
        else:
            out.append("".join(f"~{b:02x}" for b in char.encode("utf-8", "surrogatepass")))
    return "".join(out)


def _unescape(key: str) -> str:
    raw = bytearray()
    at = 0
    for found in _ESCAPED.finditer(key):
        raw += key[at : found.start()].replace(".", "/").encode()
        raw.append(int(found.group(1), 16))
        at = found.end()
    raw += key[at:].replace(".", "/").encode()
    return raw.decode("utf-8", "surrogatepass")


def topic_key(topic: str) -> str:
    """The directory value of ``topic``: ``/imu/data`` is ``imu.data`` (see the module)."""
    if topic.startswith("/"):
        return _escape(topic[1:], ".")
    return "~-" + _escape(topic, ".")


def topic_of_key(key: str) -> str:
    """The topic ``topic_key`` made ``key`` of (a split table's ``@md5`` left out)."""
    key = key.partition("@")[0]
    if key.startswith("~-"):
        return _unescape(key[2:])
    return "/" + _unescape(key)


def table_key(topic: str, md5sum: str | None) -> str:
    """The key of one table: the topic's, with ``@`` and 8 md5 digits for a split topic."""
    key = topic_key(topic)
    return f"{key}@{md5sum[:MD5_DIGITS]}" if md5sum else key


def bag_key(path: str | Path) -> str:
    """The directory value of a bag: its name without the suffix, escaped as a topic is."""
    return _escape(Path(path).stem, None)


def part_path(out: Path, table: str, bag: str, extension: str) -> Path:
    """The file of one table from one bag."""
    return out / f"topic={table}" / f"bag={bag}" / f"{PART}.{extension}"
