"""``bag info`` as rosbag prints it, and as data (rosbag's ``--yaml`` keys, plus ours)."""

from __future__ import annotations

import json
import re
import time
from typing import Any

from rostools.bag.formats.model import BagInfo
from rostools.cli.bag.shared import human_size
from rostools.errors import UsageError, one_line

_NS = 1_000_000_000


def human_frequency(freq: float) -> str:
    """rosbag's 1000-based rates."""
    for suffix in ("Hz", "kHz", "MHz", "GHz", "THz"):
        if freq < 1000.0:
            return f"{freq:.1f} {suffix}"
        freq /= 1000.0
    return "-"


def time_text(secs: float) -> str:
    """``Nov 22 2026 06:41:04.90``, local time, as rosbag prints it."""
    fraction = f"{secs - int(secs):.2f}"[1:]
    return time.strftime("%b %d %Y %H:%M:%S", time.localtime(secs)) + fraction


def duration_text(duration: float) -> str:
    """``3.2s``, ``3:48s (228s)`` or ``1hr 2:03s (3723s)``."""
    secs = duration % 60
    mins = int(duration / 60)
    hours = int(mins / 60)
    if hours > 0:
        return "%dhr %d:%02ds (%ds)" % (hours, mins % 60, secs, duration)  # noqa: UP031
    if mins > 0:
        return "%d:%02ds (%ds)" % (mins, secs, duration)  # noqa: UP031
    return f"{duration:.1f}s"


def info_text(
    info: BagInfo, frequencies: dict[str, float] | None = None, name: str | None = None
) -> str:
    """The text ``rosbag info`` prints, for a ``.bag`` or an MCAP file.

    Names, types, sums and the library are the file's: each is escaped (``one_line``).
    """
    rows: list[tuple[str, str]] = [("path", one_line(name or str(info.path)))]
    version = info.version if info.format == "bag" else f"mcap ({info.profile or 'no'} profile)"
    rows.append(("version", one_line(version)))
    if info.format == "mcap" and info.library:
        rows.append(("library", one_line(info.library)))
    if info.start_ns is None or info.end_ns is None:
        rows.append(("size", human_size(info.size)))
        return _table(rows + _extras_rows(info))
    start, end = info.start_ns / _NS, info.end_ns / _NS
    duration = end - start
    rows.append(("duration", duration_text(duration)))
    rows.append(("start", f"{time_text(start)} ({start:.2f})"))
    rows.append(("end", f"{time_text(end)} ({end:.2f})"))
    rows.append(("size", human_size(info.size)))
    rows.append(("messages", str(info.message_count)))
    rows += _compression_rows(info, duration)
    rows += _extras_rows(info)
    rows += _type_and_topic_rows(info, frequencies or {})
    return _table(rows)


def _extras_rows(info: BagInfo) -> list[tuple[str, str]]:
    """MCAP attachments and metadata records, when there are any."""
    counts = (("attachments", info.attachment_count), ("metadata", info.metadata_count))
    return [(label, str(n)) for label, n in counts if n and info.format == "mcap"]


def _compression_rows(info: BagInfo, duration: float) -> list[tuple[str, str]]:
    if not info.compression:
        return [("compression", "none")]
    chunks = sum(c.chunks for c in info.compression)
    parts = []
    for c in info.compression:
        if c.compression != "none" and c.uncompressed_size:
            fraction = 100.0 * c.compressed_size / c.uncompressed_size
            parts.append(f"{one_line(c.compression)} [{c.chunks}/{chunks} chunks; {fraction:.2f}%]")
        else:
            parts.append(f"{one_line(c.compression)} [{c.chunks}/{chunks} chunks]")
    rows = [("compression", ", ".join(parts))]
    if all(c.compression == "none" for c in info.compression) or not info.uncompressed_size:
        return rows
    raw, stored = human_size(info.uncompressed_size), human_size(info.compressed_size)
    width = max(len(raw), len(stored))
    if duration > 0:
        raw_rate = human_size(info.uncompressed_size / duration)
        stored_rate = human_size(info.compressed_size / duration)
        rate_width = max(len(raw_rate), len(stored_rate))
        percent = 100.0 * info.compressed_size / info.uncompressed_size
        rows.append(("uncompressed", f"{raw:>{width}} @ {raw_rate:>{rate_width}}/s"))
        rows.append(
            ("compressed", f"{stored:>{width}} @ {stored_rate:>{rate_width}}/s ({percent:.2f}%)")
        )
    else:
        rows.append(("uncompressed", f"{raw:>{width}}"))
        rows.append(("compressed", f"{stored:>{width}}"))
    return rows


