"""Types the local store lacks, learnt from a topic's publisher."""

from __future__ import annotations

import typer

from rostools.cli.common import node_session
from rostools.msgs.store import TypeStore

PROBE_TIMEOUT = 5.0


def learn_type(ctx: typer.Context, topic: str, store: TypeStore) -> TypeStore:
    """``store`` plus the definition a publisher of ``topic`` sends."""
    from rostools.node.learntype import learn_topic_type

    async def main(node, stop):  # type: ignore[no-untyped-def]
        return await learn_topic_type(node, topic, PROBE_TIMEOUT)

    learnt = node_session(ctx, main, "rostools_probe")
    return store.with_definition(learnt.type, learnt.definition)
