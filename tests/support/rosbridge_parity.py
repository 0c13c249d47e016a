"""The rosbridge v2 parity recorder: a fixed list of ops sent to a server over a raw websocket,
and its answers, normalised, so that two servers' answers compare field for field.

``record(url)`` needs the graph of ``ros1_nodes/rosbridge_graph.py`` on the server's master.
Its answers against the real rosbridge_server 0.11.17 on ``rosmaster --core`` are kept in
``tests/peers/rosbridge/golden.json``; ``python -m tests.support.rosbridge_parity`` writes
that file again.

Each step sends its ops, then a sentinel (a ``call_service`` of ``/rosapi/topic_type`` with its
own id), and records every message the server sent until the sentinel's answer, in order:
rosbridge handles a client's ops in order, so what an op makes it say arrives before the
sentinel's answer, and what it leaves unsaid is recorded as nothing. Messages of the
subscriptions still open (``publish`` ops of ``/chatter`` and ``/from_web_echo``) are left out
of the steps that do not wait for them.

Normalised: the counter in "hello N", the numeric suffixes of node names, the order of name
lists (a master gives them in any order), and CBOR frames, decoded (``bytes`` as hex).
"""

from __future__ import annotations

import json
import re
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import cbor2
from websockets.sync.client import ClientConnection, connect

from tests.support.load import scaled

GOLDEN = Path(__file__).resolve().parent.parent / "peers" / "rosbridge" / "golden.json"

Message = dict[str, Any]
#: How long a step waits for its answer, on a quiet machine (scaled by the load).
STEP_TIMEOUT = 20.0


class Session:
    """A raw websocket client to a rosbridge v2 server, reading with deadlines."""

    def __init__(self, ws: ClientConnection) -> None:
        self.ws = ws
        #: Messages received and not yet taken by a step, in order.
        self.inbox: list[Message] = []
        self.sentinels = 0

    def send(self, op: Message | str) -> None:
        """One op (a dict as JSON, a str as it is)."""
        self.ws.send(op if isinstance(op, str) else json.dumps(op))

    def _receive(self, deadline: float) -> None:
        left = deadline - time.monotonic()
        if left <= 0:
            raise AssertionError(f"no answer in time; received and not taken: {self.inbox}")
        try:
            frame = self.ws.recv(timeout=left)
        except TimeoutError:
            return
        if isinstance(frame, bytes):
            self.inbox.append({"binary": "cbor", "cbor": _plain(cbor2.loads(frame))})
        else:
            self.inbox.append(json.loads(frame))

    def seen(self, match: Callable[[Message], bool], timeout: float = STEP_TIMEOUT) -> Message:
        """The first message received that ``match``es (left in the inbox)."""
        deadline = time.monotonic() + scaled(timeout)
        while True:
            for message in self.inbox:
                if match(message):
                    return message
            self._receive(deadline)

    def until(self, match: Callable[[Message], bool], timeout: float = STEP_TIMEOUT) -> Message:
        """The first message received that ``match``es (taken out of the inbox)."""
        message = self.seen(match, timeout)
        self.inbox.remove(message)
        return message

    def step(
        self,
        *ops: Message | str,
        wait: Callable[[Message], bool] | None = None,
        keep: Callable[[Message], bool] | None = None,
    ) -> list[Message]:
        """Send ``ops``, then a sentinel; what the server said until the sentinel's answer
        (and, if ``wait`` is given, at least until the first message it matches), in the
        order received. Messages of open subscriptions are left out, but for those ``wait``
        and ``keep`` match.

        rosbridge answers each ``call_service`` from a thread of its own, after ops sent
        later perhaps: the answer of each one with an id is waited for by that id.
        """
        self.drop_stray()
        for op in ops:
            self.send(op)
        wanted = [wait] if wait is not None else []
        wanted += [
            _is("service_response", id=op["id"])
            for op in ops
            if isinstance(op, dict) and op.get("op") == "call_service" and "id" in op
        ]
        firsts = [id(self.seen(match)) for match in wanted]
        self.sentinels += 1
        sentinel = f"sentinel-{self.sentinels}"
        self.send({"op": "call_service", "id": sentinel, "service": "/rosapi/topic_type",
                   "args": {"topic": "/chatter"}})  # fmt: skip
        self.seen(lambda m: m.get("id") == sentinel)
        said = [
            m
            for m in self.inbox
            if m.get("id") != sentinel
            and (id(m) in firsts or not _stray(m) or (keep is not None and keep(m)))
        ]
        self.inbox.clear()
        return said

    def drop_stray(self) -> None:
        """Forget the messages of open subscriptions received so far."""
        self.inbox = [m for m in self.inbox if not _stray(m)]


