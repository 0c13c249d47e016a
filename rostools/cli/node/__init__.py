"""``rostools node``: rosnode's list, info, ping, kill, machine and cleanup, and graph.

Its Typer app is ``group.app``. This ``__init__`` imports nothing, so that the launcher's
quick commands (``query.py``) start without Typer.
"""
