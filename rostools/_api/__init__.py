"""The machinery behind ``from rostools import ...``: private, import the names from ``rostools``.

The public API (``rostools.__all__``) is stable within a minor version; what this package
holds may change in any release.
"""

from __future__ import annotations

__all__: list[str] = []
