"""``rostools msg``: rosmsg, rossrv and rosmsg-proto in one group; actions too.

Its Typer app is ``group.app``. This ``__init__`` imports nothing, so that the launcher's
quick command (``query.py``) starts without Typer.
"""
