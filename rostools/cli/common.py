"""What every command shares: global settings, common options and output helpers."""

from __future__ import annotations

import enum
import json
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any

import typer

if TYPE_CHECKING:
    from collections.abc import Callable

    from rostools.msgs.store import TypeStore

DEFAULT_MASTER_URI = "http://localhost:11311"


class Format(str, enum.Enum):
    """Output formats."""

    text = "text"
    json = "json"
    yaml = "yaml"


@dataclass
class Settings:
    """The global options, resolved. Stored on the root Typer context as ``ctx.obj``."""

    master_uri: str | None = None
    format: Format = Format.text
    debug: bool = False

    def resolved_master_uri(self) -> str:
        """``--master-uri``, then ``ROS_MASTER_URI``, then the ROS default."""
        return self.master_uri or os.environ.get("ROS_MASTER_URI") or DEFAULT_MASTER_URI


def settings(ctx: typer.Context) -> Settings:
    """The global settings of this invocation."""
    root = ctx.find_root()
    if not isinstance(root.obj, Settings):
        root.obj = Settings()
    return root.obj


def output_format(ctx: typer.Context, local: Format | None) -> Format:
    """A command's ``--format`` wins over the global one."""
    return local if local is not None else settings(ctx).format


def type_store(msg_paths: list[Path] | None = None) -> TypeStore:
    """The type store for this invocation, over ``--msg-path`` folders and the environment."""
    from rostools.msgs.store import TypeStore

    return TypeStore.default(msg_paths or [])


FormatOpt = Annotated[
    Format | None,
    typer.Option(
        "--format", "-F", help="Output format (overrides the global --format).", show_default=False
    ),
]
MsgPathOpt = Annotated[
    list[Path] | None,
    typer.Option(
        "--msg-path",
        help="A folder of ROS packages with msg/ and srv/ folders (repeatable; also "
        "ROSTOOLS_MSG_PATH).",
        show_default=False,
    ),
]


def emit(fmt: Format, data: Any, text: Callable[[Any], str] | None = None) -> None:
    """Print one result: as text with ``text(data)``, or as one JSON/YAML document."""
    if fmt is Format.json:
        out = json.dumps(data, indent=2, ensure_ascii=False)
    elif fmt is Format.yaml:
        import yaml

        out = yaml.safe_dump(data, sort_keys=False, allow_unicode=True).rstrip("\n")
    else:
        out = text(data) if text is not None else str(data)
    sys.stdout.write(out + "\n")
