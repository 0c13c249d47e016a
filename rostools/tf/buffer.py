"""A transform buffer with tf2 ``BufferCore``'s semantics, without tf2.

Per child frame a time-ordered cache (``cache_time_ns`` long, 10 s as tf2's), or for a
static transform one value kept for all time; a lookup walks both frames up to their common
parent, interpolating each edge between its two neighbouring stamps (translation linearly,
rotation by slerp), and fails with tf2's own words. Time 0 means the latest time at which
every edge on the path has data, as tf2's ``getLatestCommonTime``.

The per-lookup arithmetic is plain floats in tf2's own order of operations (``_mul``,
``_rotate``, ``_slerp``): for one transform, numpy's cost per call is ten times the work
(``rostools.tf.math`` holds the array forms, for many values at once).
"""

from __future__ import annotations

import math
from bisect import bisect_left, bisect_right
from dataclasses import dataclass

from rostools.errors import NotFoundError, RostoolsError, UsageError
from rostools.tf.records import Stamped, strip_slash

#: tf2's default cache time (``BufferCore::DEFAULT_CACHE_TIME``), in ns.
DEFAULT_CACHE_NS = 10_000_000_000
_NS = 1_000_000_000
#: tf2's ``MAX_GRAPH_DEPTH``: a walk longer than this is a loop.
MAX_DEPTH = 1000

# A transform as the walk carries it: tx, ty, tz, qx, qy, qz, qw.
Seven = tuple[float, float, float, float, float, float, float]
_IDENTITY: Seven = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)


class TransformError(RostoolsError):
    """A lookup that tf2 would refuse; ``kind`` names tf2's exception."""

    kind = "TransformException"


class ConnectivityError(TransformError):
    """The two frames are not in the same tree (tf2's ``ConnectivityException``)."""

    kind = "ConnectivityException"


class ExtrapolationError(TransformError):
    """The time asked is outside what the buffer holds (tf2's ``ExtrapolationException``)."""

    kind = "ExtrapolationException"


class LoopError(TransformError):
    """The tree has a loop (tf2's ``LookupException``, with its words)."""

    kind = "LookupException"


class FrameNotFoundError(NotFoundError):
    """A frame the buffer has never heard of (tf2's ``LookupException``; exit 3)."""

    kind = "LookupException"


class InvalidFrameError(UsageError):
    """An empty frame id, or one with a leading ``/`` (tf2's ``InvalidArgumentException``)."""

    kind = "InvalidArgumentException"


@dataclass(frozen=True, slots=True)
class Rejected:
    """A transform ``set_transform`` did not take, and tf2's reason (``TF_OLD_DATA``, ...)."""

    code: str
    message: str


def _mul(a: tuple[float, ...], b: tuple[float, ...]) -> tuple[float, float, float, float]:
    """Hamilton product ``a * b`` of two ``(x, y, z, w)``, as tf2's ``Quaternion::operator*=``."""
    ax, ay, az, aw = a[-4:]
    bx, by, bz, bw = b[-4:]
    return (
        aw * bx + ax * bw + ay * bz - az * by,
        aw * by + ay * bw + az * bx - ax * bz,
        aw * bz + az * bw + ax * by - ay * bx,
        aw * bw - ax * bx - ay * by - az * bz,
    )


def _rotate(q: tuple[float, ...], x: float, y: float, z: float) -> tuple[float, float, float]:
    """tf2's ``quatRotate(q, v)``: ``q * v * q.inverse()``, the inverse being the conjugate."""
    qx, qy, qz, qw = q[-4:]
    px = qw * x + qy * z - qz * y
    py = qw * y + qz * x - qx * z
    pz = qw * z + qx * y - qy * x
    pw = -qx * x - qy * y - qz * z
    # (p) * (-qx, -qy, -qz, qw)
    return (
        pw * -qx + px * qw + py * -qz - pz * -qy,
        pw * -qy + py * qw + pz * -qx - px * -qz,
        pw * -qz + pz * qw + px * -qy - py * -qx,
    )


