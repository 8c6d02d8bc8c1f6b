"""topoly's HOMFLY-PT code closes file descriptor 0 on every call; identify must give it back,
or the next file or socket the process opens gets number 0 and the next call closes it (a
sweep's Dask connections did: "fd 0 added twice", "Bad file descriptor")."""

from __future__ import annotations

import os

from helpers import trefoil
from stiffknots.knots.identify import homfly_code


def test_descriptor_0_survives_homfly(tmp_path):
    f = tmp_path / "stdin.txt"
    f.write_text("keep me\n")
    saved = os.dup(0)
    fd = os.open(f, os.O_RDONLY)
    try:
        os.dup2(fd, 0)
        before = os.fstat(0)
        for _ in range(2):  # every call closes it
            assert homfly_code(trefoil())
            after = os.fstat(0)  # OSError (EBADF) if the call left it closed
            assert (after.st_dev, after.st_ino) == (before.st_dev, before.st_ino)
        assert os.read(0, 7) == b"keep me"
    finally:
        os.dup2(saved, 0)
        os.close(saved)
        os.close(fd)
