"""rostools: the ROS 1 command-line tools in one pip-installable Python CLI, no ROS needed.

It is also a Python API for scripts and tests (``from rostools import Node, publish ...``):
the names the ``TYPE_CHECKING`` block below imports are the stable API (``__all__``). They
load on first use (``rostools.lazy``), because every command of the CLI imports this package
and its start-up time counts.
"""

from __future__ import annotations

TYPE_CHECKING = False
if TYPE_CHECKING:  # the stable API: type checkers read these imports, rostools.lazy too
    from rostools._api.asyncnode import (
        AsyncNode as AsyncNode,
        AsyncPublisher as AsyncPublisher,
        AsyncSubscription as AsyncSubscription,
    )
    from rostools._api.bags import (
        BagMessage as BagMessage,
        Recording as Recording,
        read_bag as read_bag,
        record as record,
    )
    from rostools._api.blocking import (
        Node as Node,
        Publisher as Publisher,
        Subscription as Subscription,
    )
    from rostools._api.bridges import (
        WebBridge as WebBridge,
        bridge as bridge,
    )
    from rostools._api.functions import (
        call_service as call_service,
        delete_param as delete_param,
        get_param as get_param,
        has_param as has_param,
        publish as publish,
        set_param as set_param,
        subscribe as subscribe,
        wait_for_message as wait_for_message,
        wait_for_service as wait_for_service,
    )
    from rostools._api.master import (
        Master as Master,
    )
    from rostools._api.messages import (
        message as message,
        message_class as message_class,
    )
    from rostools._api.snapshots import (
        SnapshotRecorder as SnapshotRecorder,
        snapshot as snapshot,
    )
    from rostools._api.tables import (
        bag_batches as bag_batches,
        bag_table as bag_table,
    )
    from rostools.errors import (
        DataLossError as DataLossError,
        NotFoundError as NotFoundError,
        RostoolsError as RostoolsError,
        ServiceError as ServiceError,
        TimeoutExpired as TimeoutExpired,
        UnreachableError as UnreachableError,
        UsageError as UsageError,
    )
    from rostools.msgs.message import (
        Duration as Duration,
        Message as Message,
        Time as Time,
    )
    from rostools.version import (
        __version__ as __version__,
    )


def __getattr__(name: str) -> object:
    """Load a public name on first use (PEP 562); ``__all__`` is their list."""
    from rostools.lazy import load

    return load(__name__, name)


def __dir__() -> list[str]:
    from rostools.lazy import homes

    return sorted([*globals(), *homes(__name__)])
