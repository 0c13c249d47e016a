"""rostools: the ROS 1 command-line tools in one pip-installable Python CLI, no ROS needed."""

from __future__ import annotations

__version__ = "0.1.0"
