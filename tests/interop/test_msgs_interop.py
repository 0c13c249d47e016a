"""The type system against the real ROS 1 (genmsg, genpy, rosmsg, rostopic from Debian)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

import pytest
import yaml

from rostools.errors import NotFoundError
from rostools.msgs.codec import BYTE_TYPES, Codec
from rostools.msgs.describe import show_srv_text, show_text
from rostools.msgs.fill import Filler
from rostools.msgs.plain import CsvOptions, csv_header, csv_row, to_plain
from rostools.msgs.store import BuiltinSource, TypeStore, default_sources
from rostools.msgs.text import TextOptions, formatter, message_type
from tests.support.env import ask_ros1, needs_ros1, run_cli
from tests.support.randmsg import RandomMessages

pytestmark = [pytest.mark.interop, needs_ros1]


@pytest.fixture(scope="module")
def installed() -> dict[str, str]:
    """Every type the installed ROS packages list (rosmsg list + rossrv list)."""
    types = ask_ros1([{"op": "types"}])[0]
    assert isinstance(types, dict)
    assert len(types) > 150, "expected the message packages of install-ros1-peers.sh"
    return types


@pytest.fixture(scope="module")
def system_store() -> TypeStore:
    """What rostools finds on this machine with no settings: Debian's /usr/share packages."""
    saved = os.environ.pop("ROS_PACKAGE_PATH", None)
    try:
        return TypeStore(default_sources())
    finally:
        if saved is not None:
            os.environ["ROS_PACKAGE_PATH"] = saved


def test_md5_show_and_raw_agree_with_rosmsg_for_every_installed_type(
    installed: dict[str, str], system_store: TypeStore
) -> None:
    names = sorted(installed)
    answers = ask_ros1([{"op": "describe", "kind": installed[n], "type": n} for n in names])
    builtin = TypeStore([BuiltinSource()])
    compared_builtin = 0
    for name, ref in zip(names, answers, strict=True):
        assert isinstance(ref, dict) and "error" not in ref, (name, ref)
        if installed[name] == "msg":
            spec = system_store.msg(name)
            assert system_store.md5(name) == ref["md5"], name
            assert show_text(system_store, spec) == ref["show"], name
            assert spec.text == ref["raw"], name
            assert system_store.full_text(name) == ref["full"], name
            if builtin.has_msg(name):  # the table from rosbags, checked against real files
                assert builtin.md5(name) == ref["md5"], name
                assert show_text(builtin, builtin.msg(name)) == ref["show"], name
                compared_builtin += 1
        else:
            srv = system_store.srv(name)
            assert system_store.srv_md5(name) == ref["md5"], name
            assert show_srv_text(system_store, srv) == ref["show"], name
            assert srv.text == ref["raw"], name
            try:
                assert builtin.srv_md5(name) == ref["md5"], name
                compared_builtin += 1
            except NotFoundError:
                pass
    assert compared_builtin > 100


TRICKY = {
    "msg/Tricky.msg": (
        '# comment\nstring Q="hi"  \nfloat64 E=1e-3\nfloat64 F=1.50\nint32 P=+5\nstring EMPTY=\n'
        "string HASH=a # not a comment\nbool B=True\nuint8 U=0\nchar C=65\nbyte Y=-3\n"
        "Header header\nInner[] inners\nInner[2] pair\ntime t\nduration d\nuint8[16] uuid\n"
        "string[] names\n"
    ),
    "msg/Inner.msg": "int64 X=-9  # trailing\nfloat32[] values\nstring s\n",
    "srv/Ask.srv": "Inner in # req\nstring  Q=a=b\n---\nTricky out\nint8 R=-1\n",
}


def test_custom_types_with_tricky_constants_agree_with_genmsg(tmp_path: Path) -> None:
    folder = tmp_path / "tricky_pkg"
    for rel, text in TRICKY.items():
        (folder / rel).parent.mkdir(parents=True, exist_ok=True)
        (folder / rel).write_text(text)
    std = Path("/usr/share/std_msgs")
    packages = {"tricky_pkg": str(folder), "std_msgs": str(std)}
    cases = [("msg", "tricky_pkg/Tricky"), ("msg", "tricky_pkg/Inner"), ("srv", "tricky_pkg/Ask")]
    answers = ask_ros1(
        [{"op": "custom", "packages": packages, "kind": k, "type": t} for k, t in cases]
    )
    store = TypeStore.default([tmp_path])
    for (kind, name), ref in zip(cases, answers, strict=True):
        assert isinstance(ref, dict) and "error" not in ref, ref
        if kind == "msg":
            assert store.md5(name) == ref["md5"], name
            assert store.full_text(name) == ref["full"], name
        else:
            assert store.srv_md5(name) == ref["md5"], name


