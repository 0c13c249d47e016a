"""Answers from the real ROS 1 Python stack, for differential tests.

Run with the system interpreter (``/usr/bin/python3``), where Debian's genmsg, genpy, rosmsg
and rostopic live. Reads one JSON request per line on stdin and writes one JSON answer per line.
Nothing of rostools is imported here: this is the reference side.
"""

from __future__ import annotations

import json
import os
import sys
import traceback


def op_types(req):
    import rosmsg
    import rospkg

    rospack = rospkg.RosPack()
    out = {}
    for mode, kind in ((rosmsg.MODE_MSG, "msg"), (rosmsg.MODE_SRV, "srv")):
        for pkg, path in sorted(rosmsg.iterate_packages(rospack, mode)):
            for name in rosmsg._list_types(path, kind, mode):
                out[f"{pkg}/{name}"] = kind
    return out


def _md5(kind, type_name):
    import genmsg
    import genmsg.gentools
    import rospkg

    rospack = rospkg.RosPack()
    search = {}
    for p in rospack.list():
        base = rospack.get_path(p)
        search[p] = [os.path.join(base, "msg")]
    context = genmsg.MsgContext.create_default()
    if kind == "msg":
        spec = genmsg.load_msg_by_type(context, type_name, search)
    else:
        srv_search = {p: [os.path.join(rospack.get_path(p), "srv")] for p in rospack.list()}
        spec = genmsg.load_srv_by_type(context, type_name, srv_search)
    genmsg.load_depends(context, spec, search)
    md5 = genmsg.gentools.compute_md5(context, spec)
    full = genmsg.gentools.compute_full_text(context, spec) if kind == "msg" else None
    return md5, full


def op_describe(req):
    import rosmsg

    kind, type_name = req["kind"], req["type"]
    if kind == "msg":
        show = rosmsg.get_msg_text(type_name)
        raw = rosmsg.get_msg_text(type_name, raw=True)
    else:
        show = rosmsg.get_srv_text(type_name)
        raw = rosmsg.get_srv_text(type_name, raw=True)
    md5, full = _md5(kind, type_name)
    return {"show": show, "raw": raw, "md5": md5, "full": full}


def op_custom(req):
    """md5 and full text of types in a package folder, by genmsg alone."""
    import genmsg
    import genmsg.gentools

    search = {p: [os.path.join(d, "msg")] for p, d in req["packages"].items()}
    srv_search = {p: [os.path.join(d, "srv")] for p, d in req["packages"].items()}
    context = genmsg.MsgContext.create_default()
    if req["kind"] == "msg":
        spec = genmsg.load_msg_by_type(context, req["type"], search)
    else:
        spec = genmsg.load_srv_by_type(context, req["type"], srv_search)
    genmsg.load_depends(context, spec, search)
    full = genmsg.gentools.compute_full_text(context, spec) if req["kind"] == "msg" else None
    return {"md5": genmsg.gentools.compute_md5(context, spec), "full": full}


def _cls(type_name):
    import roslib.message

    cls = roslib.message.get_message_class(type_name)
    if cls is None:
        raise LookupError(f"no python class for {type_name}")
    return cls


def op_fill(req):
    """Serialize a message filled from YAML the way rostopic pub fills it."""
    import genpy.message
    import yaml

    msg = _cls(req["type"])()
    genpy.message.fill_message_args(msg, [yaml.safe_load(a) for a in req["args"]])
    from io import BytesIO

    buf = BytesIO()
    msg.serialize(buf)
    return buf.getvalue().hex()


def op_echo(req):
    """What rostopic echo prints for these bytes, as text and as -p CSV."""
    import rostopic

    msg = _cls(req["type"])()
    msg.deserialize(bytes.fromhex(req["hex"]))
    nostr, noarr = req.get("nostr", False), req.get("noarr", False)
    transform = rostopic.create_value_transform(nostr, noarr) if (nostr or noarr) else None
    echo = rostopic.CallbackEcho(None, None)
    text = echo.custom_strify_message(
        msg, value_transform=transform, fixed_numeric_width=req.get("width")
    )
    field_filter = rostopic.create_field_filter(nostr, noarr)
    header = "%" + rostopic._str_plot_fields(msg, "field", field_filter)
    import genpy

    row = rostopic._str_plot(msg, current_time=genpy.Time(0, 0), field_filter=field_filter)
    return {"text": text, "csv_header": header, "csv_row": row}


OPS = {
    "types": op_types,
    "describe": op_describe,
    "custom": op_custom,
    "fill": op_fill,
    "echo": op_echo,
}


def main():
    for line in sys.stdin:
        req = json.loads(line)
        try:
            answer = {"ok": OPS[req["op"]](req)}
        except Exception as err:  # noqa: BLE001 - one bad type must not end the run
            answer = {"error": f"{type(err).__name__}: {err}", "trace": traceback.format_exc()}
        sys.stdout.write(json.dumps(answer) + "\n")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
