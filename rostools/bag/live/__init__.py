"""Bags and a running graph: record, snapshot and play.

- ``follow``: subscribing to what the graph publishes; ``bagfile``: the file being written;
  ``recorder``: ``bag record``; ``ringbuffer``: the snapshot buffer.
- ``snapshot`` (the snapshot recorder), ``snapshot_job``, ``snapshot_live``,
  ``snapshot_services``, ``snapshot_srv`` (the ``TriggerSnapshot`` service) and
  ``snapshot_client`` (the trigger).
- ``player``: ``bag play``; ``play_control``: its pacing and pause service.

Imports ``formats``, never ``tools``.
"""
