"""rosgraph's address rules: the name a node gives out, where it binds, and where core listens."""

from __future__ import annotations

import socket

import pytest

from rostools.errors import UsageError
from rostools.master.core import choose_address
from rostools.rosgraph.network import address_override, bind_address, host_name, is_loopback


@pytest.fixture
def hostname(monkeypatch: pytest.MonkeyPatch) -> list[str]:
    """Pretend this machine is called whatever the test puts in the list."""
    name = ["robot"]
    monkeypatch.setattr(socket, "gethostname", lambda: name[0])
    monkeypatch.setattr(
        "rostools.rosgraph.network.local_addresses", lambda: ["127.0.0.1", "10.1.2.3"]
    )
    return name


def test_override_order_is_rosgraphs() -> None:
    # rosgraph.network.get_address_override: remaps first, then ROS_HOSTNAME, then ROS_IP
    env = {"ROS_IP": "10.0.0.2", "ROS_HOSTNAME": "named"}
    assert address_override(env) == "named"
    assert address_override(env, {"__ip": "10.9.9.9"}) == "10.9.9.9"
    assert address_override(env, {"__hostname": "h", "__ip": "10.9.9.9"}) == "h"
    assert address_override({"ROS_IP": "10.0.0.2"}) == "10.0.0.2"
    assert address_override({"ROS_HOSTNAME": "", "ROS_IP": ""}) is None


@pytest.mark.parametrize(
    "env",
    [{"ROS_IP": "http://10.0.0.2"}, {"ROS_HOSTNAME": "robot:11311"}, {"ROS_IP": "10.0.0.2:5"}],
)
def test_a_scheme_or_port_is_refused(env: dict[str, str]) -> None:
    with pytest.raises(UsageError, match="ROS_"):
        address_override(env)


def test_ipv6_override_is_not_a_port() -> None:
    assert address_override({"ROS_IP": "fd00::2"}) == "fd00::2"


def test_host_name_is_the_machines_name_whatever_the_master(hostname: list[str]) -> None:
    # the defect: with ROS_MASTER_URI=http://localhost:11311 and ROS_IP unset, our nodes gave
    # out 127.0.0.1, so nodes on other hosts could not connect back. rospy gives the hostname.
    assert host_name({}) == "robot"
    assert host_name({"ROS_MASTER_URI": "http://localhost:11311"}) == "robot"


@pytest.mark.parametrize("name", ["localhost", "127.0.1.1", ""])
def test_a_loopback_hostname_gives_an_interface_address(hostname: list[str], name: str) -> None:
    hostname[0] = name
    assert host_name({}) == "10.1.2.3"


def test_bind_follows_the_name() -> None:
    assert bind_address("localhost") == "127.0.0.1"
    assert bind_address("127.0.0.1") == "127.0.0.1"
    assert bind_address("127.0.1.1") == "127.0.1.1"
    assert bind_address("10.0.0.2") == "0.0.0.0"
    assert bind_address("robot") == "0.0.0.0"
    assert is_loopback("::1") and not is_loopback("robot")


def test_bare_core_is_loopback_only() -> None:
    address = choose_address(None, None, {})
    assert (address.bind, address.port, address.uri) == (
        "127.0.0.1",
        11311,
        "http://localhost:11311/",
    )


def test_core_with_ros_ip_listens_everywhere_and_gives_out_the_address() -> None:
    # the defect: ROS_IP=10.x made core bind only 10.x, and its /rosout then failed to
    # register through loopback; rosmaster binds every interface
    address = choose_address(None, 11400, {"ROS_IP": "10.0.0.2"})
    assert (address.bind, address.uri) == ("0.0.0.0", "http://10.0.0.2:11400/")
    named = choose_address(None, None, {"ROS_HOSTNAME": "robot", "ROS_IP": "10.0.0.2"})
    assert named.uri == "http://robot:11311/"


def test_core_host_any_gives_out_this_hosts_name(hostname: list[str]) -> None:
    # the defect: --host 0.0.0.0 gave out http://0.0.0.0:11311/
    address = choose_address("0.0.0.0", None, {"ROS_MASTER_URI": "http://localhost:11322"})
    assert (address.bind, address.uri) == ("0.0.0.0", "http://robot:11322/")
    address = choose_address("0.0.0.0", None, {"ROS_IP": "10.0.0.2"})
    assert address.uri == "http://10.0.0.2:11311/"


def test_core_host_loopback_stays_loopback() -> None:
    assert choose_address("127.0.0.1", None, {}).bind == "127.0.0.1"
    assert choose_address("localhost", None, {"ROS_IP": "10.0.0.2"}).uri == (
        "http://localhost:11311/"
    )


def test_a_node_on_the_masters_host_gives_out_the_hostname(
    hostname: list[str], monkeypatch: pytest.MonkeyPatch
) -> None:
    from rostools.node.node import LiveNode

    monkeypatch.delenv("ROS_IP", raising=False)
    monkeypatch.delenv("ROS_HOSTNAME", raising=False)
    assert LiveNode("n", "http://localhost:11311").host == "robot"
    assert LiveNode("n", "http://127.0.0.1:11311").host == "robot"
    remapped = LiveNode(
        "n", "http://localhost:11311", remappings={"__hostname": "h", "__ip": "1.2.3.4"}
    )
    assert remapped.host == "h" and not remapped.remappings  # both consumed, neither a remap


def test_a_malformed_answer_is_not_an_address_problem() -> None:
    from rostools.rosgraph.network import SET_ADDRESS, explain
    from rostools.wire.xmlvalues import BadAnswer

    # the defect: a peer on loopback that answered garbage was told to set ROS_IP
    failure = explain(BadAnswer("malformed XML-RPC answer: syntax error"), "127.0.0.1")
    assert failure.hint == "" and failure.lasting
    assert failure.reason == (
        "it does not speak the ROS XML-RPC API (malformed XML-RPC answer: syntax error)"
    )
    # a refused connection there is still one
    assert explain(ConnectionRefusedError(), "127.0.0.1").hint == SET_ADDRESS
