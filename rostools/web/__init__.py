"""``rostools bridge``: the live ROS 1 graph over WebSocket, as Foxglove's and rosbridge's."""
