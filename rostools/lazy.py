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
def _block(package: str) -> dict[str, tuple[str, str]]:
    """Each public name of ``package``: the module it comes from, and its name there."""
    import ast

    path = sys.modules[package].__file__
    assert path is not None
    with open(path, encoding="utf-8") as f:
        tree = ast.parse(f.read(), path)
    found: dict[str, tuple[str, str]] = {}
    for statement in tree.body:
        if isinstance(statement, ast.If) and ast.unparse(statement.test) == "TYPE_CHECKING":
            for node in statement.body:
                if isinstance(node, ast.ImportFrom) and node.module:
                    for alias in node.names:
                        found[alias.asname or alias.name] = (node.module, alias.name)
    return found


def homes(package: str) -> dict[str, str]:
    """Each public name of ``package`` and the module it comes from, from its block."""
    return {name: module for name, (module, _) in _block(package).items()}


def load(package: str, name: str) -> object:
    """``package.name``, imported from its home now and kept in the package from then on.

    A name the block imports ``as`` another is the other, as the import says.
    """
    if name == "__all__":
        return sorted(_block(package))
    found = _block(package).get(name)
    if found is None:
        raise AttributeError(f"module {package!r} has no attribute {name!r}")
    import importlib

    home, original = found
    value = getattr(importlib.import_module(home), original)
    setattr(sys.modules[package], name, value)
    return value
