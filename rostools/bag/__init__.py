"""ROS 1 `.bag` and MCAP: readers, writers, and the operations built on them."""
