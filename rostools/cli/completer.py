"""Tab completion, answered without importing typer: ``rostools __complete SHELL CWORD WORDS...``.

The shell scripts in ``completions/`` call this with the words of the command line. It walks
``tree.json`` (the command tree, generated from the Typer app) to see what the word under the
cursor is: a group, a command, an option, an option's value or a positional argument of some
kind. Live names (topics, services, nodes, parameters; tf frames from the first message of
each ``/tf`` and ``/tf_static`` publisher) come from the graph; types from the
type store; a topic's type and a message's YAML template after ``topic pub /t``, as rosbash
offered. The graph queries run under a hard deadline (``DEADLINE``), counted from the first
query, not from the process's start: a master that is down or slow costs at most that, and
what can be had offline is still offered. Offline words (groups, commands, options, option
choices, files, types) have no deadline: a busy machine makes them slow, never empty.

Output: one candidate per line, ``value<TAB>description``; or one directive line
``:files EXT...`` / ``:dirs`` asking the shell for its own file completion.
"""

from __future__ import annotations

import contextlib
import json
import os
import signal
import sys
import time
from collections.abc import Callable, Iterator, Sequence
from pathlib import Path
from typing import Any

from rostools.cli import output
from rostools.errors import one_line

#: Seconds the graph queries of one completion may take in all, counted from the first query
#: (``ROSTOOLS_COMPLETE_DEADLINE``). The interpreter's start-up is not counted: on a busy
#: machine it alone took longer, and nothing was completed, not even a command's name.
DEADLINE = 0.3
TREE = Path(__file__).with_name("tree.json")
Candidates = list[tuple[str, str]]


class _DeadlineError(Exception):
    """The deadline passed."""


def main(argv: Sequence[str]) -> int:
    """``SHELL CWORD WORDS...``: print the candidates for ``WORDS[CWORD]``."""
    if len(argv) < 2 or not argv[1].isdigit():
        sys.stderr.write("usage: rostools __complete SHELL CWORD WORDS...\n")
        return 2
    cword, words = int(argv[1]), list(argv[2:])
    budget = float(os.environ.get("ROSTOOLS_COMPLETE_DEADLINE", DEADLINE))
    lines = [
        f"{value}\t{help_text}" if help_text else value
        for value, help_text in Completer(words, cword, budget, argv[0]).complete()
    ]
    output.put("".join(line + "\n" for line in lines))
    return 0


def _late(signum: int, frame: Any) -> None:
    raise _DeadlineError


def load_tree() -> dict[str, Any]:
    """The command tree (see ``rostools.cli.completion.build_tree``)."""
    with TREE.open() as f:
        tree: dict[str, Any] = json.load(f)
    return tree


