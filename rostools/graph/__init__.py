"""The live ROS graph on asyncio: master proxy, Node, Publisher, Subscriber, services."""