def _type_and_topic_rows(info: BagInfo, freqs: dict[str, float]) -> list[tuple[str, str]]:
    rows: list[tuple[str, str]] = []
    if not info.topics:
        return rows
    types = [(one_line(k), one_line(v)) for k, v in sorted(info.types.items())]
    topics = [one_line(t.topic) for t in info.topics]
    type_width = max(len(k) for k, _ in types)
    for i, (kind, md5) in enumerate(types):
        rows.append(("types" if i == 0 else "", f"{kind:<{type_width}} [{md5}]"))
    topic_width = max(map(len, topics))
    count_width = max(len(str(t.messages)) for t in info.topics)
    freq_width = max((len(human_frequency(f)) for f in freqs.values()), default=0)
    for i, (shown, t) in enumerate(zip(topics, info.topics, strict=True)):
        unit = "msgs" if t.messages > 1 else "msg "
        text = f"{shown:<{topic_width}}   {t.messages:>{count_width}} {unit}"
        if t.topic in freqs:
            text += f" @ {human_frequency(freqs[t.topic]):>{freq_width}}"
        else:
            text += "   " + " " * freq_width
        text += f" : {one_line(t.type):<{type_width}}"
        if t.connections > 1:
            text += f" ({t.connections} connections)"
        rows.append(("topics" if i == 0 else "", text))
    return rows


def _table(rows: list[tuple[str, str]]) -> str:
    width = max(len(field) for field, _ in rows) + 1
    lines = [f"{(field + ':') if field else '':<{width}} {value}" for field, value in rows]
    return "\n".join(lines).rstrip()


def info_data(
    info: BagInfo, frequencies: dict[str, float] | None = None, name: str | None = None
) -> dict[str, Any]:
    """``rosbag info --yaml``'s keys (times in seconds, sizes in bytes), plus ours.

    ``indexed`` is rosbag's: False for a bag read without its index, and for a bag without
    chunks (an empty one).
    """
    data: dict[str, Any] = {
        "path": name or str(info.path),
        "version": info.version,
        "format": info.format,
    }
    if info.format == "mcap":
        data |= {"profile": info.profile, "library": info.library}
    if info.start_ns is not None and info.end_ns is not None:
        start, end = info.start_ns / _NS, info.end_ns / _NS
        data |= {"duration": _micro(end - start), "start": _micro(start), "end": _micro(end)}
    indexed = info.indexed and bool(info.chunk_count or info.message_count)
    data |= {"size": info.size, "messages": info.message_count, "indexed": indexed}
    data["compression"] = info.compression[0].compression if info.compression else "none"
    if any(c.compression != "none" for c in info.compression):
        data |= {"uncompressed": info.uncompressed_size, "compressed": info.compressed_size}
    data["chunks"] = info.chunk_count
    if info.format == "mcap":
        data |= {"attachments": info.attachment_count, "metadata": info.metadata_count}
    data["types"] = [{"type": k, "md5": v} for k, v in sorted(info.types.items())]
    topics = []
    for t in info.topics:
        row: dict[str, Any] = {"topic": t.topic, "type": t.type, "messages": t.messages}
        if t.connections > 1:
            row["connections"] = t.connections
        if frequencies and t.topic in frequencies:
            row["frequency"] = frequencies[t.topic]
        topics.append(row)
    data["topics"] = topics
    return data