def _accum(
    st: Seven, v: tuple[float, float, float], q: tuple[float, float, float, float]
) -> tuple[tuple[float, float, float], tuple[float, float, float, float]]:
    """tf2's ``TransformAccum::accum``: ``st`` applied after ``(v, q)``.

    ``_rotate`` and ``_mul`` written out, in their order of operations: the walk's inner loop.
    """
    tx, ty, tz, qx, qy, qz, qw = st
    x, y, z = v
    px = qw * x + qy * z - qz * y
    py = qw * y + qz * x - qx * z
    pz = qw * z + qx * y - qy * x
    pw = -qx * x - qy * y - qz * z
    bx, by, bz, bw = q
    return (
        pw * -qx + px * qw + py * -qz - pz * -qy + tx,
        pw * -qy + py * qw + pz * -qx - px * -qz + ty,
        pw * -qz + pz * qw + px * -qy - py * -qx + tz,
    ), (
        qw * bx + qx * bw + qy * bz - qz * by,
        qw * by + qy * bw + qz * bx - qx * bz,
        qw * bz + qz * bw + qx * by - qy * bx,
        qw * bw - qx * bx - qy * by - qz * bz,
    )


def _acos(x: float) -> float:
    """tf2's ``tf2Acos``: clamped to [-1, 1] first."""
    return math.acos(-1.0 if x < -1.0 else 1.0 if x > 1.0 else x)


def _slerp(a: Seven, b: Seven, t: float) -> tuple[float, float, float, float]:
    """tf2's ``Quaternion::slerp``: the short way round, not renormalised."""
    ax, ay, az, aw = a[3:]
    bx, by, bz, bw = b[3:]
    dot = ax * bx + ay * by + az * bz + aw * bw
    s = math.sqrt((ax * ax + ay * ay + az * az + aw * aw) * (bx * bx + by * by + bz * bz + bw * bw))
    theta = _acos(-dot / s) if dot < 0 else _acos(dot / s)  # tf2: angleShortestPath / 2
    if theta == 0.0:
        return ax, ay, az, aw
    d = 1.0 / math.sin(theta)
    s0 = math.sin((1.0 - t) * theta)
    s1 = math.sin(t * theta)
    if dot < 0:
        return (
            (ax * s0 + -bx * s1) * d,
            (ay * s0 + -by * s1) * d,
            (az * s0 + -bz * s1) * d,
            (aw * s0 + -bw * s1) * d,
        )
    return (
        (ax * s0 + bx * s1) * d,
        (ay * s0 + by * s1) * d,
        (az * s0 + bz * s1) * d,
        (aw * s0 + bw * s1) * d,
    )


def _stamp(ns: int) -> str:
    """A time as tf2's messages print it (``%.09f``)."""
    secs, nsecs = divmod(ns, 1_000_000_000)
    return f"{secs}.{nsecs:09d}"


