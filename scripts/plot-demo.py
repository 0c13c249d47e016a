#!/usr/bin/env python3
"""Write the demo bag of docs/plot.md and draw ``docs/bag-plot.png`` from it.

A robot drives for 30 s: ``/cmd_vel`` (10 Hz) steps its speed and turn rate, ``/odom``
(50 Hz) integrates them, with a little noise. The picture is what ``bag plot -o`` draws.

Usage: python scripts/plot-demo.py [BAG]   (default: a temporary file, deleted afterwards)
"""

from __future__ import annotations

import math
import random
import subprocess
import sys
import tempfile
from pathlib import Path

from rostools.bag.formats.access import open_writer
from rostools.msgs.codec import Codec
from rostools.msgs.message import Time
from rostools.msgs.store import TypeStore

ROOT = Path(__file__).resolve().parent.parent
IMAGE = ROOT / "docs" / "bag-plot.png"
START = 1_700_000_000.0
FIELDS = ["/odom/pose/pose/position/x", "/odom/pose/pose/position/y", "/cmd_vel/linear/x"]


def command(t: float) -> tuple[float, float]:
    """Speed (m/s) and turn rate (rad/s) asked for at ``t`` seconds."""
    speed = 0.0 if t < 2 else 0.5 if t < 12 else 1.0 if t < 22 else 0.2
    return speed, 0.3 if 6 <= t < 18 else -0.2 if t >= 22 else 0.0


def write_bag(path: Path) -> None:
    """30 s of /cmd_vel and /odom."""
    store = TypeStore.default()
    codec = Codec.of(store)
    writer = open_writer(path, format="bag", overwrite=True)
    conns = {
        topic: writer.add_connection(topic, kind, store.md5(kind), store.full_text(kind),
                                     callerid="/robot")
        for topic, kind in (("/cmd_vel", "geometry_msgs/Twist"), ("/odom", "nav_msgs/Odometry"))
    }  # fmt: skip
    rng = random.Random(7)
    x = y = heading = 0.0
    for step in range(30 * 50):
        t = step / 50
        speed, turn = command(t)
        heading += turn / 50
        x += speed * math.cos(heading) / 50
        y += speed * math.sin(heading) / 50
        stamp = int((START + t) * 1e9)
        if step % 5 == 0:
            twist = codec.message_class("geometry_msgs/Twist")()
            twist.linear.x, twist.angular.z = speed, turn
            writer.write(conns["/cmd_vel"], stamp, codec.serialize(twist))
        odom = codec.message_class("nav_msgs/Odometry")()
        odom.header.stamp = Time.from_nsec(stamp)
        odom.header.frame_id = "odom"
        odom.pose.pose.position.x = x + rng.gauss(0, 0.01)
        odom.pose.pose.position.y = y + rng.gauss(0, 0.01)
        writer.write(conns["/odom"], stamp, codec.serialize(odom))
    writer.close()


def main() -> int:
    with tempfile.TemporaryDirectory() as tmp:
        bag = Path(sys.argv[1]) if len(sys.argv) > 1 else Path(tmp) / "demo.bag"
        write_bag(bag)
        IMAGE.parent.mkdir(exist_ok=True)
        rostools = [sys.executable, "-m", "rostools", "bag", "plot", str(bag), *FIELDS]
        subprocess.run([*rostools, "-o", str(IMAGE)], check=True)
        print(f"wrote {IMAGE.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
