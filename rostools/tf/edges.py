"""The tree's edges as tf2's buffer keeps them: what ``view_frames`` draws on each.

Per child frame, tf2's ``BufferCore`` keeps a time cache (``/tf``: every stamp within its cache
time of the newest; ``/tf_static``: the last one, stamped 0) and the broadcaster that last set
it. ``allFramesAsYAML`` reads each cache as parent, broadcaster, rate (entries over the span,
the span at least 0.1 ms), most recent and oldest stamp, and buffer length (the span). ``Edges``
keeps the same counts from the same inputs, without the transforms, so that its numbers equal
tf2's for one feed (``tests/interop/test_tf_frames_interop.py`` feeds both).
"""

from __future__ import annotations

import bisect
import math
from dataclasses import dataclass, field

from rostools.tf.records import Stamped

#: tf2's default cache time (``BufferCore::DEFAULT_CACHE_TIME``), in ns.
DEFAULT_CACHE_NS = 10_000_000_000
#: tf2's floor under the span a rate is taken over, in seconds (``allFramesAsYAML``).
MIN_SPAN = 0.0001
#: How far from 1 a quaternion's squared norm may be before tf2 refuses it.
NORM_TOLERANCE = 10e-6
#: The broadcaster tf2 names when none was given.
NO_AUTHORITY = "no recorded authority"
#: How text names a broadcaster whose callerid was not recorded (tf_monitor's word).
UNKNOWN_BROADCASTER = "unknown_publisher"


def shown_broadcaster(who: str) -> str:
    """A broadcaster as text shows it: a bag may not have kept its callerid."""
    return who or UNKNOWN_BROADCASTER


def refusal(t: Stamped) -> str | None:
    """Why tf2's ``setTransform`` refuses ``t`` (its error's name), or None if it takes it."""
    if not t.child:
        return "TF_NO_CHILD_FRAME_ID"
    if not t.parent:
        return "TF_NO_FRAME_ID"
    if t.child == t.parent:
        return "TF_SELF_TRANSFORM"
    if not all(math.isfinite(v) for v in (*t.translation, *t.rotation)):
        return "TF_NAN_INPUT"
    if abs(sum(v * v for v in t.rotation) - 1.0) > NORM_TOLERANCE:
        return "TF_DENORMALIZED_QUATERNION"
    return None


@dataclass(slots=True)
class Edge:
    """One child frame's cache: its stamps (newest last) and parents, and its broadcaster."""

    child: str
    static: bool
    broadcaster: str = NO_AUTHORITY
    #: Stamps in ns, ascending; a static frame keeps one, read as 0 (tf2's ``StaticCache``).
    stamps: list[int] = field(default_factory=list)
    #: The parent of each stamp, in the same order.
    parents: list[str] = field(default_factory=list)

    @property
    def parent(self) -> str:
        """The parent of the newest entry (tf2's ``getData(Time())``)."""
        return self.parents[-1]

    @property
    def newest_ns(self) -> int:
        """The most recent stamp (0 for a static frame, as tf2 reads it)."""
        return 0 if self.static else self.stamps[-1]

    @property
    def oldest_ns(self) -> int:
        """The oldest stamp kept (0 for a static frame)."""
        return 0 if self.static else self.stamps[0]

    @property
    def length(self) -> int:
        """Entries kept (1 for a static frame)."""
        return len(self.stamps)

    @property
    def span(self) -> float:
        """The buffer length: newest less oldest, in seconds."""
        return (self.newest_ns - self.oldest_ns) / 1e9

    @property
    def rate(self) -> float:
        """Entries a second over the span, as tf2's ``allFramesAsYAML`` (at least 0.1 ms)."""
        return self.length / max(self.span, MIN_SPAN)

    def insert(self, stamp_ns: int, parent: str, cache_ns: int) -> bool:
        """Keep one entry as tf2's cache would; whether it was taken."""
        if self.static:
            self.stamps[:], self.parents[:] = [stamp_ns], [parent]
            return True
        if self.stamps and self.stamps[-1] > stamp_ns + cache_ns:
            return False  # TF_OLD_DATA
        at = bisect.bisect_left(self.stamps, stamp_ns)
        if at < len(self.stamps) and self.stamps[at] == stamp_ns:
            return False  # TF_REPEATED_DATA: tf2 keeps the first
        self.stamps.insert(at, stamp_ns)
        self.parents.insert(at, parent)
        newest = self.stamps[-1]
        drop = bisect.bisect_left(self.stamps, newest - cache_ns)
        if drop:
            del self.stamps[:drop], self.parents[:drop]
        return True

    def to_data(self) -> dict[str, object]:
        """The edge as ``allFramesAsYAML`` gives it, numbers unrounded."""
        return {
            "parent": self.parent,
            "child": self.child,
            "broadcaster": self.broadcaster,
            "static": self.static,
            "rate": self.rate,
            "most_recent_transform": self.newest_ns / 1e9,
            "oldest_transform": self.oldest_ns / 1e9,
            "buffer_length": self.span,
        }


class Edges:
    """Every child frame's edge, fed transforms as tf2's listener feeds its buffer.

    ``cache_ns`` is how long a ``/tf`` frame's entries are kept (tf2's cache time).
    """

    def __init__(self, cache_ns: int = DEFAULT_CACHE_NS) -> None:
        self.cache_ns = cache_ns
        #: Child frame -> its edge, in the order frames were first seen (as tf2 numbers them).
        self.by_child: dict[str, Edge] = {}
        #: Transforms refused, by tf2's reason.
        self.refused: dict[str, int] = {}

    def add(self, transforms: list[Stamped], broadcaster: str, static: bool) -> None:
        """One ``/tf`` (or, ``static``, ``/tf_static``) message from ``broadcaster``."""
        for t in transforms:
            if (why := refusal(t)) is not None:
                self.refused[why] = self.refused.get(why, 0) + 1
                continue
            edge = self.by_child.get(t.child)
            if edge is None:  # a cache is static or not from its first entry on, as tf2's
                edge = self.by_child[t.child] = Edge(t.child, static)
            if edge.insert(t.stamp_ns, t.parent, self.cache_ns):
                edge.broadcaster = broadcaster  # as given, even empty: tf2 keeps it so

    def edges(self) -> list[Edge]:
        """The edges, by child frame name."""
        return [self.by_child[c] for c in sorted(self.by_child)]

    def frames(self) -> list[str]:
        """Every frame named, parents and children, sorted."""
        names = set(self.by_child)
        names.update(e.parent for e in self.by_child.values())
        return sorted(names)

    def roots(self) -> list[str]:
        """The frames that are no edge's child: the trees' tops."""
        return [f for f in self.frames() if f not in self.by_child]

    def children(self) -> dict[str, list[str]]:
        """Parent -> its children, sorted."""
        out: dict[str, list[str]] = {}
        for edge in self.edges():
            out.setdefault(edge.parent, []).append(edge.child)
        return out