class _Cache:
    """One child frame's transforms to its parent: tf2's ``TimeCache`` (oldest first here)."""

    __slots__ = ("data", "parents", "stamps")

    def __init__(self) -> None:
        self.stamps: list[int] = []
        self.parents: list[str] = []
        self.data: list[Seven] = []

    def insert(self, stamp: int, parent: str, value: Seven, keep_ns: int) -> str | None:
        """Add one; tf2's code for a refusal (``TF_OLD_DATA``, ``TF_REPEATED_DATA``), or None."""
        stamps = self.stamps
        if stamps and stamps[-1] > stamp + keep_ns:
            return "TF_OLD_DATA"
        at = bisect_right(stamps, stamp)
        if at and stamps[at - 1] == stamp:
            return "TF_REPEATED_DATA"  # the first of a stamp stays, as tf2's
        stamps.insert(at, stamp)
        self.parents.insert(at, parent)
        self.data.insert(at, value)
        cut = bisect_left(stamps, stamps[-1] - keep_ns)  # older than latest - cache time
        if cut:
            del stamps[:cut], self.parents[:cut], self.data[:cut]
        return None

    def latest(self) -> tuple[int, str | None]:
        """tf2's ``getLatestTimeAndParent``: (0, None) when empty."""
        if not self.stamps:
            return 0, None
        return self.stamps[-1], self.parents[-1]

    def get(self, time: int) -> tuple[str, Seven] | str:
        """The parent and transform at ``time`` (0: the latest), or tf2's reason it has none."""
        stamps = self.stamps
        if stamps:  # the usual cases first: the latest, and between two stamps
            if time == 0:
                return self.parents[-1], self.data[-1]
            if stamps[0] < time < stamps[-1]:
                return self._between(time, bisect_right(stamps, time))
        return self._edge(time)

    def _between(self, time: int, newer: int) -> tuple[str, Seven]:
        """Interpolated between the stamps at ``newer - 1`` and ``newer``."""
        stamps, parents = self.stamps, self.parents
        older = newer - 1
        parent = parents[older]
        if parents[newer] != parent:
            return parent, self.data[older]  # the parent changed: the older holds, as tf2's
        one, two = self.data[older], self.data[newer]
        # ros::Duration::toSec() of each: whole seconds plus 1e-9 times the nanoseconds
        a, b = time - stamps[older], stamps[newer] - stamps[older]
        ratio = (a // _NS + 1e-9 * (a % _NS)) / (b // _NS + 1e-9 * (b % _NS))
        keep = 1.0 - ratio
        return parent, (
            keep * one[0] + ratio * two[0],
            keep * one[1] + ratio * two[1],
            keep * one[2] + ratio * two[2],
            *_slerp(one, two, ratio),
        )

    def _edge(self, time: int) -> tuple[str, Seven] | str:
        """tf2's ``findClosest`` where ``time`` is not strictly inside: a stamp, or why not."""
        stamps = self.stamps
        n = len(stamps)
        if n == 0:
            return "Lookup would require extrapolation into the past, but the cache is empty"
        if time == 0:
            return self.parents[-1], self.data[-1]
        if n == 1:
            if stamps[0] == time:
                return self.parents[0], self.data[0]
            return (
                f"Lookup would require extrapolation at time {_stamp(time)}, "
                f"but only time {_stamp(stamps[0])} is in the buffer"
            )
        latest, earliest = stamps[-1], stamps[0]
        if time == latest:
            return self.parents[-1], self.data[-1]
        if time == earliest:
            return self.parents[0], self.data[0]
        if time > latest:
            return (
                f"Lookup would require extrapolation {_stamp(time - latest)}s into the future."
                f"  Requested time {_stamp(time)} but the latest data is at time {_stamp(latest)}"
            )
        return (
            f"Lookup would require extrapolation {_stamp(earliest - time)}s into the past."
            f"  Requested time {_stamp(time)} but the earliest data is at time "
            f"{_stamp(earliest)}"
        )


class _Static:
    """A static transform: tf2's ``StaticCache``, one value for every time."""

    __slots__ = ("data", "parent")

    def __init__(self) -> None:
        self.parent: str | None = None
        self.data: Seven = _IDENTITY

    def insert(self, stamp: int, parent: str, value: Seven, keep_ns: int) -> str | None:
        """Replace the value (a static transform sent again overrides the last)."""
        self.parent, self.data = parent, value
        return None

    def latest(self) -> tuple[int, str | None]:
        """Time 0 (it holds at every time) and the parent."""
        return 0, self.parent

    def get(self, time: int) -> tuple[str, Seven] | str:
        """The value, whatever the time."""
        if self.parent is None:
            return "Lookup would require extrapolation into the past, but the cache is empty"
        return self.parent, self.data


class TransformBuffer:
    """tf2's ``BufferCore``: transforms in, ``lookup(target, source, time_ns)`` out.

    Frame ids are kept without a leading ``/`` (``set_transform`` strips it, as tf2's).
    """

    def __init__(self, cache_time_ns: int = DEFAULT_CACHE_NS) -> None:
        self.cache_time_ns = cache_time_ns
        #: Every frame named so far, as child or parent, in the order tf2 numbers them.
        self.known: dict[str, None] = {}
        self.caches: dict[str, _Cache | _Static] = {}
        #: The authority (broadcaster) of each frame's last accepted transform.
        self.authority: dict[str, str] = {}

    def set_transform(
        self, t: Stamped, authority: str = "", static: bool = False
    ) -> Rejected | None:
        """Add one transform; what tf2 would refuse is refused, and the reason returned."""
        child, parent = strip_slash(t.child), strip_slash(t.parent)
        problem = _refusal(t, child, parent, authority)
        if problem is not None:
            return problem
        self.known.setdefault(child)
        self.known.setdefault(parent)
        cache = self.caches.get(child)
        if cache is None:  # the first transform decides what kind of frame it is, as tf2's
            cache = self.caches[child] = _Static() if static else _Cache()
        code = cache.insert(t.stamp_ns, parent, (*t.translation, *t.rotation), self.cache_time_ns)
        if code is not None:
            what = "redundant timestamp" if code == "TF_REPEATED_DATA" else "data from the past"
            return Rejected(
                code,
                f"{code} ignoring {what} for frame {child} at time {t.stamp_ns / 1e9:f}"
                f" according to authority {authority}",
            )
        self.authority[child] = authority
        return None

    def set_transforms(
        self, transforms: list[Stamped], authority: str = "", static: bool = False
    ) -> list[Rejected]:
        """Add one message's transforms; those refused, with tf2's reasons."""
        out = []
        for t in transforms:
            problem = self.set_transform(t, authority, static)
            if problem is not None:
                out.append(problem)
        return out

    def frames(self) -> list[str]:
        """Every frame id the buffer has heard of."""
        return list(self.known)

    def has_frame(self, frame: str) -> bool:
        """Whether ``frame`` was named by some transform."""
        return frame in self.known

    def parent(self, frame: str, time_ns: int = 0) -> str | None:
        """``frame``'s parent at ``time_ns`` (0: the latest), or None (a root, or no data)."""
        cache = self.caches.get(frame)
        if cache is None:
            return None
        found = cache.get(time_ns)
        return None if isinstance(found, str) else found[0]

    def lookup(self, target: str, source: str, time_ns: int = 0) -> Stamped:
        """The transform that takes data in ``source`` to ``target`` at ``time_ns``.

        ``parent`` is ``target`` and ``child`` is ``source`` in the answer; its stamp is the
        time looked up (0: the latest common time). Raises the ``TransformError`` and
        ``FrameNotFoundError``/``InvalidFrameError`` that tf2's ``lookupTransform`` would.
        """
        if target == source:
            stamp = time_ns
            cache = self.caches.get(target)
            if time_ns == 0 and cache is not None:
                stamp = cache.latest()[0]
            return Stamped(target, source, stamp, (0.0, 0.0, 0.0), (0.0, 0.0, 0.0, 1.0))
        self._validate(target, "target_frame")
        self._validate(source, "source_frame")
        time = time_ns if time_ns else self.latest_common_time(target, source)
        value = self._walk(target, source, time)
        return Stamped(target, source, time, value[:3], value[3:])

    def _validate(self, frame: str, argument: str) -> None:
        what = f"lookupTransform argument {argument}"
        if not frame:
            raise InvalidFrameError(
                f"Invalid argument passed to {what} in tf2 frame_ids cannot be empty"
            )
        if frame.startswith("/"):
            raise InvalidFrameError(
                f'Invalid argument "{frame}" passed to {what} in tf2 frame_ids cannot start'
                " with a '/' like: "
            )
        if frame not in self.known:
            known = sorted(self.known)
            hint = (
                "no transform has been received"
                if not known
                else "the frames are "
                + ", ".join(known[:12])
                + (", ..." if len(known) > 12 else "")
            )
            raise FrameNotFoundError(f'"{frame}" passed to {what} does not exist. ', hint=hint)

    def latest_common_time(self, target: str, source: str) -> int:
        """tf2's ``getLatestCommonTime``: the latest time every edge between them has data.

        0 when every edge on the path is static.
        """
        caches = self.caches
        if target == source:
            cache = caches.get(source)
            return cache.latest()[0] if cache is not None else 0
        chain: list[tuple[int, str]] = []  # (latest stamp, parent) up from source
        frame: str | None = source
        common = -1  # -1 stands for tf2's TIME_MAX: no stamp seen yet
        depth = 0
        while frame is not None:
            cache = caches.get(frame)
            if cache is None:
                break
            stamp, parent = cache.latest()
            if parent is None:
                break
            if stamp and (common < 0 or stamp < common):
                common = stamp
            chain.append((stamp, parent))
            frame = parent
            if frame == target:
                return max(common, 0)
            depth += 1
            if depth > MAX_DEPTH:
                raise self._loop()
        frame = target
        common = -1
        depth = 0
        meet: str | None = None
        parents = {p for _, p in chain}
        while True:
            cache = caches.get(frame)
            if cache is None:
                break
            stamp, parent = cache.latest()
            if parent is None:
                break
            if stamp and (common < 0 or stamp < common):
                common = stamp
            if parent in parents:
                meet = parent
                break
            frame = parent
            if frame == source:
                return max(common, 0)
            depth += 1
            if depth > MAX_DEPTH:
                raise self._loop()
        if meet is None:
            raise ConnectivityError(_not_connected(target, source))
        for stamp, parent in chain:
            if stamp and (common < 0 or stamp < common):
                common = stamp
            if parent == meet:
                break
        return max(common, 0)

    def _walk(self, target: str, source: str, time: int) -> Seven:
        """tf2's ``walkToTopParent`` with its ``TransformAccum``: the composed transform."""
        caches = self.caches
        sv = (0.0, 0.0, 0.0)
        sq: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
        frame: str | None = source
        top = source
        depth = 0
        why: str | None = None  # an edge up from the source had no data at this time
        while frame is not None:
            cache = caches.get(frame)
            if cache is None:
                top = frame
                break
            found = cache.get(time)
            if isinstance(found, str):
                top, why = frame, found
                break
            if frame == target:
                return (*sv, *sq)  # the target is the source's ancestor
            parent, st = found
            sv, sq = _accum(st, sv, sq)
            top = frame
            frame = parent
            depth += 1
            if depth > MAX_DEPTH:
                raise self._loop()
        tv = (0.0, 0.0, 0.0)
        tq: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 1.0)
        frame = target
        depth = 0
        while frame != top:
            cache = caches.get(frame)
            if cache is None:
                break
            found = cache.get(time)
            if isinstance(found, str):
                raise ExtrapolationError(_extrapolation(found, target, source))
            if frame == source:  # the source is the target's ancestor
                iq = (-tq[0], -tq[1], -tq[2], tq[3])
                return (*_rotate(iq, -tv[0], -tv[1], -tv[2]), *iq)
            parent, st = found
            tv, tq = _accum(st, tv, tq)
            frame = parent
            depth += 1
            if depth > MAX_DEPTH:
                raise self._loop()
        if frame != top:
            if why is not None:
                raise ExtrapolationError(_extrapolation(why, target, source))
            raise ConnectivityError(_not_connected(target, source))
        iq = (-tq[0], -tq[1], -tq[2], tq[3])
        ix, iy, iz = _rotate(iq, -tv[0], -tv[1], -tv[2])
        x, y, z = _rotate(iq, *sv)
        return (x + ix, y + iy, z + iz, *_mul(iq, sq))

    def _loop(self) -> LoopError:
        lines = [
            f"Frame {child} exists with parent {cache.latest()[1]}."
            for child in self.known
            if (cache := self.caches.get(child)) is not None and cache.latest()[1] is not None
        ]
        return LoopError("The tf tree is invalid because it contains a loop. " + " ".join(lines))


