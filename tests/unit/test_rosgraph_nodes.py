"""The pure parts of ``rostools.rosgraph.nodeapi``: no sockets."""

from __future__ import annotations

import pytest

from rostools.errors import NotFoundError
from rostools.rosgraph.cleanup import Unregistration, plan_cleanup
from rostools.rosgraph.machines import machines, nodes_on_machine
from rostools.rosgraph.nodeapi import BusConnection
from rostools.rosgraph.state import SystemState, build_graph

# getSystemState of a real roscore with the rospy talker and listener of tests/support
# (captured), plus a node in a namespace that provides a service.
RAW_STATE = [
    [
        ["/rosout_agg", ["/rosout"]],
        ["/rosout", ["/listener", "/talker"]],
        ["/chatter", ["/talker"]],
    ],
    [["/rosout", ["/rosout"]], ["/chatter", ["/listener", "/robot/arm"]]],
    [
        ["/rosout/get_loggers", ["/rosout"]],
        ["/talker/get_loggers", ["/talker"]],
        ["/listener/get_loggers", ["/listener"]],
        ["/robot/arm/move", ["/robot/arm"]],
    ],
]
TYPES = {
    "/rosout": "rosgraph_msgs/Log",
    "/rosout_agg": "rosgraph_msgs/Log",
    "/chatter": "std_msgs/String",
}


@pytest.fixture
def state() -> SystemState:
    return SystemState.from_master(RAW_STATE)


def test_nodes_are_sorted_unique_and_filtered_by_namespace(state: SystemState) -> None:
    assert state.nodes() == ["/listener", "/robot/arm", "/rosout", "/talker"]
    assert state.nodes("/") == state.nodes()
    assert state.nodes("/robot") == ["/robot/arm"]
    assert state.nodes("/robot/") == ["/robot/arm"]
    assert state.nodes("/robot/arm") == ["/robot/arm"]  # a node named like the namespace
    assert state.nodes("/rob") == []  # a prefix of a name is not a namespace


def test_registrations_of_one_node(state: SystemState) -> None:
    regs = state.registrations("/talker")
    assert regs.publications == ["/chatter", "/rosout"]
    assert regs.subscriptions == []
    assert regs.services == ["/talker/get_loggers"]
    assert state.registrations("/nobody").publications == []
    assert state.on_topic("/chatter") == ["/talker", "/listener", "/robot/arm"]


def test_bus_info_entries_of_rospy_and_old_nodes() -> None:
    # rospy publisher side, captured
    out = BusConnection.from_bus_info(
        [1, "/listener", "o", "TCPROS", "/chatter", True,
         "TCPROS connection on port 37153 to [127.0.0.1:55906 on socket 8]"]
    )  # fmt: skip
    assert (out.direction, out.peer, out.local_port, out.remote, out.socket) == (
        "outbound",
        "/listener",
        37153,
        "127.0.0.1:55906",
        8,
    )
    # rospy subscriber side: "socket None" does not match, so no details (as rosnode)
    inbound = BusConnection.from_bus_info(
        [1, "http://127.0.0.1:45843/", "i", "TCPROS", "/chatter", True,
         "TCPROS connection on port 55906 to [127.0.0.1:37153 on socket None]"]
    )  # fmt: skip
    assert inbound.direction == "inbound" and inbound.local_port is None
    old = BusConnection.from_bus_info([3, "/x", "b", "UDPROS", "/t"])
    assert (old.direction, old.connected, old.info, old.transport) == (
        "unknown",
        True,
        "",
        "UDPROS",
    )
    assert not BusConnection.from_bus_info([4, "/x", "o", "TCPROS", "/t", False]).connected


def test_a_short_bus_info_entry_is_an_error() -> None:
    with pytest.raises(Exception, match="bad getBusInfo entry"):
        BusConnection.from_bus_info([1, "/x", "o"])


def test_cleanup_plan_uses_the_dead_nodes_own_names_and_apis(state: SystemState) -> None:
    dead = {"/listener": "http://127.0.0.1:44973/", "/robot/arm": "http://10.0.0.2:4000/"}
    apis = {"/listener/get_loggers": "rosrpc://127.0.0.1:5000"}  # /robot/arm/move has gone
    plan = plan_cleanup(state, dead, apis)
    assert plan == [
        Unregistration("/listener", "unregisterPublisher", "/rosout", "http://127.0.0.1:44973/"),
        Unregistration("/listener", "unregisterSubscriber", "/chatter", "http://127.0.0.1:44973/"),
        Unregistration(
            "/listener", "unregisterService", "/listener/get_loggers", "rosrpc://127.0.0.1:5000"
        ),
        Unregistration("/robot/arm", "unregisterSubscriber", "/chatter", "http://10.0.0.2:4000/"),
    ]
    assert [s.kind for s in plan] == ["publisher", "subscriber", "service", "subscriber"]
    assert plan_cleanup(state, {}, apis) == []


def test_graph_hides_rosout_unless_asked(state: SystemState) -> None:
    graph = build_graph(state, TYPES)
    assert [n.name for n in graph.nodes] == ["/listener", "/robot/arm", "/talker"]
    assert [t.name for t in graph.topics] == ["/chatter"]
    assert graph.topic("/chatter").subscribers == ["/listener", "/robot/arm"]
    assert graph.node("/robot/arm").services == ["/robot/arm/move"]
    data = graph.to_data()
    assert data["edges"] == [
        {
            "source": "/talker",
            "target": "/listener",
            "topic": "/chatter",
            "type": "std_msgs/String",
        },
        {
            "source": "/talker",
            "target": "/robot/arm",
            "topic": "/chatter",
            "type": "std_msgs/String",
        },
    ]
    full = build_graph(state, TYPES, include_debug=True)
    assert [n.name for n in full.nodes] == ["/listener", "/robot/arm", "/rosout", "/talker"]
    assert full.topic("/rosout").publishers == ["/listener", "/talker"]
    assert full.topic("/rosout_agg").subscribers == []
    assert len(full.edges) == 4  # chatter x2, and /listener and /talker -> /rosout


def test_graph_of_a_topic_without_a_known_type() -> None:
    state = SystemState.from_master([[["/a", ["/n"]]], [], []])
    graph = build_graph(state, {})
    assert graph.topic("/a").type == "unknown type" and graph.edges == []


def test_machines_group_nodes_by_host() -> None:
    uris = {
        "/a": "http://robot1:3000/",
        "/b": "http://127.0.0.1:3001/",
        "/c": "http://robot1:3002/",
        "/gone": None,
    }
    assert machines(uris) == {"127.0.0.1": ["/b"], "robot1": ["/a", "/c"]}


def test_nodes_on_machine_match_by_name_or_shared_address() -> None:
    table = {"localhost": {"127.0.0.1"}, "robot1": {"10.0.0.1"}, "10.0.0.1": {"10.0.0.1"}}
    uris = {
        "/a": "http://robot1:3000/",
        "/b": "http://localhost:3001/",
        "/c": "http://10.0.0.1:3002/",
        "/d": "http://127.0.0.1:3003/",
    }

    def resolve(host: str) -> set[str]:
        return table.get(host, {host} if host[0].isdigit() else set())

    assert nodes_on_machine(uris, "robot1", resolve) == ["/a", "/c"]
    assert nodes_on_machine(uris, "localhost", resolve) == ["/b", "/d"]
    with pytest.raises(NotFoundError, match="cannot resolve machine name nowhere"):
        nodes_on_machine(uris, "nowhere", resolve)
