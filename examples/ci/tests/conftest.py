"""Starting the robot's nodes under the test's master (the rostools plugin's ros_process)."""

import os
from pathlib import Path

import pytest

NODES = Path(__file__).resolve().parent.parent / "nodes"
#: rospy lives on the system interpreter of a ROS 1 install, not in this virtualenv.
ROS_PYTHON = os.environ.get("ROS_PYTHON", "/usr/bin/python3")


@pytest.fixture
def start_node(ros_process):
    """Start a node script (``start_node("heartbeat.py", "_rate:=20")``) and wait for it."""

    def start(script, *args):
        """The started process; its node has registered with the master."""
        name = "/" + script.removesuffix(".py")
        return ros_process([ROS_PYTHON, str(NODES / script), *args], wait_for_node=name)

    return start
