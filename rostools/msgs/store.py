"""Where types come from, and the md5sum and full definition text of each.

A ``TypeStore`` looks a type up in layered sources, first hit wins:

1. definitions learnt from a connection header or a bag (``with_definition``);
2. ``.msg``/``.srv``/``.action`` files in package folders: ``--msg-path`` folders,
   ``ROSTOOLS_MSG_PATH``, then ``ROS_PACKAGE_PATH`` (unset: ``/usr/share`` when it holds ROS
   packages, as Debian's rospkg does); an ``.action`` file gives the seven messages genmsg
   generates from it (``msgs/action.py``);
3. the built-in table: rosbags' Noetic store plus the common Noetic services.
"""

from __future__ import annotations

import hashlib
import json
import os
import re
from collections.abc import Iterable, Sequence
from functools import cache
from pathlib import Path
from typing import Any, Literal

from rostools.errors import NotFoundError
from rostools.msgs.action import (
    AUTOGEN,
    SUFFIXES,
    ActionSpec,
    action_name,
    generated_texts,
    split_generated,
)
from rostools.msgs.spec import (
    SECTION_RULE,
    DefinitionError,
    MsgSpec,
    SrvSpec,
    is_valid_type,
    normalize_type_name,
    parse_msg,
    parse_srv,
    split_definition,
)

#: How deeply message types may nest (see ``TypeStore.check``): the deepest of Noetic's
#: packages nest 7 levels (nav_msgs/GetMapAction); each level costs a few recursive calls.
MAX_NESTING = 64

Kind = Literal["msg", "srv", "action"]
MSG_PATH_ENV = "ROSTOOLS_MSG_PATH"
# Debian installs ROS packages here and its rospkg searches it when ROS_PACKAGE_PATH is unset.
DEBIAN_SHARE = "/usr/share"
# How deep to look for packages below a search-path folder (a catkin src/ with repositories).
_CRAWL_DEPTH = 4
_PKG_NAME_RE = re.compile(rb"<name>\s*([^<\s]+)\s*</name>")


class Source:
    """Something that holds the text of message and service types."""

    def text(self, kind: Kind, name: str) -> str | None:
        """The ``.msg``/``.srv``/``.action`` text of ``pkg/Type``, or None."""
        raise NotImplementedError

    def packages(self, kind: Kind) -> Iterable[str]:
        """Packages that hold types of this kind."""
        raise NotImplementedError

    def types(self, kind: Kind, package: str) -> list[str]:
        """Short names of the types of this kind in a package, sorted."""
        raise NotImplementedError


class DefinitionSource(Source):
    """Types from a full ``message_definition`` (connection header, bag, MCAP schema)."""

    def __init__(self, name: str, full_text: str) -> None:
        self.sections = split_definition(full_text, name)

    def text(self, kind: Kind, name: str) -> str | None:
        """The section of the definition for ``name``."""
        return self.sections.get(name) if kind == "msg" else None

    def packages(self, kind: Kind) -> Iterable[str]:
        """Packages named in the definition."""
        return sorted({n.partition("/")[0] for n in self.sections}) if kind == "msg" else []

    def types(self, kind: Kind, package: str) -> list[str]:
        """Types of ``package`` named in the definition."""
        if kind != "msg":
            return []
        return sorted(n.partition("/")[2] for n in self.sections if n.startswith(package + "/"))


