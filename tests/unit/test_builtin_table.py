"""The built-in type table is generated from rosbags' Noetic store and must stay in sync."""

from __future__ import annotations

import subprocess
import sys

from rosbags.typesys import Stores, get_typestore

from rostools.msgs.store import BuiltinSource, TypeStore
from tests.support.env import ROOT


def test_table_is_current() -> None:
    proc = subprocess.run(
        [sys.executable, str(ROOT / "scripts" / "gen-builtin-types.py"), "--check"],
        capture_output=True,
        text=True,
        check=False,
    )
    assert proc.returncode == 0, proc.stderr


def test_every_md5_equals_rosbags() -> None:
    rosbags = get_typestore(Stores.ROS1_NOETIC)
    store = TypeStore([BuiltinSource()])
    checked = 0
    for name in rosbags.fielddefs:
        package, _, short = name.split("/")
        if package == "builtin_interfaces":
            continue
        assert store.md5(f"{package}/{short}") == rosbags.generate_msgdef(name)[1], name
        checked += 1
    assert checked > 150