def _stray(message: Message) -> bool:
    """A message of a subscription still open, not an answer to a step."""
    inner = message.get("cbor", message)
    return isinstance(inner, dict) and inner.get("op") == "publish"


def _plain(value: Any) -> Any:
    """CBOR's decoded value as JSON can hold it: bytes as hex, tags by number."""
    if isinstance(value, bytes):
        return {"bytes": value.hex()}
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_plain(v) for v in value]
    if isinstance(value, cbor2.CBORTag):
        return {"tag": value.tag, "value": _plain(value.value)}
    return value


def _call(service: str, args: Message, id: str) -> Message:
    return {"op": "call_service", "id": id, "service": service, "args": args}


def _is(op: str, **fields: Any) -> Callable[[Message], bool]:
    def match(message: Message) -> bool:
        inner = message.get("cbor", message)
        return (
            isinstance(inner, dict)
            and inner.get("op") == op
            and all(inner.get(k) == v for k, v in fields.items())
        )

    return match


def _echoed(text: str) -> Callable[[Message], bool]:
    def match(message: Message) -> bool:
        return (
            message.get("op") == "publish"
            and message.get("topic") == "/from_web_echo"
            and message.get("msg", {}).get("data") == text
        )

    return match


def record(url: str) -> dict[str, list[Message]]:
    """Every step's answers from the server at ``url``, normalised (see the module's text)."""
    steps: dict[str, list[Message]] = {}
    with connect(url, open_timeout=scaled(STEP_TIMEOUT), max_size=None, compression=None) as ws:
        s = Session(ws)
        chatter = {"op": "subscribe", "id": "sub-json", "topic": "/chatter",
                   "type": "std_msgs/String"}  # fmt: skip
        steps["subscribe /chatter"] = s.step(chatter, wait=_is("publish", topic="/chatter"))
        steps["unsubscribe /chatter"] = s.step(
            {"op": "unsubscribe", "id": "sub-json", "topic": "/chatter"}
        )
        cbor = {"op": "subscribe", "id": "sub-cbor", "topic": "/chatter",
                "type": "std_msgs/String", "compression": "cbor"}  # fmt: skip
        steps["subscribe /chatter cbor"] = s.step(cbor, wait=lambda m: "cbor" in m)
        steps["unsubscribe /chatter cbor"] = s.step(
            {"op": "unsubscribe", "id": "sub-cbor", "topic": "/chatter"}
        )

        steps["advertise /from_web"] = s.step(
            {"op": "advertise", "id": "adv", "topic": "/from_web", "type": "std_msgs/String"},
            {"op": "subscribe", "id": "sub-echo", "topic": "/from_web_echo",
             "type": "std_msgs/String"},
        )  # fmt: skip
        steps["publish /from_web, echoed"] = [_publish_until_echoed(s)]

        steps["call_service /set_flag"] = s.step(
            _call("/set_flag", {"data": True}, "call-set-flag"),
        )
        steps["call_service missing"] = s.step(
            _call("/no_such_service", {"data": True}, "call-missing"),
        )
        steps["call_service /set_flag, bad args"] = s.step(
            _call("/set_flag", {"dta": True}, "call-bad-args"),
        )
        steps["advertise_service /web_setbool, called by rospy"] = _web_service(s)

        rosapi = [
            ("rosapi topics", "/rosapi/topics", {}),
            ("rosapi topics, no leading slash", "rosapi/topics", {}),
            ("rosapi topic_type", "/rosapi/topic_type", {"topic": "/chatter"}),
            ("rosapi topic_type, unknown topic", "/rosapi/topic_type", {"topic": "/nope"}),
            ("rosapi services", "/rosapi/services", {}),
            ("rosapi service_type", "/rosapi/service_type", {"service": "/set_flag"}),
            ("rosapi nodes", "/rosapi/nodes", {}),
            ("rosapi get_param", "/rosapi/get_param", {"name": "/rbs_test/greeting"}),
            ("rosapi set_param", "/rosapi/set_param",
             {"name": "/rbs_test/from_web", "value": json.dumps({"a": 1, "b": [1.5, "x"]})}),
            ("rosapi get_param, as set", "/rosapi/get_param", {"name": "/rbs_test/from_web"}),
            ("rosapi get_param, missing", "/rosapi/get_param", {"name": "/rbs_test/none"}),
            ("rosapi message_details", "/rosapi/message_details",
             {"type": "geometry_msgs/PoseStamped"}),
        ]  # fmt: skip
        for n, (name, service, args) in enumerate(rosapi):
            steps[name] = s.step(_call(service, args, f"rosapi-{n}"))

        steps["malformed JSON"] = s.step('{"op": "call_service", "id": "malformed"')
        steps["unknown op"] = s.step({"op": "no_such_op", "id": "unknown-op"})
        steps["no op"] = s.step({"id": "no-op", "topic": "/chatter"})
        steps["publish, no such field"] = _publish_bad(s, "pub-bad-field", {"dta": "x"})
        steps["publish, wrong field type"] = _publish_bad(s, "pub-bad-type", {"data": 5})
        steps["subscribe, unknown type"] = s.step(
            {"op": "subscribe", "id": "sub-bad-type", "topic": "/nowhere",
             "type": "no_pkg/NoType"}
        )  # fmt: skip
        steps["still answers"] = s.step(_call("/set_flag", {"data": False}, "call-after"))
    return normalise(steps)


