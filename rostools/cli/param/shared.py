"""What the parameter commands share, without Typer."""

from __future__ import annotations

import sys

TOOL = "rosparam"


def say(verbose: bool, text: str) -> None:
    """rosparam's -v: a line on stdout, as rosparam prints it."""
    if verbose:
        sys.stdout.write(text + "\n")
