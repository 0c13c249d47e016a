#!/usr/bin/env python3
"""Regenerate ``rostools/msgs/data/noetic.json``, the built-in type table.

Messages come from rosbags' Noetic store; the text of each type is the first section of
rosbags' ``generate_msgdef`` (fully qualified names, no comments), ending in a newline like a
``.msg`` file. rosbags has no services, so the common Noetic services are written out here.
``tests/unit/test_builtin_table.py`` fails when the checked-in table is stale.

Usage: python scripts/gen-builtin-types.py [--check]
"""

from __future__ import annotations

import json
import re
import sys
from pathlib import Path

TABLE = Path(__file__).resolve().parent.parent / "rostools" / "msgs" / "data" / "noetic.json"

# The service interfaces of the Noetic packages people call most. Field lists only: the md5
# depends on nothing else, and tests check each md5 against genmsg or a published value.
SERVICES = {
    "std_srvs/Empty": "---\n",
    "std_srvs/Trigger": "---\nbool success\nstring message\n",
    "std_srvs/SetBool": "bool data\n---\nbool success\nstring message\n",
    "roscpp/Empty": "---\n",
    "roscpp/GetLoggers": "---\nroscpp/Logger[] loggers\n",
    "roscpp/SetLoggerLevel": "string logger\nstring level\n---\n",
    "sensor_msgs/SetCameraInfo": (
        "sensor_msgs/CameraInfo camera_info\n---\nbool success\nstring status_message\n"
    ),
    "nav_msgs/GetMap": "---\nnav_msgs/OccupancyGrid map\n",
    "nav_msgs/GetPlan": (
        "geometry_msgs/PoseStamped start\ngeometry_msgs/PoseStamped goal\nfloat32 tolerance\n"
        "---\nnav_msgs/Path plan\n"
    ),
    "nav_msgs/SetMap": (
        "nav_msgs/OccupancyGrid map\ngeometry_msgs/PoseWithCovarianceStamped initial_pose\n"
        "---\nbool success\n"
    ),
    "nav_msgs/LoadMap": (
        "string map_url\n---\nuint8 RESULT_SUCCESS=0\nuint8 RESULT_MAP_DOES_NOT_EXIST=1\n"
        "uint8 RESULT_INVALID_MAP_DATA=2\nuint8 RESULT_INVALID_MAP_METADATA=3\n"
        "uint8 RESULT_UNDEFINED_FAILURE=255\nnav_msgs/OccupancyGrid map\nuint8 result\n"
    ),
    "diagnostic_msgs/AddDiagnostics": "string load_namespace\n---\nbool success\nstring message\n",
    "diagnostic_msgs/SelfTest": (
        "---\nstring id\nbyte passed\ndiagnostic_msgs/DiagnosticStatus[] status\n"
    ),
    "dynamic_reconfigure/Reconfigure": (
        "dynamic_reconfigure/Config config\n---\ndynamic_reconfigure/Config config\n"
    ),
    "rospy_tutorials/AddTwoInts": "int64 a\nint64 b\n---\nint64 sum\n",
    "roscpp_tutorials/TwoInts": "int64 a\nint64 b\n---\nint64 sum\n",
}

# tf's messages, which rosbags' Noetic store lacks: `rostools tf` reads /tf and /tf_static, and
# tf1's tfMessage is the same bytes as tf2's TFMessage (tf/tfMessage in old bags).
TF_MESSAGES = {
    "tf2_msgs/TFMessage": "geometry_msgs/TransformStamped[] transforms\n",
    "tf/tfMessage": "geometry_msgs/TransformStamped[] transforms\n",
}

# rosapi 0.11.17's interfaces (rosbridge_suite), which `rostools bridge` serves as ROS services
# (web/rosapi.py): rosapi/TypeDef and its 25 services, as in its msg/ and srv/ files.
ROSAPI_MESSAGES = {
    "rosapi/TypeDef": (
        "string type\nstring[] fieldnames\nstring[] fieldtypes\nint32[] fieldarraylen\n"
        "string[] examples\nstring[] constnames\nstring[] constvalues\n"
    ),
}
ROSAPI_SERVICES = {
    "rosapi/DeleteParam": "string name\n---\n",
    "rosapi/GetActionServers": "---\nstring[] action_servers\n",
    "rosapi/GetParam": "string name\nstring default\n---\nstring value\n",
    "rosapi/GetParamNames": "---\nstring[] names\n",
    "rosapi/GetTime": "---\ntime time\n",
    "rosapi/HasParam": "string name\n---\nbool exists\n",
    "rosapi/MessageDetails": "string type\n---\nrosapi/TypeDef[] typedefs\n",
    "rosapi/NodeDetails": (
        "string node\n---\nstring[] subscribing\nstring[] publishing\nstring[] services\n"
    ),
    "rosapi/Nodes": "---\nstring[] nodes\n",
    "rosapi/Publishers": "string topic\n---\nstring[] publishers\n",
    "rosapi/SearchParam": "string name\n---\nstring global_name\n",
    "rosapi/ServiceHost": "string service\n---\nstring host\n",
    "rosapi/ServiceNode": "string service\n---\nstring node\n",
    "rosapi/ServiceProviders": "string service\n---\nstring[] providers\n",
    "rosapi/ServiceRequestDetails": "string type\n---\nrosapi/TypeDef[] typedefs\n",
    "rosapi/ServiceResponseDetails": "string type\n---\nrosapi/TypeDef[] typedefs\n",
    "rosapi/ServiceType": "string service\n---\nstring type\n",
    "rosapi/Services": "---\nstring[] services\n",
    "rosapi/ServicesForType": "string type\n---\nstring[] services\n",
    "rosapi/SetParam": "string name\nstring value\n---\n",
    "rosapi/Subscribers": "string topic\n---\nstring[] subscribers\n",
    "rosapi/TopicType": "string topic\n---\nstring type\n",
    "rosapi/Topics": "---\nstring[] topics\nstring[] types\n",
    "rosapi/TopicsAndRawTypes": (
        "---\nstring[] topics\nstring[] types\nstring[] typedefs_full_text\n"
    ),
    "rosapi/TopicsForType": "string type\n---\nstring[] topics\n",
}


def build() -> str:
    """The table as JSON text."""
    from rosbags.typesys import Stores, get_typestore

    store = get_typestore(Stores.ROS1_NOETIC)
    msgs: dict[str, str] = {}
    for name in sorted(store.fielddefs):
        package, _, short = name.split("/")
        if package == "builtin_interfaces":  # rosbags' stand-ins for ROS 1 time/duration
            continue
        text, _ = store.generate_msgdef(name)
        first = re.split(r"\n={80}\n", text)[0].rstrip("\n")
        msgs[f"{package}/{short}"] = first + "\n"
    msgs.update(ROSAPI_MESSAGES)
    msgs.update(TF_MESSAGES)
    services = SERVICES | ROSAPI_SERVICES
    table = {"msg": dict(sorted(msgs.items())), "srv": dict(sorted(services.items()))}
    return json.dumps(table, indent=0, sort_keys=True) + "\n"


def main() -> int:
    """Write the table, or with --check report whether it is current."""
    text = build()
    if "--check" in sys.argv[1:]:
        current = TABLE.read_text() if TABLE.exists() else ""
        if current != text:
            print(f"{TABLE.name} is stale: run scripts/gen-builtin-types.py", file=sys.stderr)
            return 1
        return 0
    TABLE.parent.mkdir(parents=True, exist_ok=True)
    TABLE.write_text(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
