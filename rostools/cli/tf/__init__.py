"""``rostools tf``: tf2_echo, view_frames, tf2_monitor and static_transform_publisher.

Its Typer app is ``group.app``. This ``__init__`` imports nothing, so that nothing loads
Typer before a command of the group runs.
"""
