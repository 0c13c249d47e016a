"""``param get``'s YAML without PyYAML for the common values, byte for byte as ``paramyaml.dump``.

PyYAML is 20 ms of imports, as much as the rest of ``param get``. Most parameters are
numbers, booleans, names and lists or dicts of them, which PyYAML prints in a fixed block
layout: ``plain`` writes exactly that. Anything it is not sure to print as PyYAML would (a
string to quote, a float's special form, a binary, a repeated object that PyYAML would
anchor) makes it give up, and ``dump`` asks ``paramyaml``. ``tests/unit/test_plainyaml.py``
compares the two on many values.
"""

from __future__ import annotations

TYPE_CHECKING = False  # ``typing`` is 5-10 ms of start-up; only annotations use it
if TYPE_CHECKING:
    from typing import Any

#: What a string may hold to be printed plain: no indicator (``: ``, ``#``, ``,``, brackets,
#: quotes), no space (PyYAML folds long lines at spaces) and nothing beyond ASCII (PyYAML
#: escapes it).
_PLAIN = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789_./-")
#: ... and must start with one of these, which no YAML 1.1 number, date, merge key or
#: document marker starts with.
_PLAIN_START = frozenset("abcdefghijklmnopqrstuvwxyzABCDEFGHIJKLMNOPQRSTUVWXYZ_/")
#: The words YAML 1.1 reads as booleans or null (PyYAML's resolver): PyYAML quotes them.
_RESERVED = frozenset(
    spelling
    for word in ("yes", "no", "true", "false", "on", "off", "null")
    for spelling in (word, word.capitalize(), word.upper())
)
#: PyYAML writes a key as a complex key (``? key``) when it and its tag (``!!str``, counted
#: even when not written) reach 128 characters.
_MAX_SIMPLE_KEY = 128 - len("!!str")


class _Unsure(Exception):  # noqa: N818 - a signal, not an error
    """A value ``plain`` does not print; PyYAML will."""


def dump(value: Any, *, pretty: bool = False) -> str:
    """``paramyaml.dump(value, pretty=pretty)``, without importing PyYAML when it can."""
    text = plain(value)
    if text is not None:
        return text  # strings with line breaks, the only ones -p changes, are not plain
    from rostools.cli.param import paramyaml

    return paramyaml.dump(value, pretty=pretty)


def plain(value: Any) -> str | None:
    """``value`` as ``paramyaml.dump`` prints it, or None when it is not sure to match."""
    try:
        if type(value) in (dict, list):
            if not value:
                return "{}\n" if type(value) is dict else "[]\n"
            out: list[str] = []
            _node(value, 0, False, out, set())
            return "".join(out)
        return _scalar(value)  # PyYAML's "\n...\n" after a bare scalar, taken off by dump
    except _Unsure:
        return None


def _scalar(value: Any) -> str:
    """A scalar PyYAML prints plain, as it prints it."""
    kind = type(value)
    if kind is bool:
        return "true" if value else "false"
    if kind is int:
        return str(value)
    if kind is float:
        if value != value or value in (float("inf"), float("-inf")):
            raise _Unsure  # .nan, .inf: rare, and PyYAML's to spell
        text = repr(value).lower()
        # PyYAML's fix for repr without a dot (1e+16): a YAML 1.1 float needs one.
        return text.replace("e", ".0e", 1) if "." not in text and "e" in text else text
    if kind is str and _is_plain(value):
        return str(value)
    raise _Unsure


def _is_plain(text: str) -> bool:
    """Whether PyYAML writes ``text`` as a plain scalar (no quotes) in block style."""
    return text[:1] in _PLAIN_START and text not in _RESERVED and all(c in _PLAIN for c in text)


def _node(value: Any, indent: int, inline: bool, out: list[str], seen: set[int]) -> None:
    """A non-empty dict or list in PyYAML's block layout, at ``indent``.

    ``inline``: the first line follows a ``- `` already written, so it is not indented.
    """
    _once(value, seen)
    pad = " " * indent
    if type(value) is dict:
        keys = list(value)
        if not all(type(k) is str and len(k) < _MAX_SIMPLE_KEY and _is_plain(k) for k in keys):
            raise _Unsure
        for i, key in enumerate(sorted(keys)):
            out.append(("" if inline and i == 0 else pad) + key + ":")
            item = value[key]
            if type(item) in (dict, list) and item:
                out.append("\n")
                # A list in a mapping is not indented ("indentless"); a mapping is, by 2.
                _node(item, indent + 2 if type(item) is dict else indent, False, out, seen)
            else:
                out.append(" " + _leaf(item, seen) + "\n")
    else:
        for i, item in enumerate(value):
            out.append(("" if inline and i == 0 else pad) + "-")
            if type(item) in (dict, list) and item:
                out.append(" ")
                _node(item, indent + 2, True, out, seen)
            else:
                out.append(" " + _leaf(item, seen) + "\n")


def _leaf(value: Any, seen: set[int]) -> str:
    """A scalar, or an empty dict or list, inside a collection."""
    if type(value) is dict:
        _once(value, seen)
        return "{}"
    if type(value) is list:
        _once(value, seen)
        return "[]"
    return _scalar(value)


def _once(value: Any, seen: set[int]) -> None:
    """Give up on a dict or list met twice: PyYAML writes it as an anchor and an alias."""
    if id(value) in seen:
        raise _Unsure
    seen.add(id(value))
