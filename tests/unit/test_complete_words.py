"""``rostools __complete``'s reading of the words a shell hands it."""

from __future__ import annotations

import pytest

from rostools.cli.completer import Completer, _join_breaks


@pytest.mark.parametrize(
    ("words", "cword", "joined", "new_cword"),
    [
        (["rostools", "echo", "--format", "="], 3, ["rostools", "echo", "--format="], 2),
        (["rostools", "x", "--format", "=", "js"], 4, ["rostools", "x", "--format=js"], 2),
        (["rostools", "x", "/a", ":=", "/b", "/c"], 5, ["rostools", "x", "/a:=/b", "/c"], 3),
        (["rostools", "=", "x"], 2, ["rostools", "=x"], 1),  # never glued to the program
        (["rostools", "topic", ""], 2, ["rostools", "topic", ""], 2),
    ],
)  # fmt: skip
def test_bash_word_breaks_are_joined(
    words: list[str], cword: int, joined: list[str], new_cword: int
) -> None:
    assert _join_breaks(words, cword) == (joined, new_cword)


def values(shell: str, words: list[str]) -> list[str]:
    completer = Completer(words, len(words) - 1, 5, shell)
    return [v for v, _ in completer.complete()]


def test_option_values_after_an_equals_sign() -> None:
    # bash replaces only what follows "="; zsh and fish the whole word
    assert values("bash", ["rostools", "topic", "echo", "--format", "=", "j"]) == ["json"]
    assert values("bash", ["rostools", "topic", "echo", "--format", "="]) == [
        "text",
        "json",
        "yaml",
    ]
    assert values("zsh", ["rostools", "topic", "echo", "--format=y"]) == ["--format=yaml"]
    assert values("fish", ["rostools", "topic", "echo", "--quiet=x"]) == []  # a flag takes no value


def test_a_peers_name_with_a_line_break_is_not_offered(monkeypatch: pytest.MonkeyPatch) -> None:
    # before: "/x\n/y" came out as two candidates, "/x" and "/y", neither of them a topic
    def ask(self: Completer, method: str) -> object:
        assert method == "getSystemState"
        return [[["/x\n/y", ["/n"]], ["/ok", ["/n"]], ["/u\u2028", ["/n"]]], [], []]

    monkeypatch.setattr(Completer, "_ask", ask)
    assert values("bash", ["rostools", "topic", "hz", "/"]) == ["/ok"]
