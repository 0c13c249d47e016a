"""``rostools tf echo``: one transform, as tf_echo prints it (live or from a bag)."""

from __future__ import annotations

import typer

from rostools.cli.declare import command
from rostools.cli.tf.options import BagOpt, FrameArg
from rostools.errors import RostoolsError


@command()
def echo(ctx: typer.Context, source: FrameArg, target: FrameArg, bag: BagOpt = None) -> None:
    """Print the transform from SOURCE to TARGET (tf_echo)."""
    raise RostoolsError("tf echo is being written")  # the skeleton the feed lands with
