"""The Python API's nodes at a script's end: each unregisters, however the script ends.

A script (a child of its own) starts every kind of node the API has, leaves them all open,
and ends: cleanly, by an exception, by SIGINT or by SIGTERM. The master, ours and a real
roscore, must then know none of them, and the script must say nothing about its master.
Its ``ROS_MASTER_URI`` names the master's host (``localhost``), as most users' does: the
address is looked up on a thread pool, which Python shuts as the main thread ends, so the
nodes could neither unregister nor reach their master after it (issue 33).
"""

from __future__ import annotations

import signal
import subprocess
import sys
import xmlrpc.client
from pathlib import Path

import pytest

from rostools.bag.formats.access import bag_info
from tests.conftest import MasterInfo
from tests.support.procs import Proc, wait_for

pytestmark = pytest.mark.interop

SCRIPT = """
import asyncio, sys, threading, time
import rostools

rostools.publish("/exit/pub", {"data": "x"}, "std_msgs/String")  # the default node
rostools.subscribe("/exit/pub", lambda msg: None)
node = rostools.Node("exit_explicit")
node.advertise_service("/exit/srv", "std_srvs/Trigger", lambda req: {"success": True})
rostools.record(["/exit/pub"], sys.argv[1]).start()


async def left_open():  # a node on a loop of the script's own, which ends
    aio = await rostools.AsyncNode("exit_async").start()
    await aio.advertise("/exit/async", "std_msgs/String")


asyncio.run(left_open())
print("ready", flush=True)


def outlives_main():
    threading.main_thread().join()
    time.sleep(1.0)  # the master's watch looks twice meanwhile
    rostools.set_param("/exit/late", 1)


how = sys.stdin.readline().strip()  # a signal ends it here
threading.Thread(target=outlives_main).start()
if how == "raise":
    raise RuntimeError("ending by an exception")
"""

#: How each ending is asked for, its exit status, and the end of its stderr.
ENDINGS = {
    "clean": ("end", 0, ""),
    "exception": ("raise", 1, "RuntimeError: ending by an exception\n"),
    "sigint": (signal.SIGINT, -signal.SIGINT, "KeyboardInterrupt\n"),
    "sigterm": (signal.SIGTERM, -signal.SIGTERM, ""),
}


def _exit_nodes(master: xmlrpc.client.ServerProxy) -> set[str]:
    """The nodes the master lists under any /exit/ name."""
    state = master.getSystemState("/probe")[2]
    return {n for kind in state for name, nodes in kind if name.startswith("/exit/") for n in nodes}


@pytest.mark.parametrize("ending", list(ENDINGS))
def test_the_api_leaves_nothing_on_the_master(
    any_master: MasterInfo, tmp_path: Path, ending: str
) -> None:
    script = tmp_path / "script.py"
    script.write_text(SCRIPT)
    bag = tmp_path / "left.bag"
    env = dict(any_master.cli_env)
    env["ROS_MASTER_URI"] = any_master.uri.replace("127.0.0.1", "localhost")
    env["ROSTOOLS_MASTER_TIMEOUT"] = "30"  # a loaded machine: every call gets its answer
    master = xmlrpc.client.ServerProxy(any_master.uri)
    proc = Proc([sys.executable, str(script), str(bag)], env=env, stdin=subprocess.PIPE)
    try:
        proc.expect("^ready", timeout=60)
        # the default node, the explicit one, the async one and the recording's
        wait_for(lambda: len(_exit_nodes(master)) == 4, 30, "the script's four nodes")
        nodes = _exit_nodes(master)
        how, status, stderr_end = ENDINGS[ending]
        if isinstance(how, str):
            assert proc.popen.stdin is not None
            proc.popen.stdin.write(how.encode() + b"\n")
            proc.popen.stdin.flush()
        else:
            proc.signal(how)
        assert proc.popen.wait(60) == status
        _, err = proc.output()
    finally:
        proc.stop()
        if proc.popen.stdin is not None:
            proc.popen.stdin.close()
    assert err.endswith(stderr_end), err
    # no word of the master, which was there all along; no failure but the script's own
    assert "master" not in err and "futures" not in err, err
    assert err.count("Traceback") == (1 if stderr_end else 0), err
    assert "Exception" not in err, err
    assert _exit_nodes(master) == set()
    for name in nodes:
        code, message, _ = master.lookupNode("/probe", name)
        assert code == -1, (name, message)
    if isinstance(how, str):  # the thread that outlived the main one still had the API
        assert master.getParam("/probe", "/exit/late")[2] == 1
    assert not bag.with_name(bag.name + ".active").exists()
    assert bag_info(bag).message_count == 1  # the recording was completed as it ended
