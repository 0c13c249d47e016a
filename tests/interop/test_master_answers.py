"""Master API answers that rosmaster gives, compared in one test with rosmaster beside ours.

Boundaries a planted bug slipped through: getPublishedTopics' namespace filter (``/a`` must
not match ``/ab/x``), and faults, which the standard library's client must read as faults.
"""

from __future__ import annotations

import xmlrpc.client
from collections.abc import Iterator
from pathlib import Path

import pytest

from tests.support.env import needs_ros1
from tests.support.procs import free_port, ros_env, start_roscore, start_rostools_core

pytestmark = [pytest.mark.interop, needs_ros1]

PUBLISHED = ["/a", "/ab/x", "/a/b", "/a/b/c", "/ns/c", "/nsx/d", "/ns/a/e"]
CALLER = "/ns/node"


@pytest.fixture(scope="module")
def masters(tmp_path_factory: pytest.TempPathFactory) -> Iterator[dict[str, str]]:
    """rosmaster (roscore) and rostools core side by side: their URIs."""
    home: Path = tmp_path_factory.mktemp("ros_home")
    uris, procs = {}, []
    try:
        for name, start in (("rosmaster", start_roscore), ("rostools", start_rostools_core)):
            port = free_port()
            uri = f"http://127.0.0.1:{port}/"
            procs.append(start(port, ros_env(uri, home)))
            uris[name] = uri
            master = xmlrpc.client.ServerProxy(uri)
            for i, topic in enumerate(PUBLISHED):
                code, _, _ = master.registerPublisher(
                    f"/pub{i}", topic, "std_msgs/String", f"http://127.0.0.1:9/pub{i}"
                )
                assert code == 1
        yield uris
    finally:
        for proc in procs:
            proc.stop()


def _ask(uri: str, method: str, *args: object) -> object:
    try:
        return getattr(xmlrpc.client.ServerProxy(uri), method)(CALLER, *args)
    except xmlrpc.client.Fault as fault:
        return ("fault", fault.faultCode)


@pytest.mark.parametrize("subgraph", ["/a", "/a/", "/ns", "/", "", "a", "ns", "/nsx", "/n"])
def test_published_topics_under_a_namespace(masters: dict[str, str], subgraph: str) -> None:
    def topics(uri: str) -> object:
        answer = _ask(uri, "getPublishedTopics", subgraph)
        assert isinstance(answer, list), answer
        code, _, found = answer
        return code, sorted(t for t, _ in found)

    ours, theirs = topics(masters["rostools"]), topics(masters["rosmaster"])
    assert ours == theirs
    assert ours[1] != sorted(PUBLISHED) or subgraph in ("/", "")  # the filter filters


@pytest.mark.parametrize(
    ("method", "args"),
    [
        ("noSuchMethod", ()),  # an unknown method is a fault, not a triple
        ("getPid", ("extra", "args")),  # wrong arity
        ("lookupNode", (5,)),  # a wrong type
        ("getParam", ({"a": 1},)),
        ("system.multicall", ("not a list",)),
    ],
)
def test_faults_and_errors_read_as_rosmaster_gives_them(
    masters: dict[str, str], method: str, args: tuple[object, ...]
) -> None:
    def answer(uri: str) -> object:
        got = _ask(uri, method, *args)
        return got[:1] + got[2:] if isinstance(got, list) and len(got) == 3 else got

    ours, theirs = answer(masters["rostools"]), answer(masters["rosmaster"])
    # the same kind of answer: a fault with its code, or a triple with its code (and value)
    assert (ours[0], type(ours)) == (theirs[0], type(theirs)), (ours, theirs)
