"""``rostools topic``: rostopic. The group is ``group.app``; each module adds its commands."""

# isort: off
# The order of these imports is the order of the commands in --help.
from rostools.cli.topic import query  # noqa: F401 - each module adds its commands to app
from rostools.cli.topic import echo, pub, rates  # noqa: F401
from rostools.cli.topic import plot  # noqa: F401

# isort: on
from rostools.cli.topic.group import app

__all__ = ["app"]
