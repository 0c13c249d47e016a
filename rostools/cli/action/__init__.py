"""``rostools action``: actionlib from the terminal. The group is ``group.app``."""

# isort: off
# The order of these imports is the order of the commands in --help.
from rostools.cli.action import graph  # noqa: F401 - each module adds its commands to app
from rostools.cli.action import goal, control  # noqa: F401

# isort: on
from rostools.cli.action.group import app

__all__ = ["app"]
