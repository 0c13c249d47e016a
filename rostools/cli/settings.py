"""The global options of one invocation, without Typer: all a quick command needs."""

from __future__ import annotations

import os

from rostools.cli.output import Format

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    import asyncio
    from pathlib import Path

    from rostools.msgs.store import TypeStore
    from rostools.msgs.topictype import TopicType
    from rostools.node.node import LiveNode
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
        """``--master-uri``, then ``ROS_MASTER_URI``, then the ROS default.

        One that is not ``http://host[:port][/]`` is a usage error that says what is wrong:
        ``127.0.0.1:11311`` was read as port 80 of localhost, and ``htp://`` as ``http://``.
        """
        if self.master_uri:
            return checked_master_uri(self.master_uri, "--master-uri")
        if uri := os.environ.get("ROS_MASTER_URI"):
            return checked_master_uri(uri, "ROS_MASTER_URI")
        return DEFAULT_MASTER_URI

    def output_format(self, local: Format | str | None) -> Format:
        """A command's ``--format`` wins over the global one."""
        return self.format if local is None else Format(local)

    def master(self, tool: str) -> MasterProxy:
        """A master client for this invocation, named like rospy tools name themselves."""
        from rostools.rosgraph.masterapi import MasterProxy

        return MasterProxy(self.resolved_master_uri(), caller_id(tool))


def checked_master_uri(uri: str, source: str) -> str:
    """``uri`` if it is an ``http://`` URI with a host (and a numeric port), else a UsageError."""
    from rostools.errors import UsageError

    scheme, sep, rest = uri.partition("://")
    if not sep:
        raise UsageError(f"{source}={uri} has no scheme", hint=f"write it as http://{uri}")
    if scheme.lower() != "http":
        raise UsageError(
            f"{source}={uri} has the scheme {scheme!r}; a ROS master speaks http",
            hint=f"write it as http://{rest}",
        )
    netloc = rest.partition("/")[0]
    if netloc.startswith("["):  # [IPv6]:port
        host, _, tail = netloc[1:].partition("]")
        port: str | None = tail[1:] if tail.startswith(":") else None
    else:
        host, colon, port = netloc.partition(":")
        port = port if colon else None
    if not host:
        problem = "has no host"
    elif port is not None and not port.isdigit():
        problem = f"has a port that is not a number ({port!r})"
    else:
        return uri
    raise UsageError(f"{source}={uri} {problem}", hint="write it as http://HOST:PORT")


def caller_id(tool: str) -> str:
    """The caller id a rospy tool gives itself: ``/rosparam_1234``, in ROS_NAMESPACE."""
    from rostools.names import ros_namespace

    return f"{ros_namespace()}{tool}_{os.getpid()}"


def type_store(msg_paths: list[Path] | None = None) -> TypeStore:
    """The type store for this invocation, over ``--msg-path`` folders and the environment."""
    from rostools.msgs.store import TypeStore

    return TypeStore.default(msg_paths or [])


def learn_type(s: Settings, topic: str, store: TypeStore) -> TypeStore:
    """``store`` plus the definition a publisher of ``topic`` sends, asked as a short node.

    The publisher's header is waited for as long as a service server's (``PROBE_TIMEOUT``).
    """
    from rostools.node.learntype import learn_topic_type
    from rostools.node.notice import to_stderr
    from rostools.node.session import run_node
    from rostools.rosgraph.masterapi import PROBE_TIMEOUT

    async def main(node: LiveNode, stop: asyncio.Event) -> TopicType:
        return await learn_topic_type(node, topic, PROBE_TIMEOUT)

    learnt = run_node(
        main, s.resolved_master_uri(), "rostools_probe", remappings=s.remappings, notify=to_stderr
    )
    return store.with_definition(learnt.type, learnt.definition)
