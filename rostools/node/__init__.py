"""A live ROS node on asyncio: what rospy is to ROS 1.

Publishers, subscribers, service servers and clients, the slave API, and the TCPROS and
XML-RPC servers and clients under them.
"""
