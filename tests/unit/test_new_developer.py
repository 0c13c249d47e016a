"""A new developer's test: with the map alone, each feature is found at the first guess.

For each of the twelve features issue 37 names, a phrase of ARCHITECTURE.md leads to it: the
row, bullet or paragraph that holds the phrase names the feature's module, and that module
defines the feature. A home that moves without the map, or a map that sends a reader
elsewhere, fails here.
"""

from __future__ import annotations

import importlib
import inspect
import re

import pytest

from tests.support import archmap

#: feature -> (the map's words for it, the module the map names, what there is the feature).
FEATURES: dict[str, tuple[str, str, str]] = {
    "topic hz --filter": ("`topic hz`", "rostools.cli.topic.hz", "_filter"),
    "the snapshot trigger service": (
        "`trigger_snapshot`",
        "rostools.bag.live.snapshot_services",
        "serve",
    ),
    "bag play's pacing": ("`bag play`: `Player`, its pacing", "rostools.bag.live.player", "Player"),
    "the XML-RPC fault": ("answers and faults", "rostools.wire.xmlvalues", "Fault"),
    "the .bag index check": (
        "index entries are checked against them",
        "rostools.bag.formats.rosbag1_index",
        "checked_entries",
    ),
    "a type mismatch's exit code": ("a type mismatch", "rostools.errors", "UsageError"),
    "tab completion of topics": ("answers a TAB", "rostools.cli.completer", "Completer"),
    "ROS_IP": ("ROS_IP", "rostools.rosgraph.network", "host_name"),
    "the MCAP CRC": ("**CRCs.**", "rostools.bag.formats.mcap_format", "crc32"),
    "rosparam load's !degrees": ("`!degrees`", "rostools.cli.param.paramyaml", "ParamLoader"),
    "topic echo -b": ("`topic echo -b`", "rostools.cli.topic.bagecho", "echo_bag"),
    "the plugin's reaper": ("a reaper process", "rostools.testing.reaper", "main"),
}


def blocks(text: str) -> list[str]:
    """The map as a reader takes it in: table rows, bullets and paragraphs, one line each."""
    found: list[str] = []
    for line in text.splitlines():
        stripped = line.strip()
        starts = not stripped or stripped.startswith(("|", "- ", "#"))
        if starts or not found or found[-1].startswith("|"):
            found.append(stripped)
        else:
            found[-1] += " " + stripped
    return [b for b in found if b]


def leads_to(words: str, module: str, text: str) -> list[str]:
    """The blocks of ``text`` that hold ``words`` and name ``module``."""
    path = module.removeprefix("rostools.").replace(".", "/") + ".py"
    parts = path.split("/")
    tails = ["/".join(parts[i:]) for i in range(len(parts))]  # a/b.py, b.py
    return [b for b in blocks(text) if words in b and any(archmap.mentions(b, t) for t in tails)]


@pytest.mark.parametrize("feature", FEATURES)
def test_the_map_leads_to_the_feature(feature: str) -> None:
    words, module, _ = FEATURES[feature]
    text = archmap.text()
    assert words in text, f"the map never says {words!r}"
    assert leads_to(words, module, text), f"where the map says {words!r}, it names no {module}"


@pytest.mark.parametrize("feature", FEATURES)
def test_the_feature_lives_where_the_map_says(feature: str) -> None:
    _, module, name = FEATURES[feature]
    found = getattr(importlib.import_module(module), name)
    if inspect.isclass(found) or inspect.isfunction(found):
        assert found.__module__ == module, f"{module} imports {name}; it lives elsewhere"


def test_a_type_mismatch_is_a_usage_error() -> None:
    from rostools.errors import UsageError

    assert UsageError.exit_code == 2


def test_a_wrong_lead_is_caught() -> None:
    text = "| 4 | `rosgraph/` | the rules of ROS_IP (`network.py`) |\n\n- **Other.** `reaper.py`\n"
    assert leads_to("ROS_IP", "rostools.rosgraph.network", text)
    assert not leads_to("ROS_IP", "rostools.testing.reaper", text)
    assert re.search("Other", blocks(text)[1])
