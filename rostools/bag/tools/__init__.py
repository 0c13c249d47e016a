"""Offline operations on bag files.

- ``ops``: ``convert``, ``filter`` (``filter_bag``), ``compress``, ``decompress``.
- ``merge``, ``split``, ``rename`` (``--rename``, ``--rename-type``), ``recover`` (alias
  ``reindex``, returning a ``RecoverReport``), ``findings`` (what ``doctor`` reports of a bag).

Imports ``formats``, never ``live``.
"""