class PathSource(Source):
    """``.msg``/``.srv`` files in package folders below search-path roots."""

    def __init__(self, roots: Sequence[Path], *, shallow: Sequence[Path] = ()) -> None:
        self.roots = list(roots)
        self.shallow = list(shallow)  # roots searched one level deep only (big system folders)
        self._index: dict[str, list[Path]] | None = None

    def _package_name(self, folder: Path) -> str:
        try:
            match = _PKG_NAME_RE.search((folder / "package.xml").read_bytes())
        except OSError:
            match = None
        return match.group(1).decode() if match else folder.name

    @staticmethod
    def _is_package(folder: Path) -> bool:
        return (
            (folder / "package.xml").is_file()
            or (folder / "msg").is_dir()
            or (folder / "srv").is_dir()
            or (folder / "action").is_dir()
        )

    def _crawl(self) -> dict[str, list[Path]]:
        if self._index is not None:
            return self._index
        index: dict[str, list[Path]] = {}

        def visit(folder: Path, depth: int) -> None:
            if self._is_package(folder):
                index.setdefault(self._package_name(folder), []).append(folder)
                return
            if depth == 0 or (folder / "CATKIN_IGNORE").exists():
                return
            try:
                children = sorted(p for p in folder.iterdir() if not p.name.startswith("."))
            except OSError:
                return
            for child in children:
                if child.is_dir():
                    visit(child, depth - 1)

        for root in self.roots:
            visit(root, _CRAWL_DEPTH)
        for root in self.shallow:
            visit(root, 1)
        self._index = index
        return index

    def _folders(self, package: str) -> list[Path]:
        # Fast path: <root>/<package> is where nearly every layout puts it.
        for root in [*self.roots, *self.shallow]:
            for folder in (root / package, root):
                if folder.name == package and self._is_package(folder):
                    return [folder]
        return self._crawl().get(package, [])

    def text(self, kind: Kind, name: str) -> str | None:
        """Read ``<package>/<kind>/<Type>.<kind>``; a message generated from an ``.action``."""
        found = self._file_text(kind, name)
        if found is None and kind == "msg" and (parts := split_generated(name)) is not None:
            stem, suffix = parts
            action = self._file_text("action", stem)
            if action is not None:
                short = name.partition("/")[2]
                return generated_texts(short.removesuffix(suffix), action)[short]
        return found

    def _file_text(self, kind: Kind, name: str) -> str | None:
        package, _, short = name.partition("/")
        if not package or not short or "/" in short:
            return None
        for folder in self._folders(package):
            path = folder / kind / f"{short}.{kind}"
            try:
                return path.read_bytes().decode("utf-8")
            except FileNotFoundError:
                continue
            except (OSError, UnicodeDecodeError) as err:
                raise DefinitionError(f"cannot read {path}: {err}") from err
        return None

    def packages(self, kind: Kind) -> Iterable[str]:
        """Packages with a ``msg/`` (or ``srv/``, ``action/``) folder; actions give messages."""
        kinds = ("msg", "action") if kind == "msg" else (kind,)
        return [
            p
            for p, dirs in self._crawl().items()
            if any((d / k).is_dir() for d in dirs for k in kinds)
        ]

    def types(self, kind: Kind, package: str) -> list[str]:
        """Type files in the package's ``msg/`` (or ``srv/``, ``action/``) folder.

        The messages of a package include those generated from its actions.
        """
        found: set[str] = set()
        for folder in self._crawl().get(package, []):
            sub = folder / kind
            if sub.is_dir():
                found.update(
                    p.stem for p in sub.iterdir() if p.suffix == f".{kind}" and p.is_file()
                )
        if kind == "msg":
            for stem in self.types("action", package):
                found.update(stem + suffix for suffix in SUFFIXES)
        return sorted(found)


@cache
def _builtin_table() -> dict[str, dict[str, str]]:
    # Package data beside this module (importlib.resources costs 10 ms of start-up).
    with open(os.path.join(os.path.dirname(__file__), "data", "noetic.json"), "rb") as f:
        table: dict[str, dict[str, str]] = json.load(f)
    return table


class BuiltinSource(Source):
    """The types rostools carries: rosbags' Noetic store and the common Noetic services."""

    def text(self, kind: Kind, name: str) -> str | None:
        """The stored text of a type (actions are there as their seven messages)."""
        return _builtin_table().get(kind, {}).get(name)

    def packages(self, kind: Kind) -> Iterable[str]:
        """Packages in the table."""
        return sorted({n.partition("/")[0] for n in _builtin_table().get(kind, {})})

    def types(self, kind: Kind, package: str) -> list[str]:
        """Types of a package in the table."""
        prefix = package + "/"
        table = _builtin_table().get(kind, {})
        return sorted(n[len(prefix) :] for n in table if n.startswith(prefix))


def _split_path(value: str | None) -> list[Path]:
    return [Path(p) for p in (value or "").split(os.pathsep) if p]


def default_sources(msg_paths: Sequence[str | Path] = ()) -> list[Source]:
    """The search path from the command line and the environment, then the built-in table."""
    roots = [Path(p) for p in msg_paths] + _split_path(os.environ.get(MSG_PATH_ENV))
    shallow: list[Path] = []
    if "ROS_PACKAGE_PATH" in os.environ:
        roots += _split_path(os.environ["ROS_PACKAGE_PATH"])
    elif Path(DEBIAN_SHARE, "std_msgs", "package.xml").is_file():
        shallow.append(Path(DEBIAN_SHARE))
    sources: list[Source] = []
    if roots or shallow:
        sources.append(PathSource(roots, shallow=shallow))
    sources.append(BuiltinSource())
    return sources


