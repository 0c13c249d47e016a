"""Types as a publisher or a bag defines them: one codec per (type, md5sum, definition).

A publisher's connection header and a bag's connection carry a type's name, md5sum and full
definition text, and what they carry is decoded with that definition, not the local one.
Echo, ``topic plot``, ``--filter``, ``delay``, ``bag cat``, ``bag plot``, ``bag filter``,
``bag doctor`` and the API's subscribers all get their codec here, built once per key and
shared by every path of the process: parsing the definition and generating the decoder are
the work repeated for every connection of a type.

A definition that holds its type and every type nested in it does not depend on the store it
is read over, so its codec is shared whatever the caller's store (``TypeStore([])``, the
default one, one with ``--msg-path``). A definition that leaves types out (some bags' are
empty or partial) is completed from the caller's store and kept with that store.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any, Final

from rostools.errors import NotFoundError
from rostools.msgs.codec import Codec
from rostools.msgs.store import TypeStore

#: Codecs kept per table; past it the oldest is dropped (and built again if asked for). A peer
#: picks the definitions it sends, so their number is bounded here; a graph rarely carries more
#: than a few hundred types (Noetic's common packages, the built-in table: 162).
MAX_LEARNT: Final = 1024

Key = tuple[str, str, str]

#: Codecs of self-contained definitions, for every caller of the process.
_shared: dict[Key, Codec] = {}


def codec(base: TypeStore, type_name: str, md5sum: str, definition: str) -> Codec:
    """The codec for ``type_name`` as ``definition`` defines it, over ``base`` for the rest.

    Its ``store`` resolves the type and every type in it. An empty definition means
    ``base``'s own type. A definition that does not parse, or names a type that contains
    itself, is a ``DefinitionError``.
    """
    if not definition or definition.isspace():  # as with_definition's strip(), without a copy
        return Codec.of(base.with_definition(type_name, definition))
    key = (type_name, md5sum, definition)
    own: dict[Key, Codec] = base.cache.setdefault("learnt", {})
    found = _shared.get(key) or own.get(key)
    if found is not None:
        return found
    alone = TypeStore([]).with_definition(type_name, definition)
    try:
        alone.dependencies(type_name)
    except NotFoundError:  # a type left out: the caller's store completes it
        return _keep(own, key, Codec.of(base.with_definition(type_name, definition)))
    return _keep(_shared, key, Codec.of(alone))


def decoder(
    base: TypeStore, type_name: str, md5sum: str, definition: str
) -> Callable[[Any, int], tuple[Any, int]]:
    """``decode(buf, pos) -> (message, new_pos)`` for a type as ``definition`` defines it."""
    return codec(base, type_name, md5sum, definition).decoder(type_name)


def _keep(table: dict[Key, Codec], key: Key, found: Codec) -> Codec:
    if len(table) >= MAX_LEARNT:
        del table[next(iter(table))]
    table[key] = found
    return found