#: The echo of the first publish, sent again until rospy has connected: may come late.
_ECHO_OF_FIRST = {
    "op": "publish",
    "topic": "/from_web_echo",
    "msg": {"data": "rospy got: hi from the parity recorder"},
}


def _publish_until_echoed(s: Session) -> Message:
    """Publish to /from_web until rospy's echo arrives (its subscriber connects in its time)."""
    deadline = time.monotonic() + scaled(STEP_TIMEOUT)
    text = _ECHO_OF_FIRST["msg"]["data"]
    while time.monotonic() < deadline:
        s.send({"op": "publish", "id": "pub", "topic": "/from_web",
                "msg": {"data": "hi from the parity recorder"}})  # fmt: skip
        try:
            return s.until(_echoed(text), 0.25)
        except AssertionError:
            continue
    raise AssertionError(f"rospy never echoed /from_web; received: {s.inbox[-5:]}")


def _publish_bad(s: Session, id: str, msg: Message) -> list[Message]:
    """A publish of ``msg`` to /from_web (std_msgs/String), then a good one: what the server
    said, with the echoes before the good one's (a bad message published would be one)."""
    good = {"op": "publish", "topic": "/from_web", "msg": {"data": f"after {id}"}}
    return s.step(
        {"op": "publish", "id": id, "topic": "/from_web", "msg": msg},
        good,
        wait=_echoed(f"rospy got: after {id}"),
        keep=lambda m: m.get("topic") == "/from_web_echo" and m != _ECHO_OF_FIRST,
    )


def _web_service(s: Session) -> list[Message]:
    """advertise_service /web_setbool; rospy calls it; the client's answer reaches rospy."""
    said = s.step({"op": "advertise_service", "id": "adv-srv", "service": "/web_setbool",
                   "type": "std_srvs/SetBool"})  # fmt: skip
    s.send({"op": "publish", "topic": "/from_web", "msg": {"data": "call /web_setbool"}})
    request = s.until(_is("call_service", service="/web_setbool"))
    s.send({"op": "service_response", "id": request["id"], "service": "/web_setbool",
            "values": {"success": True, "message": "web says ok"}, "result": True})  # fmt: skip
    echo = s.until(_echoed("web service said: web says ok"))
    said += [request, echo]
    said += s.step({"op": "unadvertise_service", "id": "unadv-srv", "service": "/web_setbool"})
    return said


#: An anonymous node's numbers, at the end of its name or of the node part of a service's.
NODE_SUFFIX = re.compile(r"(_\d+)+(?=$|/get_loggers$|/set_logger_level$)")
HELLO = re.compile(r"^hello \d+$")
#: Lists whose order a master does not fix.
NAME_LISTS = {"topics", "services", "nodes", "names", "publishers", "subscribers", "providers"}


