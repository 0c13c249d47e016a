"""The docs: README.md is the front door, docs/ the rest, built as a site with mkdocs --strict.

Their examples are run by tests/integration/test_doc_examples.py; here, that each fenced
block says what it holds, that the site builds without a broken link or anchor, and that the
README's links into the repository name files that are there.
"""

from __future__ import annotations

import os
import re
import subprocess
import sys
from pathlib import Path

from tests.support.docblocks import Block, blocks, documents, problems
from tests.support.env import ROOT

REPO = "https://github.com/rostools/rostools/blob/main/"


def test_the_site_builds_with_no_broken_link(tmp_path: Path) -> None:
    # --strict: a link to a page or an anchor that is not there fails the build
    done = subprocess.run(
        [sys.executable, "-m", "mkdocs", "build", "--strict", "-q",
         "-f", str(ROOT / "mkdocs.yml"), "-d", str(tmp_path / "site")],
        cwd=tmp_path, capture_output=True, text=True, timeout=300, check=False,
        env=dict(os.environ, NO_MKDOCS_2_WARNING="1"),
    )  # fmt: skip
    assert done.returncode == 0, done.stdout[-3000:] + done.stderr[-3000:]
    site = tmp_path / "site"
    for page in ("index", "topic", "bag", "api", "testing", "limits", "benchmarks", "design"):
        assert (site / page / "index.html").is_file() or (site / f"{page}.html").is_file(), page
    home = (site / "index.html").read_text()
    assert "From ROS 1 to rostools" in home  # README.md, included whole
    assert "Bird" in (site / "design" / "index.html").read_text()  # and ARCHITECTURE.md


def test_every_block_says_what_it_holds() -> None:
    found = [f"{b.where}: {p}" for doc in documents(ROOT) for b in blocks(doc) for p in problems(b)]
    assert found == []


def test_the_readme_is_the_front_door() -> None:
    readme = (ROOT / "README.md").read_text()
    for heading in ("## Install", "## Start here", "## From ROS 1 to rostools", "## Documentation"):
        assert heading in readme, heading
    assert len(readme.splitlines()) < 250
    # what fails today is said, and what works today is given
    assert "not on the package index (PyPI) yet" in readme
    assert "pipx install ." in readme


def test_every_page_of_docs_is_linked_from_the_readme() -> None:
    readme = (ROOT / "README.md").read_text()
    linked = set(re.findall(re.escape(REPO) + r"docs/([\w-]+\.md)", readme))
    pages = {p.name for p in (ROOT / "docs").glob("*.md")} - {"changelog.md"}
    assert pages - linked == set()


def test_the_readmes_links_into_the_repository_are_there() -> None:
    readme = (ROOT / "README.md").read_text()
    targets = re.findall(re.escape(REPO) + r"([^)#\s]+)(?:#([\w-]+))?\)", readme)
    assert targets
    for path, anchor in targets:
        assert (ROOT / path).is_file(), path
        if anchor:
            headings = re.findall(r"^#+ (.+)$", (ROOT / path).read_text(), re.M)
            assert anchor in {_slug(h) for h in headings}, f"{path}#{anchor}"


def _slug(heading: str) -> str:
    """The anchor GitHub and mkdocs give a heading."""
    return re.sub(r"[^\w\- ]", "", heading.lower()).strip().replace(" ", "-")


def test_blocks_are_read_as_the_examples_test_reads_them(tmp_path: Path) -> None:
    page = tmp_path / "page.markdown"
    page.write_text(
        "<!-- exit: 6 -->\n```console\n$ rostools bag info a.bag \\\n    -y   # a comment\n"
        "path: a.bag\n...\n$ rostools msg md5 X\n```\n\n```\nrostools topic list\n```\n"
        "<!-- not run -->\n<!-- colour: blue -->\n```sh\nrostools core\n```\n"
        "```html\n<p>a page</p>\n```\n"
    )
    first, untagged, odd, page_block = blocks(page)
    assert isinstance(first, Block) and first.markers == {"exit": "6"}
    assert [(c.text, c.line, c.output) for c in first.commands()] == [
        ("rostools bag info a.bag -y", 3, ["path: a.bag", "..."]),
        ("rostools msg md5 X", 7, []),
    ]
    assert problems(first) == []
    assert problems(untagged) == [
        "a fence of no language (use one of "
        "('console', 'sh', 'python', 'html', 'text', 'yaml', 'json'))"
    ]
    assert problems(odd) == [
        "an unknown marker 'colour' (known: not run, output not compared, exit, excerpt, xfail)",
        "the marker 'not run' gives no reason",
    ]
    assert problems(page_block) == [
        "a page with no 'not run' marker naming the browser test that runs it"
    ]
