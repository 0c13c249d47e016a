"""ROS 1 ``.bag`` (v2.0) and MCAP (ROS 1 profile): readers, writers, and operations on them.

Entry points (import the module you need; nothing is imported here, to keep start-up fast):

- ``rostools.bag.access``: ``open_bag(path) -> BagReader`` (format from the file's content),
  ``open_writer(path, format=None, compression=None, chunk_size=None) -> BagWriter`` (format
  from the name), ``bag_info``, ``detect_format``, ``merged_messages``, ``topic_frequencies``.
- ``rostools.bag.ops``: ``convert``, ``filter`` (``filter_bag``), ``compress``, ``decompress``.
- ``rostools.bag.recover``: ``recover`` (alias ``reindex``) returning a ``RecoverReport``.
- ``rostools.bag.model``: ``Connection``, ``BagInfo`` and the bag errors.

Modules: ``rosbag1_format``/``rosbag1_reader``/``rosbag1_writer`` and
``mcap_format``/``mcap_reader``/``mcap_writer`` per format; ``ordering`` (time-ordered
merging of chunks), ``sink`` (writer output), ``fastcopy`` (chunk-for-chunk .bag -> MCAP).
"""
