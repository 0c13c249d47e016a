"""What every generator of Python source in ``msgs/`` shares.

The codec, the text, plain, JSON and CSV formatters and the partial decoders of plots each
write the source of one function per type and ``exec`` it: that is what makes them fast. Each
keeps its own logic; this module is the rest, in one place: the table of objects the source
refers to by name (``GeneratedCode.ref``), fresh local names (``GeneratedCode.fresh``), field
names as attributes (``attr_name``), and compiling (``GeneratedCode.compile``: ``<rostools KIND
NAME>`` in tracebacks, the table as globals or bound as default arguments).
"""

from __future__ import annotations

import keyword
from typing import Any

from rostools.msgs.spec import Field


def attr_name(field_name: str) -> str:
    """The Python attribute for a ROS field; keywords get a ``_`` suffix, as in genpy."""
    return field_name + "_" if keyword.iskeyword(field_name) else field_name


def element(base: str) -> Field:
    """The value type of one element of an array of ``base`` (a scalar field)."""
    return Field("_", base, base, False, None)


class GeneratedCode:
    """The source of one generated function: its lines, and the objects they refer to.

    ``env`` holds names the generator fixes in advance (helpers it calls by name); ``ref``
    adds the rest. Refs start with ``_`` and locals from ``fresh`` do not, so they never meet.
    """

    def __init__(self, env: dict[str, Any] | None = None) -> None:
        self.env: dict[str, Any] = dict(env or {})
        self.lines: list[str] = []
        self.indent = "    "
        self.counter = 0
        self._names: dict[int, str] = {}  # by id: the env keeps each object alive

    def ref(self, obj: Any, prefix: str = "k") -> str:
        """The name the source uses for ``obj``: one name per object."""
        name = self._names.get(id(obj))
        if name is None:
            name = self._names[id(obj)] = f"_{prefix}{len(self.env)}"
            self.env[name] = obj
        return name

    def fresh(self, prefix: str) -> str:
        """A new local name."""
        self.counter += 1
        return f"{prefix}{self.counter}"

    def line(self, text: str) -> None:
        """Add a line at the current indent."""
        self.lines.append(self.indent + text)

    def compile(self, signature: str, kind: str, name: str, *, bind: bool = False) -> Any:
        """``def SIGNATURE:`` over the lines, compiled as ``<rostools KIND NAME>``: the function.

        ``bind``: the refs become default arguments, which Python reads as locals, faster
        than globals in a hot loop (the codec's and the partial decoders'); else the
        function sees them as its globals.
        """
        params = "".join(f", {k}={k}" for k in self.env) if bind else ""
        body = "\n".join(self.lines) if self.lines else self.indent + "pass"
        source = f"def {signature[:-1]}{params}):\n{body}\n"
        namespace = dict(self.env)
        exec(compile(source, f"<rostools {kind} {name}>", "exec"), namespace)  # noqa: S102
        return namespace[signature.partition("(")[0]]
