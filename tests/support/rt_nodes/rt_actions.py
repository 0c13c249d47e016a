"""A rostools action server: actionlib/TestAction on /fib, written with rostools.action.

Run with the project's python: ``rt_actions.py [NAME TYPE MSG_PATH]`` serves another name, of
a type from an ``.action`` under MSG_PATH whose parts have the fields goal, result and
feedback. The goal's number says what happens:

- n > 0: feedback 1..n every 50 ms, then SUCCEEDED with result n * 10;
- n < 0: ABORTED ("negative goal n");
- n == 13: REJECTED ("unlucky");
- n == 666: the process dies mid-goal (os._exit) after the first feedback;
- a cancel ends the goal as PREEMPTED, with the feedback count so far as its result.
"""

from __future__ import annotations

import asyncio
import os
import sys
from pathlib import Path

from rostools.action.server import ActionServer, ServerGoalHandle
from rostools.action.types import ActionTypes
from rostools.msgs.store import BuiltinSource, PathSource, TypeStore
from rostools.node.node import LiveNode


async def main() -> None:
    name, type_name, msg_path = (*sys.argv[1:4], "", "", "")[:3] if sys.argv[1:] else ("",) * 3
    sources = [PathSource([Path(msg_path)])] if msg_path else []
    types = ActionTypes(TypeStore([*sources, BuiltinSource()]), type_name or "actionlib/TestAction")
    node_name = "rt_actions" + name.replace("/", "_") if name else "rt_actions"
    node = await LiveNode(node_name, os.environ["ROS_MASTER_URI"]).start()

    async def execute(goal: ServerGoalHandle) -> object:
        n = goal.goal.goal
        if n == 13:
            goal.reject("unlucky")
            return None
        goal.accept()
        if n < 0:
            goal.abort(text=f"negative goal {n}")
            return None
        for i in range(1, n + 1):
            goal.publish_feedback(feedback=i)
            if n == 666:
                await asyncio.sleep(0.2)  # the feedback leaves first
                os._exit(3)
            try:
                await asyncio.wait_for(goal.cancel_requested.wait(), 0.05)
            except asyncio.TimeoutError:
                continue
            goal.canceled(types.message("Result", result=i), "canceled at " + str(i))
            return None
        return types.message("Result", result=n * 10)

    server = await ActionServer(node, name or "/fib", types, execute, auto_accept=False).start()
    print("ready", flush=True)
    await node.shutdown_requested.wait()
    await server.close()
    await node.close()


if __name__ == "__main__":
    asyncio.run(main())
