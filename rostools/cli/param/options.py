"""The arguments and options the parameter commands share.

Typer's: the commands import them for their annotations only.
"""

from __future__ import annotations

from typing import Annotated

import typer

VerboseOpt = Annotated[
    bool, typer.Option("-v", "--verbose", help="Say what is done, as rosparam -v (stdout).")
]
NameArg = Annotated[str, typer.Argument(help="Parameter name; relative names join ROS_NAMESPACE.")]