class TypeStore:
    """Message and service types by name, with their md5sums and full definitions."""

    def __init__(self, sources: Sequence[Source]) -> None:
        self.sources = list(sources)
        self._msgs: dict[str, MsgSpec] = {}
        self._srvs: dict[str, SrvSpec] = {}
        self._md5: dict[str, str] = {}
        #: Things derived from these types by other modules (the codec, formatters).
        self.cache: dict[object, Any] = {}

    @classmethod
    def default(cls, msg_paths: Sequence[str | Path] = ()) -> TypeStore:
        """A store over ``default_sources``."""
        return cls(default_sources(msg_paths))

    def with_definition(self, name: str, full_text: str) -> TypeStore:
        """A store that resolves ``name`` and its dependencies from ``full_text`` first.

        An empty definition (some bags have one) falls through to this store's sources.
        """
        name = normalize_type_name(name)
        if not is_valid_type(name) or name.endswith("]"):
            raise DefinitionError(f"{name!r} is not a legal message type name")
        if not full_text.strip():
            return self
        store = TypeStore([DefinitionSource(name, full_text), *self.sources])
        store.check(name)
        return store

    def check(self, name: str) -> None:
        """Refuse a type that contains itself or nests deeper than ``MAX_NESTING``.

        The codec, the md5 and the definition text recurse once per level, so a definition
        from a peer or a bag is checked here first, without recursion, and a bad one is a
        ``DefinitionError`` naming the type.
        """
        root = normalize_type_name(name)
        done: set[str] = set()  # checked with all below them (a type shared twice is fine)
        stack = [(root, iter(self.msg(root).dependencies))]
        on_path = {root}
        while stack:
            current, deps = stack[-1]
            dep = next(deps, None)
            if dep is None:
                stack.pop()
                on_path.discard(current)
                done.add(current)
            elif dep in on_path:
                raise DefinitionError(f"invalid definition of {root}: {dep} contains itself")
            elif dep not in done:
                if len(stack) >= MAX_NESTING:
                    raise DefinitionError(
                        f"invalid definition of {root}: types nest deeper than {MAX_NESTING} levels"
                    )
                try:
                    spec = self.msg(dep)
                except NotFoundError:
                    done.add(dep)  # unknown here: whoever needs it says so
                    continue
                on_path.add(dep)
                stack.append((dep, iter(spec.dependencies)))

    def _text(self, kind: Kind, name: str) -> str:
        for source in self.sources:
            text = source.text(kind, name)
            if text is not None:
                return text
        noun = "message" if kind == "msg" else "service"
        raise NotFoundError(
            f"unknown {noun} type {name}",
            hint="check the spelling, or add its package folder with --msg-path",
        )

    def msg(self, name: str) -> MsgSpec:
        """The spec of message type ``pkg/Type``."""
        name = normalize_type_name(name)
        spec = self._msgs.get(name)
        if spec is None:
            if name.count("/") != 1:
                raise NotFoundError(f"unknown message type {name}", hint="use the form pkg/Type")
            spec = self._msgs[name] = parse_msg(self._text("msg", name), name)
        return spec

    def srv(self, name: str) -> SrvSpec:
        """The spec of service type ``pkg/Type``."""
        name = normalize_type_name(name)
        spec = self._srvs.get(name)
        if spec is None:
            if name.count("/") != 1:
                raise NotFoundError(f"unknown service type {name}", hint="use the form pkg/Type")
            spec = self._srvs[name] = parse_srv(self._text("srv", name), name)
            # Register the halves so md5 and codecs can find them by name.
            self._msgs[spec.request.name] = spec.request
            self._msgs[spec.response.name] = spec.response
        return spec

    def action(self, name: str) -> ActionSpec:
        """The action ``pkg/NameAction`` (also written ``pkg/Name``, ``pkg/action/Name``).

        Its messages come from wherever messages come from: an ``.action`` file on the search
        path, the built-in table, or definitions learnt from a peer.
        """
        full = action_name(name)
        stem = full.removesuffix("Action")
        if full.count("/") != 1 or not stem.partition("/")[2]:
            raise NotFoundError(f"unknown action type {name}", hint="use the form pkg/NameAction")
        try:
            for suffix in SUFFIXES[1:4]:  # the wrappers on the wire must be there too
                self.msg(stem + suffix)
            goal, result, feedback = (self.msg(stem + s) for s in ("Goal", "Result", "Feedback"))
        except NotFoundError:
            raise NotFoundError(
                f"unknown action type {full}",
                hint="check the spelling, or add the folder of its package (with action/) "
                "with --msg-path",
            ) from None
        text = self._file_text_or_none("action", stem)
        if text is None:  # rejoined as the file would have been written
            parts = [s.text.removeprefix(AUTOGEN) for s in (goal, result, feedback)]
            text = "---\n".join(parts)
        return ActionSpec(full, goal, result, feedback, text)

    def has_action(self, name: str) -> bool:
        """True when the action type can be found."""
        try:
            self.action(name)
        except NotFoundError:
            return False
        return True

    def _file_text_or_none(self, kind: Kind, name: str) -> str | None:
        for source in self.sources:
            text = source.text(kind, name)
            if text is not None:
                return text
        return None

    def has_msg(self, name: str) -> bool:
        """True when the message type can be found."""
        try:
            self.msg(name)
        except NotFoundError:
            return False
        return True

    def md5_text(self, spec: MsgSpec, _visiting: frozenset[str] = frozenset()) -> str:
        """Genmsg's ``compute_md5_text``: constants first, nested types by their md5."""
        lines = [f"{c.type} {c.name}={c.text}" for c in spec.constants]
        for f in spec.fields:
            if f.is_builtin:
                lines.append(f"{f.type} {f.name}")
            else:
                lines.append(f"{self._md5_of(f.base, _visiting | {spec.name})} {f.name}")
        return "\n".join(lines)

    def _md5_of(self, name: str, visiting: frozenset[str]) -> str:
        md5 = self._md5.get(name)
        if md5 is None:
            if name in visiting:
                raise DefinitionError(f"{name} contains itself")
            text = self.md5_text(self.msg(name), visiting)
            md5 = self._md5[name] = hashlib.md5(text.encode(), usedforsecurity=False).hexdigest()
        return md5

    def md5(self, name: str) -> str:
        """The md5sum of a message type, as on the wire."""
        return self._md5_of(normalize_type_name(name), frozenset())

    def srv_md5(self, name: str) -> str:
        """The md5sum of a service type: request and response md5 texts, concatenated."""
        spec = self.srv(name)
        text = self.md5_text(spec.request) + self.md5_text(spec.response)
        return hashlib.md5(text.encode(), usedforsecurity=False).hexdigest()

    def dependencies(self, name: str) -> list[str]:
        """Every nested type, depth first in order of first appearance (genmsg's order)."""
        seen: list[str] = []

        def walk(spec: MsgSpec, stack: tuple[str, ...]) -> None:
            for dep in spec.dependencies:
                if dep in stack:
                    raise DefinitionError(f"{dep} contains itself")
                if dep not in seen:
                    seen.append(dep)
                walk(self.msg(dep), (*stack, dep))

        root = self.msg(name)
        walk(root, (root.name,))
        return seen

    def full_text(self, name: str) -> str:
        """The full ``message_definition`` text, as ROS writes it into headers and bags."""
        spec = self.msg(name)
        parts = [spec.text, "\n"]
        for dep in self.dependencies(spec.name):
            parts += [SECTION_RULE, "\nMSG: ", dep, "\n", self.msg(dep).text, "\n"]
        return "".join(parts)[:-1]

    def find(self, kind: Kind, short: str) -> list[str]:
        """Every ``pkg/short`` of this kind, as rosmsg's search of a bare name finds them."""
        return [f"{p}/{short}" for p in self.packages(kind) if short in self._types_of(kind, p)]

    def _types_of(self, kind: Kind, package: str) -> set[str]:
        found: set[str] = set()
        for source in self.sources:
            found.update(source.types(kind, package))
        return found

    def packages(self, kind: Kind) -> list[str]:
        """Packages that hold types of this kind, sorted."""
        found: set[str] = set()
        for source in self.sources:
            found.update(source.packages(kind))
        return sorted(found)

    def types(self, kind: Kind, package: str | None = None) -> list[str]:
        """``pkg/Type`` names of this kind, in one package or all, sorted by package."""
        packages = [package] if package else self.packages(kind)
        return [f"{p}/{t}" for p in packages for t in sorted(self._types_of(kind, p))]


def md5_of(name: str, definition: str) -> str:
    """The md5sum of type ``name`` from its full definition text, or "" if it does not resolve."""
    from rostools.errors import RostoolsError

    try:
        return TypeStore([]).with_definition(name, definition).md5(name)
    except (RostoolsError, DefinitionError, ValueError, KeyError):
        return ""
