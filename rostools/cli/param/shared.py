"""What the parameter commands share, without Typer."""

from __future__ import annotations

from rostools.cli import output

TOOL = "rosparam"


def say(verbose: bool, text: str) -> None:
    """rosparam's -v: a line on stdout, as rosparam prints it."""
    if verbose:
        output.put(text + "\n")
