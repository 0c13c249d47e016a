"""``topic list --bag``: the topics a bag holds, in order of first appearance.

With a topic or namespace, as ``rostopic list -b BAG /t``: how many messages it has, and
from when to when.
"""

from __future__ import annotations

import time
from pathlib import Path

from rostools.cli.output import Format, emit, lines
from rostools.errors import NotFoundError


def list_bag_topics(bag: Path, namespace: str | None, fmt: Format) -> None:
    """Print the topics of a bag (its connections, first appearance first)."""
    from rostools.bag.formats.connections import read_connections

    topics: dict[str, str] = {}
    for conn in read_connections(bag):
        topics.setdefault(conn.topic, conn.type)
    if namespace:
        prefix = namespace.rstrip("/") + "/"
        chosen = [t for t in topics if t == namespace or t.startswith(prefix)]
        _count(bag, namespace, chosen, fmt)
        return
    rows = [{"topic": t, "type": ty} for t, ty in topics.items()]
    emit(fmt, rows, lambda r: lines(x["topic"] for x in r))


def _count(bag: Path, namespace: str, topics: list[str], fmt: Format) -> None:
    """rostopic's "N message(s) from DATE to DATE" for the topics under ``namespace``."""
    from rostools.bag.formats.access import open_bag

    count, first, last = 0, 0, 0
    if topics:
        with open_bag(bag) as reader:
            for _, t_ns, _ in reader.times(topics):
                first = t_ns if count == 0 else first
                last, count = t_ns, count + 1
    if not count:
        raise NotFoundError(f"no message on {namespace} in {bag}")

    def local(t_ns: int) -> str:
        return time.strftime("%d %b %Y %H:%M:%S", time.localtime(t_ns / 1e9))

    data = {"topic": namespace, "messages": count, "start_ns": first, "end_ns": last}
    emit(fmt, data, lambda d: f"{count} message(s) from {local(first)} to {local(last)}")
