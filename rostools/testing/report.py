"""What the graph looked like: the text the plugin attaches to a failed test's report."""

from __future__ import annotations

from collections.abc import Iterable, Mapping
from typing import Any

from rostools.errors import RostoolsError, one_line
from rostools.rosgraph.masterapi import MasterProxy

#: A message longer than this (as text) is cut, so a report stays readable.
MAX_MESSAGE = 400
#: At most this many parameter names are listed.
MAX_PARAMS = 50


def _short(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= MAX_MESSAGE else text[: MAX_MESSAGE - 3] + "..."


def graph_report(
    master_uri: str,
    last_messages: Mapping[str, Any] | None = None,
    extra: Iterable[str] = (),
) -> str:
    """The graph on ``master_uri`` as text, for a failed test's report.

    Topics with their type, publishers and subscribers; services, nodes and parameter
    names; then the last message of each subscribed topic, then the ``extra`` lines.
    """
    lines = [f"master: {master_uri}"]
    master = MasterProxy(master_uri, "/rostools_report", timeout=2.0)
    try:
        pubs, subs, services = master.system_state()
        types = master.topic_types()
        params = master.param_names()
    except RostoolsError as err:
        lines.append(f"(the master did not answer: {err})")
    else:
        publishers = {t: n for t, n in pubs}
        subscribers = {t: n for t, n in subs}
        topics = sorted(set(publishers) | set(subscribers))
        lines.append(f"topics ({len(topics)}):")
        for topic in topics:
            lines.append(f"  {topic} [{types.get(topic, '?')}]")
            lines.append(f"    publishers: {', '.join(publishers.get(topic, [])) or '-'}")
            lines.append(f"    subscribers: {', '.join(subscribers.get(topic, [])) or '-'}")
        lines.append(f"services ({len(services)}): {', '.join(s for s, _ in services) or '-'}")
        nodes = sorted({n for _, names in (*pubs, *subs, *services) for n in names})
        lines.append(f"nodes ({len(nodes)}): {', '.join(nodes) or '-'}")
        shown = sorted(params)[:MAX_PARAMS]
        more = f" (and {len(params) - len(shown)} more)" if len(params) > len(shown) else ""
        lines.append(f"parameters ({len(params)}): {', '.join(shown) or '-'}{more}")
    finally:
        master.http.close()
    lines = [one_line(line) for line in lines]  # the names are the peers': one line each
    if last_messages:
        lines.append("last message of each subscribed topic:")
        for topic, msg in sorted(last_messages.items()):
            lines.append(f"  {topic}: {'(none yet)' if msg is None else _short(msg)}")
    lines.extend(extra)
    return "\n".join(lines)
