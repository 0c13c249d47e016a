"""ARCHITECTURE.md read as the invariants test reads it: its sections, the files it cites.

Kept apart from the tests so that each test says what it holds, not how the map is parsed.
"""

from __future__ import annotations

import ast
import io
import re
import subprocess
import tokenize
from functools import cache
from pathlib import Path

from tests.support.env import ROOT

MAP = ROOT / "ARCHITECTURE.md"
PACKAGE = ROOT / "rostools"

#: A file named in text: a path or a bare name with one of the extensions the repo holds.
CITED = re.compile(
    r"(?<![\w./*-])((?:[\w-]+/)*[\w-]+(?:\.[\w-]+)*\.(?:py|md|json|toml|sh|mjs|cfg|in))(?![\w/])"
)
#: A constant that is a wait or a limit, by its name.
BOUNDED = re.compile(r"^_?(?:[A-Z0-9_]*_(?:TIMEOUT|WAIT)|MAX_[A-Z0-9_]*)$")


def text() -> str:
    """ARCHITECTURE.md as it is now."""
    return MAP.read_text()


def section(whole: str, title: str) -> str:
    """The body of the ``## title`` section."""
    return whole.split(f"\n## {title}\n", 1)[1].split("\n## ", 1)[0]


def bullet(whole: str, start: str) -> str:
    """The top-level bullet that starts ``- **start``, with its continuation lines."""
    lines = whole.split(f"\n- **{start}", 1)[1].splitlines()
    kept = [lines[0]]
    for line in lines[1:]:
        if line.startswith("- ") or line.startswith("## "):
            break
        kept.append(line)
    return "\n".join(kept)


def items(block: str) -> list[str]:
    """A block's sub-bullets (``  - ``) and table rows (``  | ``), each with what continues it."""
    found: list[str] = []
    for line in block.splitlines():
        stripped = line.strip()
        if stripped.startswith(("- ", "| ")):
            found.append(stripped)
        elif found and stripped and not found[-1].startswith("| "):
            found[-1] += " " + stripped
    return found


def bounded_items(whole: str) -> list[str]:
    """The timeouts list and the limits table, item by item: where waits and limits live."""
    return items(bullet(whole, "Timeouts.")) + items(bullet(whole, "Limits on everything"))


#: Folders that are no part of the source: virtual environments, builds, caches.
NOT_SOURCE = {".git", ".venv", "build", "__pycache__", "node_modules", "mutants"}


@cache
def repo_files() -> tuple[str, ...]:
    """Every file of the source tree: git's (new ones too), or, in an sdist, the tree's."""
    try:
        listed = subprocess.run(
            ["git", "ls-files", "--cached", "--others", "--exclude-standard"],
            cwd=ROOT,
            capture_output=True,
            text=True,
            check=True,
        ).stdout.split()
    except (OSError, subprocess.CalledProcessError):  # no git, or not a clone
        listed = [
            p.relative_to(ROOT).as_posix()
            for p in ROOT.rglob("*")
            if p.is_file() and not NOT_SOURCE & set(p.relative_to(ROOT).parts)
        ]
    return tuple(f for f in listed if (ROOT / f).is_file())


def exists(cited: str) -> bool:
    """Whether a cited file is in the repo: its path, or a path that ends with it."""
    tail = "/" + cited
    return any(f == cited or f.endswith(tail) for f in repo_files())


def cited_in(whole: str) -> set[str]:
    """The files a text cites."""
    return set(CITED.findall(whole))


def cited_in_source(path: Path) -> set[str]:
    """The files a module's comments and strings (its docstrings among them) cite."""
    found: set[str] = set()
    with io.StringIO(path.read_text()) as source:
        for token in tokenize.generate_tokens(source.readline):
            if token.type in (tokenize.COMMENT, tokenize.STRING):
                found |= cited_in(token.string)
    return found


def modules() -> list[Path]:
    """Every module under rostools/."""
    return sorted(p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)


def relative(module: Path) -> str:
    """A module's path under rostools/: ``cli/bag/record.py``."""
    return module.relative_to(PACKAGE).as_posix()


def bounded_constants() -> list[tuple[str, str]]:
    """Each module-level wait or limit constant: (its module under rostools/, its name)."""
    found: list[tuple[str, str]] = []
    for module in modules():
        tree = ast.parse(module.read_text(), str(module))
        for statement in tree.body:
            targets: list[ast.expr] = []
            if isinstance(statement, ast.Assign):
                targets = statement.targets
            elif isinstance(statement, ast.AnnAssign):
                targets = [statement.target]
            found += [
                (relative(module), t.id)
                for t in targets
                if isinstance(t, ast.Name) and BOUNDED.match(t.id)
            ]
    return found


def names_module(cite: str, module: str) -> bool:
    """Whether a path cited in the map is ``module`` (a path under rostools/ or its tail)."""
    return module == cite or module.endswith("/" + cite)


def mentions(text: str, module: str) -> bool:
    """Whether ``text`` names ``module`` by a path: ``a/b.py``, or ``a/b.Name`` for a name in it."""
    stem = re.escape(module.removesuffix(".py"))
    return re.search(rf"(?<![\w/.]){stem}(?:\.py\b|\.[A-Za-z_])", text) is not None


def homes_in(item: str, name: str) -> list[str]:
    """The modules an item of the map gives as ``name``'s home, one per time it names it.

    The nearest file cited before the name in the item, else the first after it: a row says
    ``module `A`; `B``` for two constants of one module, a bullet ``A (module)`` for one.
    """
    found: list[str] = []
    for at in (m.start() for m in re.finditer(f"`{re.escape(name)}`", item)):
        before = [c for c in CITED.findall(item[:at]) if c.endswith(".py")]
        after = [c for c in CITED.findall(item[at:]) if c.endswith(".py")]
        if before or after:
            found.append(str(before[-1] if before else after[0]))
    return found
