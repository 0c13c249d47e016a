"""Run on the system python (real ROS 1): every message of each bag on argv, as plain values.

Writes one pickle to stdout: path -> {(topic, md5sum): [(t_ns, value), ...]} or
{"error": "..."}. A value is a message as a dict of its fields in order, ``time`` and
``duration`` as int nanoseconds (genpy's ``to_nsec``), ``uint8[]``/``char[]`` as bytes,
arrays as lists, an empty message inside another as the tables one member of 0: what
``tests/support/tables.py`` compares Arrow rows with.
"""

import pickle
import sys

import genpy
import rosbag


def plain(value, nested=False):
    if isinstance(value, genpy.Message):
        if nested and not value.__slots__:  # the tables' one member of a nested empty message
            return {"structure_needs_at_least_one_member": 0}
        return {name: plain(getattr(value, name), True) for name in value.__slots__}
    if isinstance(value, (genpy.Time, genpy.Duration)):
        return value.to_nsec()
    if isinstance(value, (list, tuple)):
        return [plain(v, nested) for v in value]
    return value


out = {}
for path in sys.argv[1:]:
    try:
        tables = {}
        with rosbag.Bag(path) as bag:
            for topic, msg, t, header in bag.read_messages(return_connection_header=True):
                key = (topic, header["md5sum"].decode())
                tables.setdefault(key, []).append((t.to_nsec(), plain(msg)))
        out[path] = tables
    except Exception as err:  # noqa: BLE001 - report what rosbag says, whatever it is
        out[path] = {"error": f"{type(err).__name__}: {err}"}
sys.stdout.buffer.write(pickle.dumps(out, protocol=4))
