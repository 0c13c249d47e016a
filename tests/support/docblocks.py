"""The fenced code blocks of README.md and docs/*.md, and what each says of itself.

Every fence names its language. ``console`` (``$ command`` lines, each followed by the output
it shows), ``sh`` (a command a line) and ``python`` blocks are examples: a test runs them
(tests/integration/test_doc_examples.py); ``html`` blocks are pages, which a browser test
runs (so each is marked ``not run``, naming that test). ``text``, ``yaml`` and ``json`` blocks
are data.
HTML comments right above a fence (hidden when the page is shown) say more:

- ``<!-- not run: REASON -->``: an example no test can run here, and why;
- ``<!-- output not compared: REASON -->``: the output shown is an illustration;
- ``<!-- exit: N -->``: each command of the block exits N (default 0);
- ``<!-- excerpt: PATH, ... -->``: Python taken from PATH, whose functions it must match;
- ``<!-- xfail: REASON -->``: an example known to fail, until REASON is fixed.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

EXAMPLES = ("console", "sh", "python", "html")
DATA = ("text", "yaml", "json")
MARKERS = ("not run", "output not compared", "exit", "excerpt", "xfail")
_FENCE = re.compile(r"^(`{3,})(.*)$")
_MARKER = re.compile(r"^<!--\s*([a-z ]+?)\s*(?::\s*(.*?))?\s*-->$")
#: A comment at the end of a command or an output line: two spaces or more, then ``# ``.
_COMMENT = re.compile(r"\s{2,}#(\s.*)?$")


@dataclass
class Command:
    """One command of a shell example, with the output lines shown after it."""

    text: str
    line: int
    output: list[str] = field(default_factory=list)


@dataclass
class Block:
    """One fenced block: where it is, its language, its text and its markers."""

    path: Path
    line: int
    lang: str
    body: str
    markers: dict[str, str]

    @property
    def where(self) -> str:
        """``docs/bag.md:12``."""
        root = self.path.parent.parent if self.path.parent.name == "docs" else self.path.parent
        return f"{self.path.relative_to(root)}:{self.line}"

    def commands(self) -> list[Command]:
        """The commands of a ``console`` or ``sh`` block (``\\`` joins continued lines)."""
        out: list[Command] = []
        pending: Command | None = None
        for n, raw in enumerate(self.body.split("\n"), self.line + 1):
            if pending is not None:  # a continued command
                pending.text += " " + raw.strip()
            elif self.lang == "console" and raw.startswith("$ "):
                pending = Command(raw[2:], n)
            elif self.lang == "sh" and raw.strip() and not raw.lstrip().startswith("#"):
                pending = Command(raw, n)
            elif out and raw.strip():
                out[-1].output.append(_COMMENT.sub("", raw).rstrip())
                continue
            else:
                continue
            if pending.text.endswith("\\"):
                pending.text = pending.text[:-1].rstrip()
                continue
            pending.text = _COMMENT.sub("", pending.text).strip()
            out.append(pending)
            pending = None
        return out


def blocks(path: Path) -> list[Block]:
    """The fenced blocks of one Markdown file, in order."""
    lines = path.read_text().split("\n")
    found: list[Block] = []
    i = 0
    while i < len(lines):
        fence = _FENCE.match(lines[i])
        if not fence:
            i += 1
            continue
        end = next(
            (j for j in range(i + 1, len(lines)) if lines[j].startswith(fence.group(1))),
            len(lines),
        )
        markers: dict[str, str] = {}
        k = i - 1
        while k >= 0 and (marker := _MARKER.match(lines[k].strip())):
            markers[marker.group(1)] = marker.group(2) or ""
            k -= 1
        body = "\n".join(lines[i + 1 : end])
        found.append(Block(path, i + 1, fence.group(2).strip(), body, markers))
        i = end + 1
    return found


def problems(block: Block) -> list[str]:
    """What is wrong with a block's language or markers (nothing: an empty list)."""
    out = []
    if block.lang not in EXAMPLES + DATA:
        out.append(f"a fence of {block.lang or 'no language'} (use one of {EXAMPLES + DATA})")
    for key, value in block.markers.items():
        if key not in MARKERS:
            out.append(f"an unknown marker {key!r} (known: {', '.join(MARKERS)})")
        elif key == "exit" and not value.isdigit():
            out.append(f"exit {value!r} is no exit code")
        elif not value:
            out.append(f"the marker {key!r} gives no reason")
    if block.markers and block.lang in DATA:
        out.append("a marker on a block that is data, not an example")
    if block.lang == "html" and "not run" not in block.markers:
        out.append("a page with no 'not run' marker naming the browser test that runs it")
    if "excerpt" in block.markers and block.lang != "python":
        out.append("an excerpt that is not Python")
    return out


def documents(root: Path) -> list[Path]:
    """README.md and the pages of docs/."""
    return [root / "README.md", *sorted((root / "docs").glob("*.md"))]
