"""Sampling for plots: from raw messages of one type to (label, x, y) samples.

``topic plot`` and ``bag plot`` share this layer, and it shares echo's: paths are parsed and
checked by ``fieldpath`` (the one parser), ``--filter`` is compiled by ``expr``, and the
numbers are read by ``extract`` without decoding the rest of the message. Only a filter
that reads ``m`` decodes a whole message.

A sample's label is the topic and path as the user wrote them; a slice gives one label per
element (``/scan/ranges[0:3]`` -> ``/scan/ranges[0]``, ``[1]``, ``[2]``).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from typing import Any, Final

from rostools.errors import UsageError
from rostools.msgs import extract, fieldpath
from rostools.msgs.codec import DECODE_ERRORS, Codec, DecodeError, why_not
from rostools.msgs.expr import Expression
from rostools.msgs.fieldpath import Step
from rostools.msgs.message import Time
from rostools.msgs.store import TypeStore

#: Elements one sliced path may plot: each is a line of its own.
MAX_SLICE: Final = 64

#: Where samples go: ``sink(label)`` gives the ``put(x, y)`` of that label's series, looked
#: up once per label, not once per sample.
Put = Callable[[float, float], None]
Sink = Callable[[str], Put]


def _step_text(step: Step, index: int | None = None) -> str:
    if index is not None:
        return f"{step.name}[{index}]"
    if step.index is None:
        return step.name
    if isinstance(step.index, int):
        return f"{step.name}[{step.index}]"
    s = step.index
    parts = ["" if v is None else str(v) for v in (s.start, s.stop)]
    if s.step is not None:
        parts.append(str(s.step))
    return f"{step.name}[{':'.join(parts)}]"


class Labels:
    """The labels of one field path of a topic, from its text alone (no type needed).

    A path without a slice has one label; a sliced one a label per element, by the
    element's own index where that does not depend on the array's length
    (``ranges[2:4]`` -> ``ranges[2]``, ``ranges[3]``), else by its place in the slice
    (``ranges[-2:]`` -> ``ranges[-2:][0]``, ``ranges[-2:][1]``).
    """

    def __init__(self, topic: str, path: str) -> None:
        steps = fieldpath.parse(path)
        slices = [i for i, s in enumerate(steps) if isinstance(s.index, slice)]
        root = topic.rstrip("/")
        self.label = root + "/" + "/".join(_step_text(s) for s in steps)
        if len(slices) > 1:
            raise UsageError(f"{self.label}: plot one slice per field path")
        self.sliced = bool(slices)
        self.labels: list[str] = []
        #: How many elements the slice gives, when the path alone says (else None).
        self.count: int | None = None
        if not slices:
            return
        at = slices[0]
        self.sliced_step = steps[at]
        self.head = "/".join([root, *(_step_text(s) for s in steps[:at])])
        self.tail = "".join("/" + _step_text(s) for s in steps[at + 1 :])
        sl = steps[at].index
        assert isinstance(sl, slice)
        self.absolute = (sl.start is None or sl.start >= 0) and (sl.step or 1) > 0
        if self.absolute and sl.stop is not None and sl.stop >= 0:
            self.count = len(range(sl.start or 0, sl.stop, sl.step or 1))
            if self.count > MAX_SLICE:
                raise UsageError(
                    f"{self.label} plots {self.count} elements, more than {MAX_SLICE}",
                    hint="take a smaller slice, or a step: ranges[0:360:30]",
                )

    def known(self) -> list[str]:
        """The labels the path alone gives, in order (a slice's, where its length is known)."""
        if not self.sliced:
            return [self.label]
        return [self.label_of(i) for i in range(self.count or 0)]

    def label_of(self, i: int) -> str:
        """The label of the ``i``-th element a slice yields."""
        while len(self.labels) <= i:
            k = len(self.labels)
            sl = self.sliced_step.index
            assert isinstance(sl, slice)
            if self.absolute:
                name = _step_text(self.sliced_step, (sl.start or 0) + k * (sl.step or 1))
            else:
                name = f"{_step_text(self.sliced_step)}[{k}]"
            self.labels.append(f"{self.head}/{name}{self.tail}")
        return self.labels[i]


class _Column(Labels):
    """One field path of a topic: its extractor, its labels and where their samples go."""

    def __init__(self, codec: Codec, type_name: str, topic: str, path: str, sink: Sink) -> None:
        super().__init__(topic, path)
        resolved = fieldpath.resolve(codec.store, type_name, path)
        name = topic.rstrip("/") + "/" + path.lstrip("/")
        self.extract = extract.extractor(codec, type_name, resolved, name)
        self.sink = sink
        self.put = None if self.sliced else sink(self.label)
        self.puts: list[Put] = []

    def put_of(self, i: int) -> Put:
        """Where the ``i``-th element of a slice goes."""
        while len(self.puts) <= i:
            self.puts.append(self.sink(self.label_of(len(self.puts))))
        return self.puts[i]


class Sampler:
    """Samples the messages of one topic, of one type as one publisher or bag defines it.

    ``paths``: field paths after the topic; ``sink``: where each label's samples go.
    ``stamp``: x is ``header.stamp`` instead of the time the caller gives. ``keep``: a
    compiled ``--filter``, which sees ``topic``, ``m`` and ``t`` as echo's and ``bag
    filter``'s do.
    """

    def __init__(
        self,
        store: TypeStore,
        type_name: str,
        topic: str,
        paths: Sequence[str],
        sink: Sink,
        stamp: bool = False,
        keep: Expression | None = None,
    ) -> None:
        self.codec = Codec.of(store)
        self.type_name = type_name
        self.topic = topic
        empty = [p for p in paths if not p.strip("/")]
        if empty:
            raise UsageError(
                f"give a field of {topic} to plot ({type_name})",
                hint=f"for example {topic}/{_first_number(store, type_name)}",
            )
        self.columns = [_Column(self.codec, type_name, topic, p, sink) for p in paths]
        self.stamp: extract.Extractor | None = None
        if stamp:
            if not store.msg(type_name).has_header:
                raise UsageError(
                    f"--stamp: {topic} ({type_name}) has no header.stamp",
                    hint="leave out --stamp to plot against receive (or bag) time",
                )
            self.stamp = extract.extractor(
                self.codec, type_name, fieldpath.resolve(store, type_name, "header/stamp")
            )
        self.keep = keep
        self.decode = self.codec.decoder(type_name) if keep and keep.needs_message else None
        #: Messages whose array was too short for an index, so gave no sample.
        self.missed = 0

    def feed(
        self,
        frames: Sequence[Any],
        t: float,
        skip: Callable[[DecodeError, Any], None] | None = None,
    ) -> int:
        """Sample messages that arrived at ``t`` (seconds); how many passed the filter.

        Bytes that do not decode as the type says are a ``DecodeError`` naming both; with
        ``skip``, it is handed the error and the message, which gives no sample.
        """
        stamp, keep, columns = self.stamp, self.keep, self.columns
        fed = 0
        for data in frames:
            try:
                if keep is not None:
                    msg = self.decode(data, 0)[0] if self.decode is not None else None
                    if not keep(self.topic, msg, Time.from_sec(t)):
                        continue
                x = stamp(data) if stamp is not None else t
                values: list[Any] = []
                for col in columns:  # every number first: a message that fails gives none
                    try:
                        values.append(col.extract(data))
                    except IndexError:
                        values.append(None)
            except (DecodeError, *DECODE_ERRORS) as err:
                failure = DecodeError(
                    f"a message on {self.topic} does not decode as {self.type_name}: {why_not(err)}"
                )
                if skip is None:
                    raise failure from err
                skip(failure, data)
                continue
            fed += 1
            for col, value in zip(columns, values, strict=True):
                if value is None:
                    self.missed += 1
                elif col.put is not None:
                    col.put(x, value)
                else:
                    for i, v in enumerate(value[:MAX_SLICE]):
                        col.put_of(i)(x, v)
        return fed


def _first_number(store: TypeStore, type_name: str, depth: int = 0) -> str:
    """A path to the first numeric field of a type, for hints."""
    for f in store.msg(type_name).fields:
        if f.is_array or f.base == "std_msgs/Header":
            continue
        if f.base in extract.NUMERIC_TYPES:
            return f.name
        if depth < 8 and f.base not in ("string",) and store.has_msg(f.base):
            inner = _first_number(store, f.base, depth + 1)
            if inner:
                return f"{f.name}/{inner}"
    return ""
