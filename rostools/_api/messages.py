"""Typed messages for the API: classes by type name, messages from dicts or YAML, decoders.

Messages are the codec's generated classes (``rostools.msgs.codec``), built from one store
shared by the process: the built-in types, ``ROSTOOLS_MSG_PATH`` and ``ROS_PACKAGE_PATH``.
A topic whose publisher sends a type that store lacks (or knows with another md5sum) is
decoded with the publisher's own definition.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

from rostools.errors import NotFoundError, UsageError
from rostools.msgs import learnt
from rostools.msgs.codec import DECODE_ERRORS, Codec, DecodeError, why_not
from rostools.msgs.message import Message
from rostools.msgs.store import TypeStore
from rostools.msgs.topictype import TopicType

#: Code generation is not thread-safe (two threads could each build a class for one type),
#: and the API builds types on the caller's thread and on the loop's.
_lock = threading.RLock()
_store: TypeStore | None = None
#: (type, md5sum, definition) -> decoder, for types learnt from a publisher or a bag: the
#: codecs behind them are ``msgs/learnt``'s, and as many are kept.
_decoders: dict[tuple[str, str, str], Callable[[Any], Message]] = {}

Values = Message | dict[str, Any] | list[Any] | str | None


def store() -> TypeStore:
    """The process's type store."""
    global _store
    with _lock:
        if _store is None:
            _store = TypeStore.default()
        return _store


def _codec() -> Codec:
    return Codec.of(store())


def _known(type_name: str) -> None:
    if not store().has_msg(type_name):
        raise NotFoundError(
            f"unknown message type {type_name}",
            hint="add its package with ROSTOOLS_MSG_PATH or ROS_PACKAGE_PATH",
        )


def message_class(type_name: str) -> type[Message]:
    """The generated class of message type ``pkg/Type``, as genpy's ``String`` is.

    ``String = message_class("std_msgs/String"); String(data="hi")``.
    """
    with _lock:
        _known(type_name)
        codec = _codec()
        for dep in codec.store.dependencies(type_name):  # nested classes built here, locked
            codec.message_class(dep)
        return codec.message_class(type_name)


def message(type_name: str, values: Values = None, /, **fields: Any) -> Message:
    """A message of ``type_name`` from a dict, a list in field order, YAML text, or keywords.

    As ``topic pub`` reads its values: fields left out keep their defaults, a Header may be
    ``auto`` and a time ``now``; a value of the wrong type names its field.
    """
    from rostools.msgs.fill import Filler

    if isinstance(values, Message):
        if values._type != type_name:
            raise UsageError(f"expected a {type_name} message, got a {values._type}")
        return values
    if isinstance(values, str):
        from rostools import yamlio

        values = yamlio.load(values, f"{type_name} values") if values.strip() else None
    if fields:
        if values is not None and not isinstance(values, dict):
            raise UsageError("give field values as a mapping or as keywords, not both")
        values = {**(values or {}), **fields}
    message_class(type_name)
    with _lock:
        filler = Filler(_codec())
        return filler.fill(filler.codec.store.msg(type_name), values, "")


def topic_type(type_name: str) -> TopicType:
    """What a topic of ``type_name`` announces (type, md5sum, definition)."""
    with _lock:
        _known(type_name)
        return TopicType.of(store(), type_name)


def decoder(type_name: str, md5sum: str, definition: str) -> Callable[[Any], Message]:
    """``decode(bytes) -> message`` for a type as a peer describes it.

    The shared store's class when it has the type with the same md5sum, so that decoded
    messages compare equal to ones built with ``message``; else the peer's definition.
    """
    key = (type_name, md5sum, definition)
    found = _decoders.get(key)
    if found is not None:
        return found
    with _lock:
        shared = store()
        if shared.has_msg(type_name) and shared.md5(type_name) == md5sum:
            codec = Codec.of(shared)
        else:
            codec = learnt.codec(shared, type_name, md5sum, definition)
        for dep in codec.store.dependencies(type_name):
            codec.message_class(dep)
        codec.message_class(type_name)
        decode = codec.decoder(type_name)

        def whole(data: Any) -> Message:
            try:
                msg: Message = decode(data, 0)[0]
            except (DecodeError, *DECODE_ERRORS) as err:
                raise DecodeError(f"cannot decode {type_name}: {why_not(err)}") from err
            return msg

        if len(_decoders) >= learnt.MAX_LEARNT:
            _decoders.clear()
        _decoders[key] = whole
        return whole


def service_types(srv_type: str) -> tuple[str, str, str]:
    """A service type's request and response message types, and its md5sum."""
    with _lock:
        try:
            spec = store().srv(srv_type)
        except Exception as err:
            raise NotFoundError(
                f"unknown service type {srv_type}",
                hint="add its package with ROSTOOLS_MSG_PATH or ROS_PACKAGE_PATH",
            ) from err
        return spec.request.name, spec.response.name, store().srv_md5(srv_type)