def normalise(value: Any, key: str = "") -> Any:
    """``value`` with its volatile parts replaced (see the module's text)."""
    if isinstance(value, dict):
        if isinstance(value.get("topics"), list) and isinstance(value.get("types"), list):
            pairs = sorted(zip(value["topics"], value["types"], strict=False))
            value = {**value, "topics": [t for t, _ in pairs], "types": [t for _, t in pairs]}
            return {k: v if k in ("topics", "types") else normalise(v, k) for k, v in value.items()}
        return {k: normalise(v, k) for k, v in value.items()}
    if isinstance(value, list):
        items = [normalise(v, key) for v in value]
        return (
            sorted(items) if key in NAME_LISTS and all(isinstance(i, str) for i in items) else items
        )
    if isinstance(value, str):
        if HELLO.match(value):
            return "hello <n>"
        if value.startswith("/") and NODE_SUFFIX.search(value):
            return NODE_SUFFIX.sub("_<n>", value)
    return value


#: Each server's own nodes, topics and services, left out of the answers that list the graph:
#: the graph compared is the one both serve.
OWN = {
    "rosbridge_server": re.compile(
        r"^/(rosapi|rosbridge_websocket)(_<n>)?(/get_loggers|/set_logger_level)?$"
        r"|^/(client_count|connected_clients)$"
    ),
    "rostools": re.compile(r"^/(rostools_bridge|rosapi)(_<n>)?(/get_loggers|/set_logger_level)?$"),
}


def without_own(answers: dict[str, list[Message]], server: str) -> dict[str, list[Message]]:
    """``answers`` with ``server``'s own names out of every name list (and their types)."""
    own = OWN[server]

    def strip(value: Any) -> Any:
        if isinstance(value, dict):
            if isinstance(value.get("topics"), list) and isinstance(value.get("types"), list):
                pairs = [p for p in zip(value["topics"], value["types"], strict=False)
                         if not own.match(p[0])]  # fmt: skip
                value = {**value, "topics": [t for t, _ in pairs], "types": [t for _, t in pairs]}
            return {k: strip(v) for k, v in value.items()}
        if isinstance(value, list):
            return [strip(v) for v in value if not (isinstance(v, str) and own.match(v))]
        return value

    return {step: strip(said) for step, said in answers.items()}


def differences(golden: Any, ours: Any, path: str = "") -> list[str]:
    """Where ``ours`` differs from ``golden``: one line per field (keys' order aside)."""
    if isinstance(golden, dict) and isinstance(ours, dict):
        out = []
        for k in golden.keys() | ours.keys():
            where = f"{path}/{k}"
            if k not in ours:
                out.append(f"{where}: missing (golden: {json.dumps(golden[k])[:200]})")
            elif k not in golden:
                out.append(f"{where}: extra ({json.dumps(ours[k])[:200]})")
            else:
                out += differences(golden[k], ours[k], where)
        return sorted(out)
    if isinstance(golden, list) and isinstance(ours, list):
        if len(golden) != len(ours):
            return [f"{path}: {len(ours)} items, golden {len(golden)}: "
                    f"{json.dumps(ours)[:300]} vs {json.dumps(golden)[:300]}"]  # fmt: skip
        return [
            d
            for n, (g, o) in enumerate(zip(golden, ours, strict=True))
            for d in differences(g, o, f"{path}[{n}]")
        ]
    if golden != ours or type(golden) is not type(ours):
        return [f"{path}: {json.dumps(ours)[:200]}, golden {json.dumps(golden)[:200]}"]
    return []


def main() -> None:
    """Write the golden file from the real rosbridge_server on ``rosmaster --core``."""
    import tempfile

    from tests.support.rosbridge import (
        rosbridge_graph,
        rosbridge_missing,
        start_rosbridge,
        start_rosmaster,
    )

    if reason := rosbridge_missing():
        raise SystemExit(reason)
    with tempfile.TemporaryDirectory() as scratch:
        home = Path(scratch)
        master, uri = start_rosmaster(home)
        try:
            with rosbridge_graph(uri, home):
                bridge = start_rosbridge(uri, home)
                try:
                    answers = record(bridge.url)
                finally:
                    bridge.stop()
        finally:
            master.stop()
    GOLDEN.write_text(json.dumps(answers, indent=1) + "\n")
    print(f"wrote {GOLDEN.name}: {len(answers)} steps")


if __name__ == "__main__":
    main()
