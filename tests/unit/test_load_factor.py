"""The run's load factor (tests/support/load.py): taken as given, measured within bounds."""

from __future__ import annotations

import os

import pytest

from tests.support import load


def test_a_given_factor_is_kept_and_scales(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setenv(load.ENV, "2.5")
    assert load.factor() == 2.5
    assert load.scaled(4) == 10


def test_a_measured_factor_is_within_its_bounds(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.delenv(load.ENV, raising=False)
    measured = load.factor()
    assert 1.0 <= measured <= load.MOST
    assert os.environ[load.ENV] == f"{measured:.2f}"  # kept for the workers and children
