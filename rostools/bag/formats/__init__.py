"""The ``.bag`` and MCAP formats: records, readers, writers and what they share.

- ``access``: ``open_bag(path) -> BagReader`` (format from the file's content),
  ``open_writer(path, format=None, compression=None, chunk_size=None) -> BagWriter`` (format
  from the name), ``bag_info``, ``detect_format``, ``merged_messages``, ``topic_frequencies``.
- ``model``: ``Connection``, ``BagInfo`` and the bag errors; ``base``: the common reader and
  writer; ``sink``: writer output; ``ordering``: time-ordered merging of chunks.
- ``rosbag1_format``/``rosbag1_index``/``rosbag1_reader``/``rosbag1_writer`` and
  ``mcap_format``/``mcap_reader``/``mcap_writer`` per format; ``lz4cut`` (LZ4 frames cut
  short); ``fastcopy`` (chunk-for-chunk .bag -> MCAP); ``ros2`` (ROS 2 MCAP read as ROS 1);
  ``ros2types``/``ros2cdr``/``rosbag2_writer`` (ROS 1 written as rosbag2: types, CDR, folder);
  ``connections`` (a file's connections, for ``msg show --bag``).

Imports neither ``live`` nor ``tools``.
"""
