"""``rostools action``: actionlib from the terminal: list, info, send-goal, cancel, status.

Its Typer app is ``group.app``. This ``__init__`` imports nothing, so that the launcher's
quick command (``query.py``) starts without Typer.
"""
