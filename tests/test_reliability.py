"""Pieces of the reliability pass that need no command line: file permissions of atomic
writes, the force limit of the engine, a single job in a worker process."""

import os

import pytest

from stiffknots.engine.params import MAX_FORCE, Ensemble
from stiffknots.errors import InvalidParameter
from stiffknots.fileio import write_bytes, write_json, write_text
from stiffknots.problems.pool import run_jobs


def test_atomic_files_get_ordinary_permissions(tmp_path):
    mask = os.umask(0o022)
    os.umask(mask)
    for write, data in ((write_text, "x"), (write_bytes, b"x"), (write_json, {"a": 1})):
        p = write(tmp_path / f"f_{write.__name__}", data)
        assert oct(p.stat().st_mode & 0o777) == oct(0o666 & ~mask)  # not mkstemp's 0600
    assert [q.name for q in tmp_path.iterdir() if q.name.startswith(".")] == []


@pytest.mark.parametrize("force", [MAX_FORCE * 1.01, 1e300, float("inf"), float("nan"), -1.0])
def test_force_limit(force):
    with pytest.raises(InvalidParameter, match=r"force must be a finite number in \[0, 100\]"):
        Ensemble("force", force=force).validate()
    Ensemble("force", force=MAX_FORCE).validate()


def test_isolate_runs_even_one_job_in_a_worker():
    (pid,), stopped = run_jobs(os.getpid, [()], workers=1, isolate=True)
    assert not stopped and pid != os.getpid()
    (pid,), _ = run_jobs(os.getpid, [()], workers=1)
    assert pid == os.getpid()  # the default: in this process
