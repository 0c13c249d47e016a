"""``rostools bridge``: the live ROS 1 graph over WebSocket, in the Foxglove protocol."""