#: How rosbag's YAML writes these numbers.
_FIXED = {"duration": "%.6f", "start": "%.6f", "end": "%.6f", "frequency": "%.4f"}


def info_yaml(data: dict[str, Any]) -> str:
    """``info_data`` as ``rosbag info -y`` writes it, our own keys where they fit.

    ``version: 2.0``, ``indexed: True``, times with 6 decimals, lists indented by 4. A name
    that YAML would read as something else (``a: b``, ``true``) is quoted.
    """
    lines = []
    for key, value in data.items():
        if isinstance(value, list):
            if not value:
                lines.append(f"{key}: []")
                continue
            lines.append(f"{key}:")
            for row in value:
                for i, (k, v) in enumerate(row.items()):
                    lines.append(f"{'    - ' if i == 0 else '      '}{k}: {_scalar(k, v)}")
        elif key == "version" and data.get("format") == "bag":
            lines.append(f"version: {value}")  # a number, as rosbag's 2.0
        else:
            lines.append(f"{key}: {_scalar(key, value)}")
    return "\n".join(lines) + "\n"


def _scalar(key: str, value: Any) -> str:
    if isinstance(value, bool):
        return str(value)  # True, as rosbag's Python prints it
    if isinstance(value, float) and key in _FIXED:
        return _FIXED[key] % value
    if isinstance(value, int | float):
        return str(value)
    text = str(value)
    return text if _plain(text) else json.dumps(text, ensure_ascii=False)


def _plain(text: str) -> bool:
    """Whether YAML reads ``text``, unquoted, back as the same string."""
    import yaml

    if not text or text != text.strip() or not text.isprintable():
        return False
    try:
        return bool(yaml.safe_load(text) == text)
    except yaml.YAMLError:
        return False


def key_yaml(value: Any) -> str:
    """One value of ``info -y -k`` as rosbag prints it.

    Python's ``str`` of each scalar read back from its YAML (``2.0``, ``True``, ``1e-06``), a
    mapping as ``key: value`` lines, a list as ``- `` items, each ending its line (so a list
    ends in a blank line).
    """
    return _rosbag_value(value, 0) + "\n"


def _rosbag_value(value: Any, indent: int) -> str:
    pad = "  " * indent
    if isinstance(value, list):
        return "".join(f"{pad}- {_rosbag_value(item, indent + 1)}\n" for item in value)
    if isinstance(value, dict):
        return "\n".join(f"{pad if i else ''}{k}: {v}" for i, (k, v) in enumerate(value.items()))
    return pad + str(value)


def as_rosbag_reads(data: dict[str, Any]) -> dict[str, Any]:
    """``data`` as rosbag's ``-k`` sees it: its YAML text, read back."""
    import yaml

    loaded: dict[str, Any] = yaml.safe_load(info_yaml(data))
    return loaded


def _micro(seconds: float) -> float:
    """Seconds as rosbag's YAML gives them: printed with 6 decimals, then read back."""
    return float(f"{seconds:.6f}")


_KEY_STEP = re.compile(r"\.?([A-Za-z_]\w*)|\[(-?\d+)\]")


def info_key(data: dict[str, Any], key: str) -> Any:
    """The part of ``info_data`` at ``key``: ``duration``, ``topics[0].type`` (rosbag info -k)."""
    value: Any = data
    pos = 0
    while pos < len(key):
        step = _KEY_STEP.match(key, pos)
        if step is None or (pos == 0 and key.startswith(".")):
            raise UsageError(f"bad key {key!r}: use names and [index], e.g. topics[0].type")
        name, index = step.groups()
        try:
            value = value[name] if name is not None else value[int(index)]
        except (KeyError, IndexError, TypeError):
            if isinstance(value, dict):
                known = "keys here: " + ", ".join(value)
            else:
                known = f"{len(value)} entries here" if isinstance(value, list) else "a value here"
            raise UsageError(f"bag info has no key {key!r} ({known})") from None
        pos = step.end()
    return value