class Completer:
    """What can go at ``words[cword]``."""

    def __init__(
        self, words: list[str], cword: int, budget: float = DEADLINE, shell: str = "bash"
    ) -> None:
        self.shell = shell
        self.words, self.cword = _join_breaks(words, cword) if shell == "bash" else (words, cword)
        self.cur = self.words[self.cword] if self.cword < len(self.words) else ""
        #: What the shell replaces: bash only the part after "=" of ``--opt=value``.
        self.prefix = ""
        #: Seconds the graph queries may take; the clock starts at the first (``left``).
        self.budget = budget
        self.deadline: float | None = None
        self.master_uri = os.environ.get("ROS_MASTER_URI") or "http://localhost:11311"
        self.positionals: list[str] = []

    def left(self) -> float:
        """Seconds left before the deadline, which the first call starts."""
        if self.deadline is None:
            self.deadline = time.monotonic() + self.budget
        return max(self.deadline - time.monotonic(), 0.001)

    @contextlib.contextmanager
    def _querying(self) -> Iterator[Any]:
        """A ``MasterProxy`` whose calls end by the deadline (its ``timeout``: what is left).

        The sockets' timeouts bound each wait; the alarm bounds the whole, however the peer
        trickles its answer, by raising ``_DeadlineError`` in the query: the caller offers
        what it can without the answer. Offline work is never under the alarm.
        """
        # imported before the clock starts: on a busy machine, importing takes a while too
        from rostools.rosgraph.masterapi import MasterProxy

        left = self.left()
        handler = signal.signal(signal.SIGALRM, _late)
        timer, _ = signal.setitimer(signal.ITIMER_REAL, left)
        started = time.monotonic()
        try:
            yield MasterProxy(self.master_uri, "/rostools_complete", timeout=left)
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
            signal.signal(signal.SIGALRM, handler)
            if timer:  # a caller's own alarm (pytest-timeout's, in a test) rings as it would
                signal.setitimer(
                    signal.ITIMER_REAL, max(timer - (time.monotonic() - started), 0.001)
                )

    def complete(self) -> Iterator[tuple[str, str]]:
        """The candidates that start with the current word.

        A name with a control character (a peer's, from the master) would break the one line
        a candidate is, and cannot be typed anyway: it is left out, and help is escaped.
        """
        for value, help_text in self._candidates():
            if one_line(value) != value:
                continue
            help_text = one_line(help_text)
            if value.startswith(self.cur) or value.startswith(":"):
                yield (value if value.startswith(":") else value[len(self.prefix) :]), help_text

    def _candidates(self) -> Candidates:
        node = load_tree()
        values = self._option_value(node)
        if values is not None:
            return values
        i = 1
        while i < self.cword:
            word = self.words[i]
            name = word.split("=", 1)[0]
            option = node["options"].get(name) if word.startswith("-") else None
            if option is not None:
                if option["value"] and "=" not in word:
                    if i + 1 == self.cword:
                        return self._value(option["value"], node)
                    if name == "--master-uri":
                        self.master_uri = self.words[i + 1]
                    i += 2
                    continue
                if name == "--master-uri":
                    self.master_uri = word.split("=", 1)[1]
            elif ":=" in word or word.startswith("-"):
                pass  # a remapping, or an option we do not know
            elif word in node.get("commands", {}):
                node = node["commands"][word]
                self.positionals = []
            else:
                self.positionals.append(word)
            i += 1
        if self.cur.startswith("-"):
            return [(name, o["help"]) for name, o in sorted(node["options"].items())]
        if node.get("commands"):
            return [(name, c["help"]) for name, c in node["commands"].items()]
        args = node.get("args", [])
        if not args:
            return []
        index = min(len(self.positionals), len(args) - 1)
        if len(self.positionals) >= len(args) and not args[-1]["many"]:
            return []
        return self._value(args[index]["kind"], node)

    def _option_value(self, node: dict[str, Any]) -> Candidates | None:
        """Values for ``--opt=VALUE`` being typed (the options of the command so far)."""
        if not self.cur.startswith("-") or "=" not in self.cur:
            return None
        for word in self.words[1 : self.cword]:
            if word in node.get("commands", {}):
                node = node["commands"][word]
        name, _ = self.cur.split("=", 1)
        option = node["options"].get(name)
        if option is None or not option["value"]:
            return []
        if self.shell == "bash":  # readline replaces only what follows the "="
            self.prefix = name + "="
        return [(f"{name}={v}", h) for v, h in self._value(option["value"], node)]

    # values -----------------------------------------------------------------------------

    def _value(self, kind: str, node: dict[str, Any]) -> Candidates:
        if kind.startswith("choice:"):
            return [(c, "") for c in kind[len("choice:") :].split(",")]
        if kind.startswith("files"):
            return [(":" + kind, "")]
        if kind == "dirs":
            return [(":dirs", "")]
        source = _KINDS.get(kind)
        return source(self) if source is not None else []

    def _ask(self, method: str) -> Any:
        """The master's answer to ``method``; None when it cannot say in time."""
        from rostools.errors import RostoolsError

        try:
            with self._querying() as master:
                return master.raw(method)[2]
        except (RostoolsError, OSError, ValueError, TypeError, _DeadlineError):
            return None

    def _state(self) -> tuple[list[Any], list[Any], list[Any]]:
        pubs, subs, services = self._ask("getSystemState") or ([], [], [])
        return pubs, subs, services

    def topics(self) -> Candidates:
        """Topics with a publisher or a subscriber."""
        pubs, subs, _ = self._state()
        return [(t, "") for t in sorted({t for t, _ in pubs} | {t for t, _ in subs})]

    def topic_fields(self) -> Candidates:
        """``topic echo /odom/<TAB>``: topics, then the fields of a topic's message type."""
        topics = self.topics()
        base = max((t for t, _ in topics if self.cur.startswith(t + "/")), key=len, default=None)
        if base is None:
            return topics
        from rostools.errors import RostoolsError
        from rostools.msgs.store import TypeStore

        store = TypeStore.default()
        path = self.cur[len(base) + 1 :].split("/")[:-1]
        try:
            spec = store.msg(dict(self._ask("getTopicTypes") or [])[base])
            for name in path:  # only into single messages: an array needs an index first
                field = next(f for f in spec.fields if f.name == name)
                if field.is_builtin or field.is_array:
                    return []
                spec = store.msg(field.base)
        except (KeyError, StopIteration, RostoolsError, ValueError):
            return []
        prefix = "/".join([base, *path])
        return [(f"{prefix}/{f.name}", f.type) for f in spec.fields]

    def services(self) -> Candidates:
        """Services with a provider."""
        return [(s, "") for s in sorted({s for s, _ in self._state()[2]})]

    def nodes(self) -> Candidates:
        """Nodes with any registration."""
        names: set[str] = set()
        for entries in self._state():
            for _, nodes in entries:
                names.update(nodes)
        return [(n, "") for n in sorted(names)]

    def params(self) -> Candidates:
        """Parameter names, and the namespaces above them."""
        names = self._ask("getParamNames") or []
        found = set(names)
        for name in names:
            parts = name.split("/")
            found.update("/".join(parts[:k]) + "/" for k in range(2, len(parts)))
        return [(n, "") for n in sorted(found)]

    def _types(self, kind: str) -> Candidates:
        from rostools.msgs.store import TypeStore

        return [(t, kind) for t in TypeStore.default().types(kind)]  # type: ignore[arg-type]

    def msg_types(self) -> Candidates:
        """Message types the store knows."""
        return self._types("msg")

    def srv_types(self) -> Candidates:
        """Service types the store knows."""
        return self._types("srv")

    def all_types(self) -> Candidates:
        """Message and service types."""
        return self._types("msg") + self._types("srv")

    def topic_type(self) -> Candidates:
        """``topic pub /t <TAB>``: the topic's current type, else every message type."""
        if self.positionals:
            types = dict(self._ask("getTopicTypes") or [])
            topic = self.positionals[0]
            current = types.get(topic if topic.startswith("/") else "/" + topic)
            if current:
                return [(current, "the topic's type")]
        return self.msg_types()

    def message_template(self) -> Candidates:
        """``topic pub /t TYPE <TAB>``: the message as one line of YAML, quoted."""
        if len(self.positionals) < 2 or self.cur:
            return []
        return self._template(lambda store: store.msg(self.positionals[1]))

    def request_template(self) -> Candidates:
        """``service call /s <TAB>``: the request as one line of YAML, quoted."""
        if not self.positionals or self.cur:
            return []
        from rostools.errors import RostoolsError
        from rostools.rosgraph.serviceclient import BlockingServiceClient

        name = self.positionals[0]
        name = name if name.startswith("/") else "/" + name
        try:
            with self._querying() as master:
                client = BlockingServiceClient(master, name, timeout=master.timeout)
                srv_type = client.probe("/rostools_complete").get("type", "")
        except (RostoolsError, OSError, _DeadlineError):
            return []
        return self._template(lambda store: store.srv(srv_type).request)

    def loggers(self) -> Candidates:
        """``log get|set NODE <TAB>``: the node's loggers and their levels (its get_loggers)."""
        if not self.positionals:
            return []
        from rostools.errors import RostoolsError
        from rostools.node.loggers import GET_LOGGERS, LoggerBytesError, decode_loggers
        from rostools.rosgraph.serviceclient import BlockingServiceClient

        node = self.positionals[0]
        name = (node if node.startswith("/") else "/" + node).rstrip("/") + "/get_loggers"
        try:
            with self._querying() as master:
                client = BlockingServiceClient(master, name, timeout=master.timeout)
                found = decode_loggers(client.call("/rostools_complete", GET_LOGGERS[1], b""))
        except (RostoolsError, OSError, LoggerBytesError, _DeadlineError):
            return []
        return found

    def actions(self) -> Candidates:
        """Actions in the graph, with their types."""
        from rostools.action.pattern import find_actions

        pubs, subs, _ = self._state()
        types = dict(self._ask("getTopicTypes") or [])
        return [(a.name, a.type) for a in find_actions(types, pubs, subs)]

    def goal_template(self) -> Candidates:
        """``action send-goal /fib <TAB>``: the goal as one line of YAML, quoted."""
        if not self.positionals or self.cur:
            return []
        from rostools.action.pattern import action_type

        name = self.positionals[0]
        goal = dict(self._ask("getTopicTypes") or []).get(
            (name if name.startswith("/") else "/" + name) + "/goal", ""
        )
        stem = action_type(goal).removesuffix("Action")
        if not stem:
            return []
        return self._template(lambda store: store.msg(stem + "Goal"))

    def frames(self) -> Candidates:
        """``tf echo <TAB>``: frame ids, from ``-b BAG``'s TF topics, else live.

        Live, from what each ``/tf`` and ``/tf_static`` publisher sends first, under the
        deadline; from a bag, what can be read by then.
        """
        from rostools.errors import RostoolsError

        found: set[str] = set()
        bag = self._bag_word()
        try:
            if bag is not None:
                from rostools.cli.tf.shared import open_feed

                with open_feed(Path(bag)) as feed:  # a big bag: what the deadline allows
                    for batch in feed.batches():
                        found.update(f for t in batch.transforms for f in (t.parent, t.child))
                        if self.left() <= 0.001:
                            break
            else:
                from rostools.cli.tf.shared import peek_frames

                with self._querying() as master:
                    peek_frames(master, found, self.left)
        except (RostoolsError, OSError, ValueError, TypeError, _DeadlineError):
            pass  # what arrived in time is offered
        return [(f, "frame") for f in sorted(found)]

    def _bag_word(self) -> str | None:
        """The value of ``-b``/``--bag`` typed so far, if any."""
        for i, word in enumerate(self.words[: self.cword]):
            if word in ("-b", "--bag") and i + 1 < self.cword:
                return self.words[i + 1]
            if word.startswith("--bag="):
                return word.split("=", 1)[1]
        return None

    def _template(self, spec_of: Callable[[Any], Any]) -> Candidates:
        from rostools.errors import RostoolsError
        from rostools.msgs.describe import proto
        from rostools.msgs.store import TypeStore

        store = TypeStore.default()
        try:
            text = proto(store, spec_of(store), flow=True)
        except (RostoolsError, KeyError, ValueError):
            return []
        # fish escapes what it inserts; bash and zsh insert the quotes we give
        return [(text if self.shell == "fish" else f'"{text}"', "YAML template")]


_KINDS: dict[str, Callable[[Completer], Candidates]] = {
    "topic": Completer.topics,
    "topic_field": Completer.topic_fields,
    "service": Completer.services,
    "node": Completer.nodes,
    "param": Completer.params,
    "msg": Completer.msg_types,
    "srv": Completer.srv_types,
    "type": Completer.all_types,
    "topic_type": Completer.topic_type,
    "message": Completer.message_template,
    "request": Completer.request_template,
    "action": Completer.actions,
    "logger": Completer.loggers,
    "goal": Completer.goal_template,
    "frame": Completer.frames,
}


_BREAKS = ("=", ":=")


def _join_breaks(words: list[str], cword: int) -> tuple[list[str], int]:
    """Words as typed: bash splits ``--opt=value`` and ``a:=b`` at its COMP_WORDBREAKS."""
    joined: list[str] = []
    new_cword = cword
    for i, word in enumerate(words):
        if i > 1 and (word in _BREAKS or words[i - 1] in _BREAKS):
            joined[-1] += word
            if i <= cword:
                new_cword -= 1
        else:
            joined.append(word)
    return joined, new_cword
