"""rostools: the ROS 1 command-line tools in one pip-installable Python CLI, no ROS needed.

It is also a Python API for scripts and tests (``from rostools import Node, publish ...``):
the names the ``TYPE_CHECKING`` block below imports are the stable API (``__all__``). They
load on first use (``rostools.lazy``), because every command of the CLI imports this package
and its start-up time counts.
"""

from __future__ import annotations

__version__ = "0.1.0"

TYPE_CHECKING = False
if TYPE_CHECKING:  # the stable API: type checkers read these imports, rostools.lazy too
    from rostools._api.asyncnode import (
        AsyncNode as AsyncNode,
    )
    from rostools._api.asyncnode import (
        AsyncPublisher as AsyncPublisher,
    )
    from rostools._api.asyncnode import (
        AsyncSubscription as AsyncSubscription,
    )
    from rostools._api.bags import (
        BagMessage as BagMessage,
    )
    from rostools._api.bags import (
        Recording as Recording,
    )
    from rostools._api.bags import (
        read_bag as read_bag,
    )
    from rostools._api.bags import (
        record as record,
    )
    from rostools._api.functions import (
        call_service as call_service,
    )
    from rostools._api.functions import (
        delete_param as delete_param,
    )
    from rostools._api.functions import (
        get_param as get_param,
    )
    from rostools._api.functions import (
        has_param as has_param,
    )
    from rostools._api.functions import (
        publish as publish,
    )
    from rostools._api.functions import (
        set_param as set_param,
    )
    from rostools._api.functions import (
        subscribe as subscribe,
    )
    from rostools._api.functions import (
        wait_for_message as wait_for_message,
    )
    from rostools._api.functions import (
        wait_for_service as wait_for_service,
    )
    from rostools._api.master import (
        Master as Master,
    )
    from rostools._api.messages import (
        message as message,
    )
    from rostools._api.messages import (
        message_class as message_class,
    )
    from rostools._api.node import (
        Node as Node,
    )
    from rostools._api.node import (
        Publisher as Publisher,
    )
    from rostools._api.node import (
        Subscription as Subscription,
    )
    from rostools.errors import (
        NotFoundError as NotFoundError,
    )
    from rostools.errors import (
        RostoolsError as RostoolsError,
    )
    from rostools.errors import (
        ServiceError as ServiceError,
    )
    from rostools.errors import (
        TimeoutExpired as TimeoutExpired,
    )
    from rostools.errors import (
        UnreachableError as UnreachableError,
    )
    from rostools.errors import (
        UsageError as UsageError,
    )
    from rostools.msgs.message import (
        Duration as Duration,
    )
    from rostools.msgs.message import (
        Message as Message,
    )
    from rostools.msgs.message import (
        Time as Time,
    )


def __getattr__(name: str) -> object:
    """Load a public name on first use (PEP 562); ``__all__`` is their list."""
    from rostools.lazy import load

    return load(__name__, name)


def __dir__() -> list[str]:
    from rostools.lazy import homes

    return sorted([*globals(), *homes(__name__)])
