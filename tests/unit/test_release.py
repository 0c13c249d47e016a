"""What a release carries: one version, its licence, its changelog, links that work on an index."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import rostools
import rostools.version

ROOT = Path(__file__).resolve().parents[2]
PYPROJECT = (ROOT / "pyproject.toml").read_text()
#: A document named in code or tests: ``NAME.md``, ``docs/NAME.md``.
CITED = re.compile(r"\b((?:docs/)?[A-Za-z0-9_-]+\.md)\b")


def _table(name: str) -> str:
    """The body of one ``[name]`` table of pyproject.toml (tomllib is 3.11+, we run on 3.10)."""
    found = re.search(rf"^\[{re.escape(name)}\]\n(.*?)(?=^\[|\Z)", PYPROJECT, re.M | re.S)
    assert found, name
    return found.group(1)


def test_the_version_has_one_source() -> None:
    project = _table("project")
    assert 'dynamic = ["version"]' in project and not re.search(r"^version\s*=", project, re.M)
    dynamic = _table("tool.setuptools.dynamic")
    assert 'version = { attr = "rostools.version.__version__" }' in dynamic
    assert rostools.__version__ is rostools.version.__version__


def test_the_changelog_starts_with_this_version() -> None:
    releases = re.findall(
        r"^## \[(\d[^\]]*)\] - \d{4}-\d\d-\d\d$", (ROOT / "CHANGELOG.md").read_text(), re.M
    )
    assert releases and releases[0] == rostools.__version__


def test_the_licence_is_declared_the_modern_way() -> None:
    project = _table("project")
    assert 'license = "BSD-3-Clause"' in project and 'license-files = ["LICENSE"]' in project
    assert (ROOT / "LICENSE").read_text().startswith("BSD 3-Clause License")
    assert "License ::" not in project  # PEP 639: the expression replaces licence classifiers


def test_every_python_the_package_claims_is_a_classifier() -> None:
    project = _table("project")
    assert 'requires-python = ">=3.10"' in project
    for minor in (10, 11, 12, 13):
        assert f'"Programming Language :: Python :: 3.{minor}"' in project


def test_readme_links_work_on_a_package_index() -> None:
    # an index shows README.md alone: a relative image or link there is a broken one
    readme = (ROOT / "README.md").read_text()
    home = re.search(r'^Source = "(https://github\.com/[^"]+)"', _table("project.urls"), re.M)
    assert home
    targets = re.findall(r"\]\(([^)\s]+)\)", readme)
    assert targets
    for target in targets:
        assert target.startswith(("https://", "#")), target
        if target.endswith((".png", ".svg")):
            assert target.startswith(
                home.group(1).replace("github.com", "raw.githubusercontent.com")
            )


def test_every_document_the_code_cites_exists() -> None:
    # seven modules cited two design notes that were never in the repository
    ours = {p.name for p in ROOT.rglob("*.md") if ".venv" not in p.parts}
    missing = []
    for folder in ("rostools", "tests", "benchmarks", "scripts"):
        for path in (ROOT / folder).rglob("*.py"):
            if ".venv" in path.parts or "build" in path.parts or path.name == Path(__file__).name:
                continue
            for name in CITED.findall(path.read_text()):
                if Path(name).name not in ours:
                    missing.append(f"{path.relative_to(ROOT)}: {name}")
    assert missing == []


def test_version_flag() -> None:
    for flag in ("-V", "--version"):
        done = subprocess.run(
            [sys.executable, "-m", "rostools", flag], capture_output=True, text=True, check=False
        )
        assert (done.returncode, done.stdout) == (0, f"rostools {rostools.__version__}\n")


def test_the_sdists_tests_run_on_this_interpreter_when_no_other_is_found(tmp_path: Path) -> None:
    """scripts/check-release.sh ran the sdist's unit tests on the other interpreters it found
    only: on a machine with none, a broken sdist passed. This one (``python3``) comes first,
    always; the others it cannot find are listed without a path."""
    script = ROOT / "scripts" / "check-release.sh"
    assert "sdist_pythons()" in script.read_text()  # sourced without it, the whole check runs
    bin_dir = tmp_path / "bin"
    bin_dir.mkdir()
    (bin_dir / "python3").symlink_to(sys.executable)
    env = {"PATH": f"{bin_dir}:/usr/bin:/bin", "PYENV_ROOT": str(tmp_path / "none"),
           "HOME": str(tmp_path)}  # fmt: skip
    listed = subprocess.run(
        ["bash", "-c", f'source "{script}" && sdist_pythons'],
        env=env, capture_output=True, text=True, timeout=60, check=True,
    ).stdout.splitlines()  # fmt: skip
    this = f"{sys.version_info[0]}.{sys.version_info[1]}"
    assert listed[0] == f"{this} {bin_dir / 'python3'}"
    assert sorted(line.split()[0] for line in listed) == sorted(
        {"3.10", "3.11", "3.12", "3.13", this}
    )
