"""``rostools bag``: rosbag for ``.bag`` and MCAP.

Its Typer app is ``group.app``; this ``__init__`` imports nothing.
"""
