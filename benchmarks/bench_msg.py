"""The type system: ``msg md5`` start-up, and echo formatting throughput."""

from __future__ import annotations

import json
import subprocess

from benchmarks.common import SYSTEM_PYTHON, Result, have, rostools_cmd, throughput, time_commands

GENPY_ECHO = r"""
import time, sys
from geometry_msgs.msg import PoseStamped
from rostopic import CallbackEcho
m = PoseStamped(); m.header.frame_id = 'map'; m.pose.position.x = 1.5
from io import BytesIO
b = BytesIO(); m.serialize(b); wire = b.getvalue()
echo = CallbackEcho(None, None)
n = 0; start = time.perf_counter()
while time.perf_counter() - start < 2.0:
    for _ in range(1000):
        x = PoseStamped(); x.deserialize(wire); echo.custom_strify_message(x)
    n += 1000
print(n / (time.perf_counter() - start))
"""


def bench_md5_startup() -> Result:
    ours = [*rostools_cmd(), "msg", "md5", "std_msgs/String"]
    theirs = ["rosmsg", "md5", "std_msgs/String"]
    if not have("rosmsg"):
        t = time_commands({"ours": ours})
        return Result(
            "msg md5 std_msgs/String (wall, whole process)",
            "ms",
            t["ours"] * 1e3,
            None,
            "<= 0.5x rosmsg",
            None,
            "rosmsg not installed",
        )
    t = time_commands({"ours": ours, "theirs": theirs})
    ratio = t["ours"] / t["theirs"]
    return Result(
        "msg md5 std_msgs/String (wall, whole process)",
        "ms",
        t["ours"] * 1e3,
        t["theirs"] * 1e3,
        "<= 0.5x rosmsg",
        ratio <= 0.5,
    )


def bench_echo_format() -> Result:
    from rostools.msgs.codec import Codec
    from rostools.msgs.store import BuiltinSource, TypeStore
    from rostools.msgs.text import formatter, message_type

    codec = Codec.of(TypeStore([BuiltinSource()]))
    msg = codec.message_class("geometry_msgs/PoseStamped")()
    msg.header.frame_id = "map"  # type: ignore[attr-defined]
    msg.pose.position.x = 1.5  # type: ignore[attr-defined]
    wire = msg.serialize()
    decode = codec.decoder("geometry_msgs/PoseStamped")
    fmt = formatter(codec, message_type("geometry_msgs/PoseStamped"))

    def batch() -> int:
        for _ in range(1000):
            fmt(decode(wire, 0)[0])
        return 1000

    ours = throughput(batch)
    theirs = None
    if have("rostopic"):
        out = subprocess.run(
            [SYSTEM_PYTHON, "-c", GENPY_ECHO], capture_output=True, text=True, check=True
        )
        theirs = float(json.loads(out.stdout.strip()))
    return Result(
        "echo decode+format geometry_msgs/PoseStamped",
        "msgs/s",
        ours,
        theirs,
        ">= 100000 msgs/s",
        ours >= 100_000,
        "theirs: genpy deserialize + rostopic strify",
    )


BENCHMARKS = {"msg_md5_startup": bench_md5_startup, "echo_format": bench_echo_format}
