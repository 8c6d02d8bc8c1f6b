"""Fixtures shared by the tests (helpers that are plain functions live in ``helpers.py``)."""

from __future__ import annotations

from pathlib import Path

import pytest

from helpers import DATA


@pytest.fixture(scope="session")
def data_dir() -> Path:
    return DATA


@pytest.fixture
def small_fs(tmp_path):
    """A factory of small file systems (#40: a full disk, read-only media): ``small_fs("1m")``
    mounts a tmpfs of that size on a new folder under ``tmp_path`` and returns it;
    ``small_fs.readonly(folder)`` remounts it read-only. Unmounted at teardown (immutable
    flags cleared first). Skipped where mounting is not permitted (it needs root)."""
    import subprocess

    mounted: list[Path] = []

    def mount(size: str = "1m") -> Path:
        d = tmp_path / f"fs{len(mounted)}"
        d.mkdir()
        p = subprocess.run(["mount", "-t", "tmpfs", "-o", f"size={size}", "tmpfs", str(d)],
                           capture_output=True, text=True)
        if p.returncode:
            pytest.skip(f"cannot mount a small file system here (needs root): "
                        f"{p.stderr.strip() or p.returncode}")
        mounted.append(d)
        return d

    def readonly(d: Path) -> None:
        subprocess.run(["mount", "-o", "remount,ro", str(d)], check=True)

    mount.readonly = readonly
    yield mount
    for d in reversed(mounted):
        subprocess.run(["chattr", "-R", "-i", str(d)], capture_output=True)
        subprocess.run(["umount", "-l", str(d)], capture_output=True)


@pytest.fixture
def immutable():
    """``immutable(path)``: make a file immutable (``chattr +i``: not even root writes it);
    skipped where the file system does not support it. Cleared at teardown."""
    import subprocess

    done: list[Path] = []

    def set_(path: Path) -> Path:
        p = subprocess.run(["chattr", "+i", str(path)], capture_output=True, text=True)
        if p.returncode:
            pytest.skip(f"chattr +i does not work here: {p.stderr.strip()}")
        done.append(path)
        return path

    yield set_
    for path in done:
        subprocess.run(["chattr", "-i", str(path)], capture_output=True)
