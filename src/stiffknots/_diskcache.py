"""A per-user cache on disk of values that are slow to compute and depend only on the
installed code and data (the parsed KnotInfo tables: ~2 s on every command otherwise).

Files live in ``$STIFFKNOTS_CACHE``, else ``$XDG_CACHE_HOME/stiffknots``, else
``~/.cache/stiffknots``; each is named by a key that includes the package version and a hash of
the source files the value depends on, so a new version or an edited source never reads a
stale value. Writes go to a temporary file renamed into place (several processes may write
at once); any failure to read or write falls back to computing the value.
"""

from __future__ import annotations

import hashlib
import os
import pickle
import tempfile
from collections.abc import Callable
from pathlib import Path
from typing import TypeVar

from stiffknots._version import __version__

T = TypeVar("T")


def cache_dir() -> Path:
    base = os.environ.get("STIFFKNOTS_CACHE")
    if base:
        return Path(base)
    xdg = os.environ.get("XDG_CACHE_HOME")
    return (Path(xdg) if xdg else Path.home() / ".cache") / "stiffknots"


def source_key(*parts: str, files: tuple[str, ...] = ()) -> str:
    """A key from ``parts``, the package version and the bytes of ``files``."""
    h = hashlib.sha256(__version__.encode())
    for p in parts:
        h.update(b"\0" + p.encode())
    for f in files:
        try:
            h.update(Path(f).read_bytes())
        except OSError:
            h.update(b"?" + f.encode())
    return h.hexdigest()[:24]


def cached(name: str, key: str, compute: Callable[[], T]) -> T:
    """``compute()``, read from or written to the cache file ``name-key.pkl``."""
    path = cache_dir() / f"{name}-{key}.pkl"
    try:
        with open(path, "rb") as fh:
            return pickle.load(fh)
    except Exception:  # missing, unreadable or from an incompatible build: compute it
        pass
    value = compute()
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.name, suffix=".tmp")
        with os.fdopen(fd, "wb") as fh:
            pickle.dump(value, fh, protocol=pickle.HIGHEST_PROTOCOL)
        os.replace(tmp, path)
    except Exception:  # a read-only home, a full disk: the value is still returned
        if tmp is not None:
            Path(tmp).unlink(missing_ok=True)
    return value