def _types_with_python_classes(installed: dict[str, str]) -> list[str]:
    skip_packages = {"map_msgs", "topic_tools"}  # definitions only, no python3 module
    return [
        n
        for n, k in sorted(installed.items())
        if k == "msg" and n.split("/")[0] not in skip_packages
    ]


def _has_byte_arrays(codec: Codec, name: str, seen: frozenset[str] = frozenset()) -> bool:
    for f in codec.store.msg(name).fields:
        if f.is_array and f.base in BYTE_TYPES:
            return True
        if (
            not f.is_builtin
            and f.base not in seen
            and _has_byte_arrays(codec, f.base, seen | {name})
        ):
            return True
    return False


def test_bytes_from_yaml_equal_genpys(installed: dict[str, str], system_store: TypeStore) -> None:
    codec = Codec.of(system_store)
    requests: list[dict[str, Any]] = []
    ours: list[bytes] = []
    for i, name in enumerate(_types_with_python_classes(installed)):
        rand = RandomMessages(codec, seed=i)
        for _ in range(2):
            plain = to_plain(codec, message_type(name))(rand.message(name))
            arg = yaml.safe_dump(plain, allow_unicode=True)
            ours.append(Filler(codec).message(name, [yaml.safe_load(arg)]).serialize())
            requests.append({"op": "fill", "type": name, "args": [arg]})
    answers = ask_ros1(requests)
    compared = 0
    for req, mine, ref in zip(requests, ours, answers, strict=True):
        assert isinstance(ref, str), (req["type"], ref)
        assert mine.hex() == ref, req["type"]
        compared += 1
    assert compared > 200


def test_echo_text_and_csv_equal_rostopics(
    installed: dict[str, str], system_store: TypeStore
) -> None:
    codec = Codec.of(system_store)
    requests: list[dict[str, Any]] = []
    for i, name in enumerate(_types_with_python_classes(installed)):
        rand = RandomMessages(codec, seed=1000 + i)
        for j in range(3):
            wire = rand.message(name).serialize()
            opts: dict[str, Any] = {}
            if j == 1:
                opts = {"width": 4}
            elif j == 2 and "[]" not in str(codec.store.msg(name).fields):
                # rostopic does not apply --nostr/--noarr inside arrays of messages; we do.
                opts = {"nostr": True, "noarr": True}
            requests.append({"op": "echo", "type": name, "hex": wire.hex(), **opts})
    answers = ask_ros1(requests)
    compared_csv = 0
    for req, ref in zip(requests, answers, strict=True):
        assert isinstance(ref, dict) and "error" not in ref, (req["type"], ref)
        name = req["type"]
        value = codec.decode(name, bytes.fromhex(req["hex"]))
        vt = message_type(name)
        options = TextOptions(req.get("nostr", False), req.get("noarr", False), req.get("width"))
        assert formatter(codec, vt, options)(value) == ref["text"], (name, req)
        if not _has_byte_arrays(codec, name):  # rostopic drops uint8[] columns; we keep them
            csv_opts = CsvOptions(req.get("nostr", False), req.get("noarr", False))
            assert csv_header(codec, vt, value, csv_opts) == ref["csv_header"], name
            assert "0," + csv_row(codec, vt, csv_opts)(value, 0) == ref["csv_row"], name
            compared_csv += 1
    assert compared_csv > 100


PROTO_CASES = [
    ["-f", "0", "msg", "std_msgs/Header"],
    ["-f", "1", "msg", "std_msgs/Header"],
    ["-f", "0", "msg", "geometry_msgs/Polygon"],
    ["-f", "1", "-H", "msg", "geometry_msgs/Twist"],
    ["-x", "stamp,x", "-f", "0", "msg", "geometry_msgs/PoseStamped"],
    ["-p", "XX", "-f", "0", "msg", "geometry_msgs/Twist"],
    ["-e", "-f", "0", "msg", "sensor_msgs/JointState"],
    ["-f", "0", "srv", "std_srvs/SetBool"],
    ["-x", "data", "msg", "std_msgs/String"],
]

ROSMSG_PROTO = """
import contextlib, io, json, sys
import rosmsg
out = []
for args in json.loads(sys.argv[1]):
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        out.append(rosmsg.rosmsg_cmd_prototype(args))
print(json.dumps(out))
"""


def test_msg_proto_flags_print_what_rosmsg_proto_prints() -> None:
    """-f 0|1, -e, -x, -p and -H, as rosmsg-proto takes them (issue 13, defect 8)."""
    import json

    from tests.support.env import run_system_python

    expected = json.loads(run_system_python(ROSMSG_PROTO, json.dumps(PROTO_CASES)))
    for args, want in zip(PROTO_CASES, expected, strict=True):
        ours = run_cli("msg", "proto", *[a for a in args if a not in ("msg", "srv")])
        assert ours.returncode == 0, ours.stderr
        assert ours.stdout == want + "\n", args
