"""Run on the system python (real ROS 1): what ``rosbag.Bag`` makes of each bag on argv.

Prints one JSON object: path -> {"stream": [[topic, t_ns, md5], ...], "info": yaml dict,
"headers": [[topic, header], ...]} or {"error": "..."}.
"""

import hashlib
import json
import sys

import rosbag
import yaml

out = {}
for path in sys.argv[1:]:
    try:
        bag = rosbag.Bag(path)
        stream = [
            [topic, t.to_nsec(), hashlib.md5(raw[1]).hexdigest()]
            for topic, raw, t in bag.read_messages(raw=True)
        ]
        headers = [
            [c.topic, {k: v.decode("utf-8", "replace") for k, v in c.header.items()}]
            for c in sorted(bag._connections.values(), key=lambda c: c.id)
        ]
        out[path] = {
            "stream": stream,
            "info": yaml.safe_load(bag._get_yaml_info()),
            "headers": headers,
        }
        bag.close()
    except Exception as err:  # noqa: BLE001 - report what rosbag says, whatever it is
        out[path] = {"error": f"{type(err).__name__}: {err}"}
print(json.dumps(out))
