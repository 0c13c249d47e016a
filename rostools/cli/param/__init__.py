"""``rostools param``: rosparam's list, get, set, delete, load and dump.

Its Typer app is ``group.app``. This ``__init__`` imports nothing, so that the launcher's
quick commands (``query.py``) start without Typer.
"""