def _refusal(t: Stamped, child: str, parent: str, authority: str) -> Rejected | None:
    """tf2's checks before a transform is stored (its codes and words)."""
    if child == parent:
        return Rejected(
            "TF_SELF_TRANSFORM",
            f'TF_SELF_TRANSFORM: Ignoring transform from authority "{authority}" with frame_id'
            f' and child_frame_id  "{child}" because they are the same',
        )
    if not child:
        return Rejected(
            "TF_NO_CHILD_FRAME_ID",
            f'TF_NO_CHILD_FRAME_ID: Ignoring transform from authority "{authority}" because'
            " child_frame_id not set ",
        )
    if not parent:
        return Rejected(
            "TF_NO_FRAME_ID",
            f'TF_NO_FRAME_ID: Ignoring transform with child_frame_id "{child}"  from authority'
            f' "{authority}" because frame_id not set',
        )
    values = (*t.translation, *t.rotation)
    if any(math.isnan(v) for v in values):
        return Rejected(
            "TF_NAN_INPUT",
            f'TF_NAN_INPUT: Ignoring transform for child_frame_id "{child}" from authority'
            f' "{authority}" because of a nan value in the transform',
        )
    qx, qy, qz, qw = t.rotation
    if not abs(qw * qw + qx * qx + qy * qy + qz * qz - 1.0) < 10e-6:
        return Rejected(
            "TF_DENORMALIZED_QUATERNION",
            f'TF_DENORMALIZED_QUATERNION: Ignoring transform for child_frame_id "{child}" from'
            f' authority "{authority}" because of an invalid quaternion in the transform'
            f" ({qx:f} {qy:f} {qz:f} {qw:f})",
        )
    return None


def _not_connected(target: str, source: str) -> str:
    return (
        f"Could not find a connection between '{target}' and '{source}' because they are not"
        " part of the same tree.Tf has two or more unconnected trees."
    )


def _extrapolation(why: str, target: str, source: str) -> str:
    return f"{why}, when looking up transform from frame [{source}] to frame [{target}]"
