"""Files written atomically: a temporary file in the same folder, then one rename.

A reader (or a run killed with ``kill -9`` half-way through a write) therefore sees either the
old file or the complete new one, never a truncated file. The temporary name is unique per
process and call, so two runs writing the same path never share a temporary file.
"""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from stiffknots._json import dumps

__all__ = ["atomic_path", "write_bytes", "write_json", "write_text"]


def _umask() -> int:
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


#: the permissions of a new file (what ``open(path, "w")`` would give): a temporary file is
#: created private (0600) and would keep that mode through the rename
_FILE_MODE = 0o666 & ~_umask()


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path next to ``path``; on success it replaces ``path`` in one rename.

    On an exception (Ctrl-C included) the temporary file is removed and ``path`` is left as it
    was.
    """
    path = Path(path)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    tmp = Path(tmp)
    try:
        with contextlib.suppress(OSError):
            os.fchmod(fd, _FILE_MODE)
        os.close(fd)
        yield tmp
        os.replace(tmp, path)
    except BaseException:
        with contextlib.suppress(OSError):
            tmp.unlink()
        raise


def write_bytes(path: str | os.PathLike, data: bytes) -> Path:
    """Write ``data`` to ``path`` atomically."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(data)
    return Path(path)


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write ``text`` (UTF-8, ``\\n`` line ends) to ``path`` atomically."""
    with atomic_path(path) as tmp, open(tmp, "w", encoding="utf-8", newline="\n") as fh:
        fh.write(text)
    return Path(path)


def write_json(path: str | os.PathLike, obj: Any, indent: int | None = 2) -> Path:
    """Write ``obj`` as JSON (numpy values converted) to ``path`` atomically."""
    return write_text(path, dumps(obj, indent=indent) + "\n")
