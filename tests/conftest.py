"""Fixtures shared by the tests (helpers that are plain functions live in ``helpers.py``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from helpers import DATA


@pytest.fixture(scope="session")
def data_dir() -> Path:
    return DATA
