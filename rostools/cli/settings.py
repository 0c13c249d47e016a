"""The global options of one invocation, without Typer: all a quick command needs."""

from __future__ import annotations

import os

from rostools.cli.output import Format

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from pathlib import Path

    from rostools.msgs.store import TypeStore
    from rostools.rosgraph.masterapi import MasterProxy

DEFAULT_MASTER_URI = "http://localhost:11311"


class Settings:
    """The global options, resolved. Stored on the root Typer context as ``ctx.obj``.

    A plain class: ``dataclasses`` costs 15 ms of start-up (it imports ``inspect``).
    """

    def __init__(
        self,
        master_uri: str | None = None,
        format: Format = Format.text,
        debug: bool = False,
        remappings: dict[str, str] | None = None,
    ) -> None:
        self.master_uri = master_uri
        self.format = format
        self.debug = debug
        #: ``name:=value`` arguments taken off the command line (remaps, ``__name``, ...).
        self.remappings = remappings if remappings is not None else {}

    def resolved_master_uri(self) -> str:
        """``--master-uri``, then ``ROS_MASTER_URI``, then the ROS default."""
        return self.master_uri or os.environ.get("ROS_MASTER_URI") or DEFAULT_MASTER_URI

    def output_format(self, local: Format | str | None) -> Format:
        """A command's ``--format`` wins over the global one."""
        return self.format if local is None else Format(local)

    def master(self, tool: str) -> MasterProxy:
        """A master client for this invocation, named like rospy tools name themselves."""
        from rostools.rosgraph.masterapi import MasterProxy

        return MasterProxy(self.resolved_master_uri(), caller_id(tool))


def caller_id(tool: str) -> str:
    """The caller id a rospy tool gives itself: ``/rosparam_1234``, in ROS_NAMESPACE."""
    from rostools.names import ros_namespace

    return f"{ros_namespace()}{tool}_{os.getpid()}"


def type_store(msg_paths: list[Path] | None = None) -> TypeStore:
    """The type store for this invocation, over ``--msg-path`` folders and the environment."""
    from rostools.msgs.store import TypeStore

    return TypeStore.default(msg_paths or [])
