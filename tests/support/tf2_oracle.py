"""Answers from tf2's own ``BufferCore`` (``tf2_py``), for differential tests of the buffer.

Run with the system interpreter (``/usr/bin/python3``), where Debian's tf2_py and rosbag
live. Reads one JSON document on stdin: ``{"cache_ns": N, "ops": [...]}``, each op one of
``["set", parent, child, stamp_ns, [tx, ty, tz, qx, qy, qz, qw], static, authority]``,
``["lookup", target, source, time_ns]``, ``["bag", path]`` (every ``/tf`` and
``/tf_static`` message of a bag, in record order, read by the ``rosbag`` module, each from its
connection's callerid) and ``["yaml"]``. Writes one JSON list: per lookup ``{"ok": [stamp_ns,
[seven values]]}`` or ``{"error": kind, "message": text}``; per yaml ``{"yaml": text}``, the
buffer's ``allFramesAsYAML`` (what view_frames draws). Nothing of rostools is imported here:
this is the reference side.
"""

from __future__ import annotations

import json
import sys


def main():
    import rospy
    import tf2_py
    from geometry_msgs.msg import TransformStamped

    doc = json.load(sys.stdin)
    buffer = tf2_py.BufferCore(rospy.Duration(0, doc["cache_ns"]))
    answers = []

    def time(ns):
        return rospy.Time(ns // 1_000_000_000, ns % 1_000_000_000)

    for op in doc["ops"]:
        if op[0] == "set":
            _, parent, child, stamp, seven, static, authority = op
            m = TransformStamped()
            m.header.frame_id, m.child_frame_id, m.header.stamp = parent, child, time(stamp)
            t, q = m.transform.translation, m.transform.rotation
            t.x, t.y, t.z, q.x, q.y, q.z, q.w = seven
            (buffer.set_transform_static if static else buffer.set_transform)(m, authority)
        elif op[0] == "bag":
            import rosbag

            with rosbag.Bag(op[1]) as bag:
                topics = ["/tf", "/tf_static", "tf"]
                for topic, msg, _, conn in bag.read_messages(topics, return_connection_header=True):
                    who = conn.get("callerid", b"")  # rosbag hands the header over as bytes
                    who = who.decode() if isinstance(who, bytes) else who
                    for m in msg.transforms:
                        if topic == "/tf_static":
                            buffer.set_transform_static(m, who)
                        else:
                            buffer.set_transform(m, who)
        elif op[0] == "yaml":
            answers.append({"yaml": buffer.all_frames_as_yaml()})
        else:
            _, target, source, at = op
            try:
                r = buffer.lookup_transform_core(target, source, time(at))
            except tf2_py.TransformException as err:
                answers.append({"error": type(err).__name__, "message": str(err)})
                continue
            t, q = r.transform.translation, r.transform.rotation
            stamp = r.header.stamp.secs * 1_000_000_000 + r.header.stamp.nsecs
            answers.append({"ok": [stamp, [t.x, t.y, t.z, q.x, q.y, q.z, q.w]]})
    json.dump(answers, sys.stdout)


if __name__ == "__main__":
    main()
