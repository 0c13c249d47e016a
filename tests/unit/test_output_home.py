"""``cli/output.py`` is the one writer to stdout (ARCHITECTURE.md, Output).

Every other module prints through it (``emit``, ``write``, ``put``, ``line``, ``put_bytes``):
one place for formats, flushing and a reader that went away.
"""

from __future__ import annotations

import ast
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2] / "rostools"
HOME = ROOT / "cli" / "output.py"


def _writes(path: Path) -> list[str]:
    """Where ``path`` writes to stdout itself: ``file:line call``."""
    found = []
    for node in ast.walk(ast.parse(path.read_text())):
        if not isinstance(node, ast.Call):
            continue
        call = ast.unparse(node.func)
        to_stdout = call.startswith("sys.stdout.") and not call.endswith(".isatty")
        bare_print = call == "print" and not any(k.arg == "file" for k in node.keywords)
        if to_stdout or bare_print or call == "typer.echo":
            found.append(f"{path.relative_to(ROOT)}:{node.lineno} {call}")
    return found


def test_only_output_writes_to_stdout() -> None:
    assert _writes(HOME), "the scan finds output.py's own writes"
    others = [w for p in sorted(ROOT.rglob("*.py")) if p != HOME for w in _writes(p)]
    assert others == [], "\n".join(others)
