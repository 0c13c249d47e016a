"""ROS graph resource names: canonical form, resolution, remapping, anonymous names.

Pure functions over strings (wiki.ros.org/Names): the standard library and our errors only.
"""

from __future__ import annotations

import os
import re
import time

from rostools.errors import UsageError

SEP = "/"
GLOBAL_NS = "/"
PRIVATE = "~"
ANYTYPE = "*"

_LEGAL_NAME = re.compile(r"^[~/A-Za-z][\w/]*$")
_LEGAL_BASE = re.compile(r"^[A-Za-z][\w]*$")


def canonicalize(name: str) -> str:
    """Drop duplicate and trailing slashes: ``//a//b/`` -> ``/a/b``; ``/`` stays ``/``."""
    if not name or name == SEP:
        return name
    if "//" not in name and name[-1] != SEP:
        return name  # already canonical: the master resolves a name or two per call
    if name[0] == SEP:
        return SEP + SEP.join(p for p in name.split(SEP) if p)
    return SEP.join(p for p in name.split(SEP) if p)


def is_global(name: str) -> bool:
    """``/a/b``."""
    return name.startswith(SEP)


def is_private(name: str) -> bool:
    """``~a``."""
    return name.startswith(PRIVATE)


def is_legal(name: str) -> bool:
    """A legal graph resource name (empty is legal: it means the namespace itself)."""
    if name == "":
        return True
    return bool(_LEGAL_NAME.match(name)) and "//" not in name


def is_legal_base(name: str) -> bool:
    """A legal base name, such as a node name without namespace."""
    return bool(_LEGAL_BASE.match(name))


def namespace(name: str) -> str:
    """The namespace of a name, with a trailing slash: ``/wg/node1`` -> ``/wg/``."""
    name = canonicalize(name)
    if name in ("", SEP):
        return SEP
    head = name.rsplit(SEP, 1)[0]
    return head + SEP if head else SEP


def make_global_ns(ns: str) -> str:
    """A namespace as a global name with a trailing slash."""
    if is_private(ns):
        raise ValueError(f"cannot turn the private name {ns} into a global namespace")
    if not is_global(ns):
        ns = SEP + ns
    return ns if ns.endswith(SEP) else ns + SEP


def join(ns: str, name: str) -> str:
    """``join('/a', 'b')`` -> ``/a/b``; a global or private name is returned as it is."""
    if is_global(name) or is_private(name):
        return name
    if ns == PRIVATE:
        return PRIVATE + name
    if not ns:
        return name
    return ns + name if ns.endswith(SEP) else ns + SEP + name


def resolve(name: str, caller_id: str, remappings: dict[str, str] | None = None) -> str:
    """Resolve ``name`` for the node ``caller_id`` (a global node name), as rosgraph does.

    Global names stay; relative names join the caller's namespace; ``~private`` names join
    the caller itself. Remappings apply to the resolved name.
    """
    if not name:
        return namespace(caller_id)
    if is_global(name):
        resolved = canonicalize(name)
    elif is_private(name):
        resolved = canonicalize(caller_id + SEP + name[1:])
    else:
        resolved = canonicalize(namespace(caller_id) + name)
    if remappings and resolved in remappings:
        return remappings[resolved]
    return resolved


#: ``__ns:=`` from this process's command line (``use_command_namespace``).
_command_ns: str | None = None


def use_command_namespace(remappings: dict[str, str]) -> None:
    """Take ``__ns:=`` from a command line's remappings as this process's namespace.

    rosgraph reads ``__ns:=`` in ``sys.argv`` before ``ROS_NAMESPACE``, so that a tool's
    relative names (``rostopic pub chatter ... __ns:=/robot``) join it.
    """
    global _command_ns
    ns = remappings.get("__ns")
    _command_ns = make_global_ns(ns) if ns else None


def ros_namespace(env: dict[str, str] | None = None) -> str:
    """The default namespace: ``__ns:=``, else ``ROS_NAMESPACE``; global, with a trailing slash."""
    if _command_ns is not None:
        return _command_ns
    value = (env if env is not None else os.environ).get("ROS_NAMESPACE", "")
    return make_global_ns(value) if value else GLOBAL_NS


def script_resolve(
    name: str, tool: str = "rostools", env: dict[str, str] | None = None, field_path: bool = False
) -> str:
    """How a command-line tool resolves a name the user typed, as rosgraph does.

    Relative names join ``ROS_NAMESPACE``; ``~private`` names join the tool's own name there.
    A name that is not a legal graph name (``-x``, ``a b``, ``a//b``) is a ``UsageError``;
    with ``field_path``, what follows a ``[`` (``/scan/ranges[0]``) is not checked.
    """
    checked = name.split("[", 1)[0] if field_path else name
    if checked.startswith("-"):  # an option the command does not have, taken for a name
        raise UsageError(f"no such option: {name} (and {name!r} is not a legal ROS name)")
    if not is_legal(checked):
        raise UsageError(
            f"{name!r} is not a legal ROS name",
            hint="names are letters, digits, _ and /, and start with a letter, / or ~",
        )
    ns = ros_namespace(env)
    if not name:
        return ns
    if is_global(name):
        return canonicalize(name)
    if is_private(name):
        return canonicalize(ns + tool + SEP + name[1:])
    return canonicalize(ns + name)


def anonymous(base: str) -> str:
    """Rospy's anonymous node name: ``<base>_<pid>_<epoch ms>``."""
    return f"{base}_{os.getpid()}_{int(time.time() * 1000)}"


#: Options whose value is itself ``old:=new`` (``bag convert --rename /a:=/b``): the argument
#: after one of these is the option's, never a remapping of the command's own node.
REMAP_VALUED = frozenset(("--rename", "--rename-type"))


def split_remappings(argv: list[str]) -> tuple[list[str], dict[str, str]]:
    """Separate ``name:=value`` arguments (remappings, ``__ns:=``, ``_param:=``) from the rest.

    Returns the remaining arguments and the raw ``{name: value}`` mapping, as rospy's
    ``myargv`` does for tools. The value of a ``REMAP_VALUED`` option stays in the arguments.
    """
    rest: list[str] = []
    mapping: dict[str, str] = {}
    for i, arg in enumerate(argv):
        if i and argv[i - 1] in REMAP_VALUED:
            rest.append(arg)
            continue
        name, sep, value = arg.partition(":=")
        if sep and name and (name[0] in "/~_" or name[0].isalpha()):
            mapping[name] = value
        else:
            rest.append(arg)
    return rest, mapping
