"""ROS 1 ``.bag`` (v2.0) and MCAP (ROS 1 profile): readers, writers, and operations on them.

Three rooms, by role (nothing is imported here, to keep start-up fast):

- ``rostools.bag.formats``: the records, readers and writers of both formats, and what they
  share (``access.open_bag``, ``access.open_writer``, ``model``, ``base``, ``sink``,
  ``ordering``).
- ``rostools.bag.live``: bags written from and played to a running graph (record, snapshot,
  play).
- ``rostools.bag.tools``: the offline operations on bag files (filter, convert, merge, split,
  rename, recover, doctor's findings).

``live`` and ``tools`` import ``formats``; neither imports the other, and ``formats`` imports
neither (``tests/unit/test_import_direction.py``).
"""
