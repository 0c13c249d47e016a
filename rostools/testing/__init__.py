"""Testing a ROS 1 system with pytest: the ``rostools`` plugin's helpers.

``pip install rostools`` registers the plugin (``rostools.testing.plugin``) with pytest, so
its fixtures need no import: ``ros_master``, ``ros_node``, ``ros_record``, ``ros_process``.
The helpers here work under any master ``ROS_MASTER_URI`` names, which ``ros_master`` sets
for its test:

    from rostools.testing import assert_message, assert_topic_rate

They load on first use: the plugin is imported by every pytest run.
"""

from __future__ import annotations

#: The stable names.
__all__ = ["RosProcess", "assert_message", "assert_topic_rate", "graph_report", "start_process"]

_HOME = {
    "assert_message": "rostools.testing.helpers",
    "assert_topic_rate": "rostools.testing.helpers",
    "RosProcess": "rostools.testing.process",
    "start_process": "rostools.testing.process",
    "graph_report": "rostools.testing.report",
}

TYPE_CHECKING = False
if TYPE_CHECKING:
    from rostools.testing.helpers import assert_message, assert_topic_rate
    from rostools.testing.process import RosProcess, start_process
    from rostools.testing.report import graph_report


def __getattr__(name: str) -> object:
    """Load a helper on first use (PEP 562)."""
    home = _HOME.get(name)
    if home is None:
        raise AttributeError(f"module 'rostools.testing' has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(home), name)
    globals()[name] = value
    return value
