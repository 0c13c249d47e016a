"""Types the local store lacks, learnt from a topic's publisher."""

from __future__ import annotations

from typing import TYPE_CHECKING

from rostools.cli.common import settings
from rostools.cli.quick import topic as quick

if TYPE_CHECKING:
    import typer

    from rostools.msgs.store import TypeStore


def learn_type(ctx: typer.Context, topic: str, store: TypeStore) -> TypeStore:
    """``store`` plus the definition a publisher of ``topic`` sends."""
    return quick.learn_type(settings(ctx), topic, store)
