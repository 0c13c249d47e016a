"""``rostools bag``: rosbag for ``.bag`` and MCAP.

The group is ``group.app``; each module adds its commands: ``files`` (info, filter, convert,
recover/reindex, compress, decompress), ``workbench`` (merge, split), ``cat``, ``plot``,
``record``, ``play`` and ``extras`` (attachments, metadata).
"""

# isort: off
# The order of these imports is the order of the commands in --help.
from rostools.cli.bag import files  # noqa: F401 - each module adds its commands to app
from rostools.cli.bag import workbench  # noqa: F401
from rostools.cli.bag import cat  # noqa: F401
from rostools.cli.bag import plot  # noqa: F401
from rostools.cli.bag import play, record  # noqa: F401
from rostools.cli.bag import snapshot  # noqa: F401
from rostools.cli.bag import extras  # noqa: F401

# isort: on
from rostools.cli.bag.group import app

__all__ = ["app"]
