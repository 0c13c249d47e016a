"""``topic list --bag``: the topics a bag holds, in order of first appearance."""

from __future__ import annotations

from pathlib import Path

from rostools.cli.output import Format, emit


def list_bag_topics(bag: Path, namespace: str | None, fmt: Format) -> None:
    """Print the topics of a bag (its connections, first appearance first)."""
    from rostools.bag.connections import read_connections

    topics: dict[str, str] = {}
    for conn in read_connections(bag):
        topics.setdefault(conn.topic, conn.type)
    if namespace:
        prefix = namespace.rstrip("/") + "/"
        topics = {t: ty for t, ty in topics.items() if t == namespace or t.startswith(prefix)}
    rows = [{"topic": t, "type": ty} for t, ty in topics.items()]
    emit(fmt, rows, lambda r: "\n".join(x["topic"] for x in r))
