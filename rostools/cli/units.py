"""Durations and sizes as users type them: ``30s``, ``500ms``, ``5m``, ``1G``, ``64K``."""

from __future__ import annotations

import re

from rostools.errors import UsageError

_DURATION = re.compile(r"^\s*([0-9]*\.?[0-9]+)\s*(ms|s|min|m|h)?\s*$")
_SECONDS = {"ms": 1e-3, "s": 1.0, "min": 60.0, "m": 60.0, "h": 3600.0, None: 1.0}
_BYTES = {"g": 1024**3, "m": 1024**2, "k": 1024}


def parse_duration(text: str, option: str) -> float:
    """``30``, ``30s``, ``500ms``, ``5m`` or ``2h`` as seconds, more than zero.

    rosbag record's ``--duration`` takes s, m and h; plots add ms.
    """
    found = _DURATION.match(text)
    seconds = float(found.group(1)) * _SECONDS[found.group(2)] if found else 0.0
    if not found:
        raise UsageError(f"bad duration {text!r} for {option} (examples: 30, 30s, 500ms, 5m, 2h)")
    if seconds <= 0:
        raise UsageError(f"{option} must be a positive duration, not {text!r}")
    return seconds


def parse_size(text: str, option: str) -> int:
    """``1G``, ``500M``, ``64K`` or a plain number of bytes (rosbag record -L), not negative."""
    scale = _BYTES.get(text[-1:].lower())
    try:
        value = int(text[:-1] if scale else text) * (scale or 1)
    except ValueError:
        raise UsageError(f"bad size {text!r} for {option} (examples: 1G, 500M, 64K, 0)") from None
    if value < 0:
        raise UsageError(f"{option} cannot be negative, not {text!r}")
    return value
