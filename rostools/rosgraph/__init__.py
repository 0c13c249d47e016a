"""A one-shot, blocking view of the ROS graph: what rosgraph is to ROS 1.

The master and parameter client, the node API client, graph snapshots, a blocking service
client, and the rules for the addresses a host gives out and how it reaches others.
"""
