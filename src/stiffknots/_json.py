"""The one JSON encoder: plain (JSON-able) Python values from results that hold numpy data."""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from typing import Any

import numpy as np

__all__ = ["dumps", "json_default", "to_plain"]


def to_plain(x: Any) -> Any:
    """Nested mappings/sequences with numpy scalars and arrays as plain Python values."""
    if isinstance(x, Mapping):
        return {str(k): to_plain(v) for k, v in x.items()}
    if isinstance(x, list | tuple):
        return [to_plain(v) for v in x]
    if isinstance(x, np.ndarray):
        return to_plain(x.tolist())
    if isinstance(x, np.generic):
        return x.item()
    return x


def json_default(x: Any) -> Any:
    """``default=`` hook of :func:`json.dumps` for numpy scalars and arrays, sets and paths."""
    if isinstance(x, np.generic):
        return x.item()
    if isinstance(x, np.ndarray):
        return x.tolist()
    if isinstance(x, set | frozenset):
        return sorted(x)
    if isinstance(x, os.PathLike):
        return os.fspath(x)
    raise TypeError(f"value of type {type(x).__name__} is not JSON-serialisable: {x!r}")


def dumps(obj: Any, indent: int | None = 2, allow_nan: bool = True) -> str:
    """``json.dumps`` with :func:`json_default` (numpy values, sets, paths)."""
    return json.dumps(obj, indent=indent, default=json_default, allow_nan=allow_nan)
