"""Files written atomically: a temporary file in the same folder, then one rename.

A reader (or a run killed with ``kill -9`` half-way through a write) therefore sees either the
old file or the complete new one, never a truncated file. The temporary name is unique per
process and call, so two runs writing the same path never share a temporary file.
"""

from __future__ import annotations

import contextlib
import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path
from typing import Any

from stiffknots._json import dumps

__all__ = ["atomic_path", "replaced_entries", "write_bytes", "write_json", "write_text"]


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
    except BaseException as exc:
        with contextlib.suppress(OSError):
            tmp.unlink()
        if isinstance(exc, OSError) and exc.filename in (None, str(tmp)):
            exc.filename = str(path)  # a full disk: name the file the user asked for
        raise


@contextlib.contextmanager
def replaced_entries(folder: str | os.PathLike, names, prefix: str = "set") -> Iterator[Path]:
    """Yield an empty hidden folder inside ``folder`` to write a new set of files into; on
    success the set replaces the previous one in ``folder``, on an exception (a full disk,
    Ctrl-C) the previous set stays as it was and the new one is removed.

    ``names``: the entries (files, folders) of ``folder`` that belong to the set: the ones
    the new set does not write again go too (no stale page of a larger set stays); the others
    of ``folder`` are left alone. The swap is one rename per entry (no space needed), the
    previous entries renamed aside first and put back if a rename fails. Hidden folders
    ``.{prefix}-new-*`` and ``.{prefix}-old-*`` left by a killed process are removed first
    (the caller holds the folder: a lock).
    """
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    for left in [*folder.glob(f".{prefix}-new-*"), *folder.glob(f".{prefix}-old-*")]:
        shutil.rmtree(left, ignore_errors=True)
    stage = Path(tempfile.mkdtemp(prefix=f".{prefix}-new-", dir=folder))
    try:
        try:
            yield stage
        except OSError as exc:  # name the file the user will look for, not the hidden one
            if exc.filename and str(exc.filename).startswith(str(stage)):
                exc.filename = str(folder) + str(exc.filename)[len(str(stage)):]
            elif not exc.filename:  # a write that failed names no file: the folder
                exc.filename = str(folder)
            raise
        old = Path(tempfile.mkdtemp(prefix=f".{prefix}-old-", dir=folder))
        moved: list[str] = []
        placed: list[str] = []
        try:
            for name in dict.fromkeys([*names, *os.listdir(stage)]):
                if os.path.lexists(folder / name):
                    os.replace(folder / name, old / name)
                    moved.append(name)
            for name in os.listdir(stage):
                os.replace(stage / name, folder / name)
                placed.append(name)
        except BaseException:
            for name in placed:
                with contextlib.suppress(OSError):
                    os.replace(folder / name, stage / name)
            for name in moved:
                with contextlib.suppress(OSError):
                    os.replace(old / name, folder / name)
            with contextlib.suppress(OSError):
                old.rmdir()  # only if every entry went back
            raise
        shutil.rmtree(old, ignore_errors=True)
    finally:
        shutil.rmtree(stage, ignore_errors=True)


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
