"""A package's public names from one list, loaded on first use (PEP 562).

The list is the package's ``if TYPE_CHECKING:`` block of imports: type checkers read it as
the names' imports, and at run time nothing in it is imported until a name is used, when
the block says from where (``homes``). ``__all__`` is the block's names too. Start-up time is
why: every command of the CLI imports ``rostools``, every pytest run ``rostools.testing``.
"""

from __future__ import annotations

import functools
import sys


@functools.cache
def homes(package: str) -> dict[str, str]:
    """Each public name of ``package`` and the module it comes from, from its block."""
    import ast

    path = sys.modules[package].__file__
    assert path is not None
    with open(path, encoding="utf-8") as f:
        tree = ast.parse(f.read(), path)
    found: dict[str, str] = {}
    for statement in tree.body:
        if isinstance(statement, ast.If) and ast.unparse(statement.test) == "TYPE_CHECKING":
            for node in statement.body:
                if isinstance(node, ast.ImportFrom) and node.module:
                    found |= {alias.asname or alias.name: node.module for alias in node.names}
    return found


def load(package: str, name: str) -> object:
    """``package.name``, imported from its home now and kept in the package from then on."""
    if name == "__all__":
        return sorted(homes(package))
    home = homes(package).get(name)
    if home is None:
        raise AttributeError(f"module {package!r} has no attribute {name!r}")
    import importlib

    value = getattr(importlib.import_module(home), name)
    setattr(sys.modules[package], name, value)
    return value
