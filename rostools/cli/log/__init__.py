"""``rostools log``: rosconsole.

Its Typer app is ``group.app``. This ``__init__`` imports nothing, so that the launcher's
quick commands (``loggers.py``) start without Typer.
"""
