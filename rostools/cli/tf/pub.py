"""``rostools tf pub``: one static transform, latched on ``/tf_static``.

As tf2_ros's ``static_transform_publisher`` publishes it: the same values, stamped now, one
``tf2_msgs/TFMessage`` per publisher, so that several (one per child) all stay visible.
"""

from __future__ import annotations

import math
import sys
import time
from functools import partial
from typing import TYPE_CHECKING, Annotated

import typer

from rostools.cli.common import node_session
from rostools.cli.declare import command
from rostools.errors import UsageError, one_line
from rostools.tf.records import Stamped

if TYPE_CHECKING:
    import asyncio

    from rostools.node.node import LiveNode

#: The arguments of each form, as static_transform_publisher names them.
RPY_FORM = "X Y Z YAW PITCH ROLL PARENT CHILD"
QUATERNION_FORM = "X Y Z QX QY QZ QW PARENT CHILD"
#: How far from 1 a quaternion's squared norm may be: past it, tf2's listeners refuse it.
NORM_TOLERANCE = 10e-6


def parse(args: list[str], now_ns: int) -> Stamped:
    """The transform the arguments name, stamped ``now_ns`` (``UsageError`` if they name none)."""
    from rostools.tf.math import from_rpy

    if len(args) not in (8, 9):
        raise UsageError(
            f"tf pub takes 8 or 9 arguments, not {len(args)}",
            hint=f"{RPY_FORM}, or {QUATERNION_FORM}",
        )
    *numbers, parent, child = args
    values: list[float] = []
    for text in numbers:
        try:
            value = float(text)
        except ValueError:
            raise UsageError(f"not a number: {one_line(text)}") from None
        if not math.isfinite(value):
            raise UsageError(f"not a finite number: {one_line(text)}")
        values.append(value)
    if parent == child:  # static_transform_publisher's words
        raise UsageError(
            f"target_frame and source frame are the same ({one_line(parent)}, "
            f"{one_line(child)}) this cannot work"
        )
    x, y, z, *angles = values
    if len(angles) == 3:
        yaw, pitch, roll = angles
        qx, qy, qz, qw = (float(v) for v in from_rpy(roll, pitch, yaw))
    else:
        qx, qy, qz, qw = angles
        norm2 = qx * qx + qy * qy + qz * qz + qw * qw
        if abs(norm2 - 1.0) > NORM_TOLERANCE:
            n = math.sqrt(norm2)
            unit = " ".join(f"{v / n:.9g}" for v in angles) if n > 0 else "0 0 0 1"
            raise UsageError(
                f"the quaternion ({qx:g} {qy:g} {qz:g} {qw:g}) is not of length 1, "
                "so tf2 listeners would refuse it (TF_DENORMALIZED_QUATERNION)",
                hint=f"normalized: {unit}",
            )
    return Stamped(parent, child, now_ns, (x, y, z), (qx, qy, qz, qw))


@command(context_settings={"ignore_unknown_options": True})
def pub(
    ctx: typer.Context,
    args: Annotated[
        list[str],
        typer.Argument(help=f"{RPY_FORM} (radians), or {QUATERNION_FORM}.", show_default=False),
    ],
) -> None:
    """Publish one static transform on /tf_static, latched, until stopped.

    As static_transform_publisher: YAW PITCH ROLL in radians, or a unit quaternion.
    """
    transform = parse(args, time.time_ns())
    node_session(ctx, partial(_publish, transform), "static_transform_publisher")


async def _publish(transform: Stamped, node: LiveNode, stop: asyncio.Event) -> None:
    """Advertise ``/tf_static`` latched, publish the one message, and wait to be stopped."""
    from rostools.cli.settings import type_store
    from rostools.msgs.topictype import TopicType
    from rostools.tf.records import encode

    kind = TopicType.of(type_store(), "tf2_msgs/TFMessage")
    publisher = await node.advertise("/tf_static", kind, latch=True, queue_size=1)
    publisher.publish(encode([transform]))
    sys.stderr.write(
        f"publishing {one_line(transform.parent)} -> {one_line(transform.child)} on "
        f"{publisher.topic}, latched. Press Ctrl-C to stop\n"
    )
    await stop.wait()
