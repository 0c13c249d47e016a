"""``topic echo --bag``: the same printing, from a ``.bag`` or MCAP file (no master needed)."""

from __future__ import annotations

import sys
from pathlib import Path
from typing import TYPE_CHECKING

from rostools.errors import NotFoundError

if TYPE_CHECKING:
    from rostools.cli.topic.printing import EchoOptions
    from rostools.msgs.store import TypeStore


def echo_bag(
    path: Path, name: str | None, store: TypeStore, opts: EchoOptions, check_crcs: bool = True
) -> None:
    """Print the messages of ``name`` (a topic, maybe with a field path), or of every topic.

    ``check_crcs`` False: ``--no-crc-check``.
    """
    from rostools.bag.formats.access import open_bag, require_ros1
    from rostools.bag.formats.base import after_reading
    from rostools.bag.formats.model import counted
    from rostools.cli.topic.printing import Echo
    from rostools.errors import InvalidDataError
    from rostools.msgs.topicpath import split_field

    with open_bag(path, check_crcs=check_crcs) as bag:
        resolved = {c.topic: _resolved(c.topic) for c in bag.connections}
        types = {resolved[c.topic]: c.type for c in bag.connections}
        topics = None
        if name is not None:
            ref = split_field(name, types, store)
            if ref is None:
                raise NotFoundError(f"topic {name} is not in {path}")
            opts.field = ref.field
            topics = [t for t, full in resolved.items() if full == ref.topic]
        require_ros1(bag, "topic echo -b", topics)
        echo = Echo(store, opts)
        for conn, t_ns, data in bag.messages(topics=topics):
            try:
                topic = resolved[conn.topic]
                printer = echo.printer(conn.type, conn.md5sum, conn.definition, topic)
                if not echo.emit(printer, [data], t_ns):
                    break  # -n reached; still say how the bag was read
            except InvalidDataError as err:  # a bad definition or message: say where
                raise InvalidDataError(f"{path}: message at {t_ns / 1e9:.9f} s: {err}") from err
    # An unindexed bag: one line saying so. A damaged one: every message that reads was
    # printed; say what was left out (exit 6).
    after_reading(
        [bag],
        f"printed {counted(echo.printed, 'message')}",
        lambda n: sys.stderr.write(f"note: {n}\n"),
    )


def _resolved(topic: str) -> str:
    """A bag's topic as rostopic echo -b names it: a relative one joins ROS_NAMESPACE.

    A name that is not legal (a hostile file's) is kept as it is.
    """
    from rostools.errors import UsageError
    from rostools.names import script_resolve

    if topic.startswith("/"):
        return topic
    try:
        return script_resolve(topic, "rostopic")
    except UsageError:
        return topic
