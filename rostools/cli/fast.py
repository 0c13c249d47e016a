"""The hottest commands, answered without importing typer (about 40 ms of start-up).

Only argument lists with no options take this path (``msg md5 T``, ``topic list [ns]``);
anything else goes through the Typer app, which runs the same functions. Tests run both paths
and compare.
"""

from __future__ import annotations

import sys
from collections.abc import Sequence


def dispatch(argv: Sequence[str]) -> int | None:
    """Run ``argv`` if it is a fast command and return its exit status, else None."""
    if argv and argv[0] == "__complete":  # the shells' completion scripts call this
        from rostools.cli.completer import main

        return main(argv[1:])
    if len(argv) == 3 and argv[0] == "msg" and argv[1] == "md5" and not argv[2].startswith("-"):
        from rostools.cli.lookup import md5_text, md5sums, read_type
        from rostools.msgs.store import TypeStore

        name = read_type(argv[2])
        sys.stdout.write(md5_text(name, md5sums(TypeStore.default(), name)))
        return 0
    if (
        argv[:2] == ["topic", "list"]
        and len(argv) <= 3
        and not any(a.startswith("-") for a in argv)
    ):
        return _topic_list(argv[2] if len(argv) == 3 else None)
    return None


def _topic_list(namespace: str | None) -> int:
    import os

    from rostools.cli.common import DEFAULT_MASTER_URI
    from rostools.cli.topiclist import list_text
    from rostools.names import ros_namespace, script_resolve
    from rostools.rosgraph.masterapi import MasterProxy
    from rostools.rosgraph.topics import topic_table

    uri = os.environ.get("ROS_MASTER_URI") or DEFAULT_MASTER_URI
    proxy = MasterProxy(uri, f"{ros_namespace()}rostopic_{os.getpid()}")
    ns = script_resolve(namespace, "rostopic") if namespace else None
    sys.stdout.write(list_text(topic_table(proxy, ns), False, False, False) + "\n")
    return 0
