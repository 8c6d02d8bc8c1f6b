"""Fixtures of the store's tests."""

from __future__ import annotations

import pytest

from stiffknots.store import Store


@pytest.fixture
def store(tmp_path):
    with Store(tmp_path / "db" / "results.db") as s:
        yield s
