"""Testing a ROS 1 system with pytest: the ``rostools`` plugin's helpers.

``pip install rostools`` registers the plugin (``rostools.testing.plugin``) with pytest, so
its fixtures need no import: ``ros_master``, ``ros_node``, ``ros_record``, ``ros_process``.
The helpers here work under any master ``ROS_MASTER_URI`` names, which ``ros_master`` sets
for its test:

    from rostools.testing import assert_message, assert_topic_rate

They load on first use (``rostools.lazy``): the plugin is imported by every pytest run.
"""

from __future__ import annotations

TYPE_CHECKING = False
if TYPE_CHECKING:  # the stable names: type checkers read these imports, rostools.lazy too
    from rostools.testing.bagsql import assert_sql as assert_sql
    from rostools.testing.helpers import (
        assert_message as assert_message,
        assert_topic_rate as assert_topic_rate,
    )
    from rostools.testing.process import RosProcess as RosProcess, start_process as start_process
    from rostools.testing.report import graph_report as graph_report


def __getattr__(name: str) -> object:
    """Load a helper on first use (PEP 562); ``__all__`` is their list."""
    from rostools.lazy import load

    return load(__name__, name)
