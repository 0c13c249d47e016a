"""Transforms as tf2 keeps them, without tf2: the math, the messages, the buffer.

Pure arithmetic over numbers and bytes (numpy and ``struct``), so the live commands, the bag
readers and the API feed it alike. ``rostools tf`` (``cli/tf/``) is its front end.
"""
