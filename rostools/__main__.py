"""``python -m rostools``."""

from __future__ import annotations

from rostools.cli import main

if __name__ == "__main__":
    main()
