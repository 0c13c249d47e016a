"""Answers from tf2's own ``BufferCore`` (``tf2_py``), for differential tests of the buffer.

Run with the system interpreter (``/usr/bin/python3``), where Debian's tf2_py and rosbag
live. Reads one JSON document on stdin: ``{"cache_ns": N, "ops": [...]}``, each op one of
``["set", parent, child, stamp_ns, [tx, ty, tz, qx, qy, qz, qw], static, authority]``,
``["lookup", target, source, time_ns]``, ``["shift", offset_ns]`` (every later time is
handed to tf2_py less ``offset_ns``: see ``time``) and ``["bag", path, until_ns]`` (the ``/tf`` and
``/tf_static`` messages of a bag recorded up to ``until_ns``, all when it is None, in record
order, read by the ``rosbag`` module, each from its connection's callerid), ``["yaml"]`` and
``["reset", cache_ns]`` (a new, empty buffer, unshifted: many cases in one run).
Writes one JSON list: per lookup ``{"ok": [stamp_ns, [seven values]]}`` or ``{"error": kind,
"message": text}``; per yaml ``{"yaml": text}``, the buffer's ``allFramesAsYAML`` (what
view_frames draws). Nothing of rostools is imported here: this is the reference side.
"""

from __future__ import annotations

import json
import sys


def _messages(path):
    """The TF messages of a bag as ``(topic, message, record time ns, callerid)``, in record
    order."""
    import rosbag

    bag = rosbag.Bag(path)

    def read():
        topics = ["/tf", "/tf_static", "tf"]
        for topic, msg, t, conn in bag.read_messages(topics, return_connection_header=True):
            who = conn.get("callerid", b"")  # rosbag hands the header over as bytes
            who = who.decode() if isinstance(who, bytes) else who
            yield topic, msg, t.secs * 1_000_000_000 + t.nsecs, who

    return {"it": read(), "next": None}


def stamp_of_msg(t):
    """A message's stamp in ns."""
    return t.secs * 1_000_000_000 + t.nsecs


def main():
    import rospy
    import tf2_py
    from geometry_msgs.msg import TransformStamped

    doc = json.load(sys.stdin)
    buffer = tf2_py.BufferCore(rospy.Duration(0, doc["cache_ns"]))
    answers = []
    bags = {}

    shift = [0]

    def time(ns):
        # tf2_py passes times as float seconds, exact to the ns only near 0: every time is
        # moved by the same offset on the way in and back on the way out. tf2 computes with
        # differences of times, so its answers do not change; only the rounding goes.
        if ns:
            ns -= shift[0]
        return rospy.Time(ns // 1_000_000_000, ns % 1_000_000_000)

    def stamp_of(t):
        ns = t.secs * 1_000_000_000 + t.nsecs
        return ns + shift[0] if ns else 0

    for op in doc["ops"]:
        if op[0] == "reset":
            buffer = tf2_py.BufferCore(rospy.Duration(0, op[1]))
            shift[0] = 0
        elif op[0] == "shift":
            shift[0] = op[1]
        elif op[0] == "set":
            _, parent, child, stamp, seven, static, authority = op
            m = TransformStamped()
            stamp = 0 if static else stamp  # a static stamp is never read: tf2 drops it
            m.header.frame_id, m.child_frame_id, m.header.stamp = parent, child, time(stamp)
            t, q = m.transform.translation, m.transform.rotation
            t.x, t.y, t.z, q.x, q.y, q.z, q.w = seven
            (buffer.set_transform_static if static else buffer.set_transform)(m, authority)
        elif op[0] == "bag":
            # ["bag", path, until_ns]: feed the messages recorded up to until_ns (None: all)
            path, until = op[1], op[2] if len(op) > 2 else None
            if path not in bags:
                bags[path] = _messages(path)
            reader = bags[path]
            while True:
                if reader["next"] is None:
                    reader["next"] = next(reader["it"], False)
                item = reader["next"]
                if item is False or (until is not None and item[2] > until):
                    break
                reader["next"] = None
                topic, msg, stamp, who = item
                for m in msg.transforms:
                    static = topic == "/tf_static"  # its stamp is never read: tf2 drops it
                    m.header.stamp = time(0 if static else stamp_of_msg(m.header.stamp))
                    if static:
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
            answers.append({"ok": [stamp_of(r.header.stamp), [t.x, t.y, t.z, q.x, q.y, q.z, q.w]]})
    json.dump(answers, sys.stdout)


if __name__ == "__main__":
    main()
