"""``rostools node``: rosnode's list, info, ping, kill, machine and cleanup, and ``graph``.

Text output follows rosnode line for line where rosnode has a command; ``--format json``
gives one document (``ping``: one object per reply). Unlike rosnode, an unknown node is an
error (exit 3), a node that cannot be reached exits 4 and one that does not answer within
``--timeout`` exits 5. The group is ``group.app``; each module adds its commands.
"""

# isort: off
# The order of these imports is the order of the commands in --help.
from rostools.cli.node import query  # noqa: F401 - each module adds its commands to app
from rostools.cli.node import ping, kill, graph  # noqa: F401

# isort: on
from rostools.cli.node.group import app

__all__ = ["app"]
