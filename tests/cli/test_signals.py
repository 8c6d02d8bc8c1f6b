"""Ctrl-C, kill -9 and a second run: what the command line does when it is stopped or shared.

Every test starts the real command in its own session with SIGINT at its default (a command
started in the background by a non-interactive shell inherits SIGINT ignored) and sends SIGINT
to the whole process group, as a terminal's Ctrl-C does; kill -9 goes to the parent only.
The interrupts are timed on what the command has visibly done (a file, a line on stderr, a
worker process), not on the clock alone. All are slow (``make test-all``).
"""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.slow

_SCRIPT = Path(sys.executable).with_name("stiffknots")
CLI = [str(_SCRIPT)] if _SCRIPT.exists() else [sys.executable, "-m", "stiffknots.cli"]


class Run:
    """A command in its own session; stderr read line by line as it comes."""

    def __init__(self, args, cwd):
        self.p = subprocess.Popen(
            [*CLI, *map(str, args)], cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
            text=True, start_new_session=True,
            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
        self.err_lines: list[str] = []
        self.out = ""
        self._t = threading.Thread(target=self._read, daemon=True)
        self._t.start()
        self._o = threading.Thread(target=self._read_out, daemon=True)
        self._o.start()

    def _read(self):
        for line in self.p.stderr:
            self.err_lines.append(line)

    def _read_out(self):
        self.out = self.p.stdout.read()

    def interrupt(self):
        os.killpg(self.p.pid, signal.SIGINT)

    def wait(self, timeout=120):
        rc = self.p.wait(timeout=timeout)
        self._t.join(5)
        self._o.join(5)
        return rc

    @property
    def err(self) -> str:
        return "".join(self.err_lines)

    def kill_group(self):
        try:
            os.killpg(self.p.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass


def until(cond, timeout, step=0.05) -> bool:
    t0 = time.monotonic()
    while time.monotonic() - t0 < timeout:
        if cond():
            return True
        time.sleep(step)
    return False


def workers(pid: int) -> list[int]:
    """The worker processes of ``pid`` (multiprocessing's spawned children)."""
    found = []
    for d in Path("/proc").iterdir():
        if not d.name.isdigit():
            continue
        try:
            stat = (d / "stat").read_text()
            cmd = (d / "cmdline").read_bytes()
        except OSError:
            continue
        ppid = int(stat.rsplit(")", 1)[1].split()[1])
        if ppid == pid and b"spawn_main" in cmd:
            found.append(int(d.name))
    return found


def alive(pid: int) -> bool:
    """Running (a zombie waiting for a reaper counts as dead)."""
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except OSError:
        return False
    return state != "Z"


@pytest.fixture
def runs():
    started: list[Run] = []
    yield started
    for r in started:  # never leave a run behind
        r.kill_group()


def start(runs, args, cwd) -> Run:
    r = Run(args, cwd)
    runs.append(r)
    return r


def assert_interrupted(r: Run, rc: int, text: str = "interrupted"):
    assert rc == 130, r.err
    assert "Traceback" not in r.err
    lines = [ln for ln in r.err.splitlines() if ln.strip()]
    assert lines and text in lines[-1], r.err


def complete(path: Path) -> bool:
    """A file stiffknots writes, complete (parses to the end)."""
    from stiffknots.formats import load

    if path.suffix == ".json":
        json.loads(path.read_text())
    elif path.suffix == ".npz":
        with np.load(path) as z:
            [z[k] for k in z.files]
    elif path.suffix == ".xyz":
        load(path, closed=True)
    elif path.suffix == ".png":
        data = path.read_bytes()
        assert data.startswith(b"\x89PNG") and data.rstrip().endswith(b"IEND\xaeB`\x82")
    return True


# -- Ctrl-C ------------------------------------------------------------------------------------


# `knot 4_1` takes ≈ 0.55 s since the command line starts without Dask (1.5 s before): both
# delays fall inside it
@pytest.mark.parametrize("delay", [0.2, 0.4])
def test_ctrl_c_while_loading_or_during_knot(tmp_path, runs, delay):
    r = start(runs, ["knot", "4_1"], tmp_path)
    time.sleep(delay)
    if r.p.poll() is not None:
        pytest.skip("the command ended before the interrupt")
    r.interrupt()
    assert_interrupted(r, r.wait())
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_during_anneal_set_up(tmp_path, runs):
    """--beads 10000: the embedding and its knot check take seconds; Ctrl-C there stops at
    once and leaves no --out folder."""
    r = start(runs, ["anneal", "3_1", "--beads", "10000", "--moves", "2000", "--replicas", "1",
                     "--out", "out"], tmp_path)
    assert until(lambda: (tmp_path / "out").exists(), 60)  # claimed: the set-up runs
    time.sleep(2.0)
    r.interrupt()
    t0 = time.monotonic()
    assert_interrupted(r, r.wait())
    assert time.monotonic() - t0 < 15
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize("command", [
    ["open", "3_1", "--excess-length", "40", "--moves", "20000000", "--replicas", "1"],
    ["tightest", "3_1", "--moves", "20000000", "--replicas", "2"],
])
def test_ctrl_c_before_the_first_replica_claims_nothing(tmp_path, runs, command):
    r = start(runs, [*command, "--out", "out"], tmp_path)
    assert until(lambda: workers(r.p.pid), 120), r.err
    time.sleep(1.0)
    r.interrupt()
    t0 = time.monotonic()
    assert_interrupted(r, r.wait(), "interrupted before any replica finished; nothing to report")
    assert time.monotonic() - t0 < 15  # a single replica runs in a worker: stopped at once
    assert not (tmp_path / "out").exists()
    assert r.out == ""


def test_ctrl_c_of_one_long_replica_is_prompt(tmp_path, runs):
    """A single replica used to run in the parent, where Ctrl-C waited for the compiled
    kernel's chunk (20 s at 1e9 moves): it runs in a worker now."""
    r = start(runs, ["anneal", "3_1", "--moves", "1e9", "--replicas", "1"], tmp_path)
    assert until(lambda: workers(r.p.pid), 120), r.err
    time.sleep(3.0)
    r.interrupt()
    t0 = time.monotonic()
    assert_interrupted(r, r.wait())
    assert time.monotonic() - t0 < 10


def test_workers_ignore_ctrl_c_from_their_very_start(tmp_path, runs):
    """SIGINT sent to the workers while they start (import the package, before their
    initializer runs): they neither die nor print a traceback — spawned with Ctrl-C held back.
    Before, a Ctrl-C in that second killed a worker with a KeyboardInterrupt traceback and the
    parent with a WorkerError."""
    r = start(runs, ["anneal", "3_1", "--moves", "1e8", "--replicas", "2"], tmp_path)
    assert until(lambda: workers(r.p.pid), 120), r.err
    t0 = time.monotonic()
    while time.monotonic() - t0 < 4.0:
        for pid in workers(r.p.pid):
            try:
                os.kill(pid, signal.SIGINT)
            except ProcessLookupError:
                pass
        time.sleep(0.02)
    assert r.p.poll() is None, r.err
    r.interrupt()
    assert_interrupted(r, r.wait())


def test_ctrl_c_after_two_of_three_replicas(tmp_path, runs):
    """The finished replicas are shown, written and marked; the marker line is visible (no
    rich markup eats its brackets) and no worker prints a traceback."""
    r = start(runs, ["anneal", "3_1", "--replicas", "3", "--moves", "600000", "--checkpoint",
                     "ck", "--out", "out"], tmp_path)
    assert until(lambda: sum("finished in" in ln for ln in r.err_lines) >= 2, 300), r.err
    r.interrupt()
    rc = r.wait()
    done = sum("finished in" in ln for ln in r.err_lines)
    if done == 3:
        pytest.skip("the third replica finished with the others (more than two cores)")
    assert_interrupted(r, rc, "interrupted: 2 of 3 replicas finished; the results above are "
                              "partial; resume with the same command and --resume "
                              "(checkpoints in ck)")
    assert "│       0 │" in r.out and "│       1 │" in r.out and "│       2 │" not in r.out
    res = json.loads((tmp_path / "out" / "result.json").read_text())
    assert res["interrupted"] is True and len(res["replicas"]) == 2
    manifest = json.loads((tmp_path / "out" / "manifest.json").read_text())
    assert set(manifest["files"]) == {p.name for p in (tmp_path / "out").iterdir()
                                      if p.name != "manifest.json"}


def test_ctrl_c_or_kill_9_while_writing_the_results(tmp_path, runs):
    """Ctrl-C while --out is written: the run's files are removed (or, if the write had just
    ended, the set is complete). kill -9 then: every file left is complete and, without a
    manifest, the folder is refused unless --overwrite, which clears it."""
    args = ["anneal", "3_1", "--moves", "20000", "--replicas", "2", "--out", "out"]
    out = tmp_path / "out"

    def first_file():
        return out.is_dir() and any(not n.startswith(".") for n in os.listdir(out))

    r = start(runs, args, tmp_path)
    assert until(first_file, 300, step=0.002), r.err
    r.interrupt()
    rc = r.wait()
    if rc == 130:
        assert_interrupted(r, rc, "interrupted while writing the results; the files of this "
                                  "run were removed")
        assert not out.exists() or list(out.iterdir()) == []
    else:  # the write ended before the interrupt arrived
        assert rc == 0 and (out / "manifest.json").exists()
        import shutil

        shutil.rmtree(out)
    r = start(runs, args, tmp_path)
    assert until(first_file, 300, step=0.002), r.err
    os.kill(r.p.pid, signal.SIGKILL)
    r.wait()
    left = sorted(p for p in out.rglob("*") if p.is_file() and not p.name.startswith("."))
    assert left  # (a hidden temporary file may stay: kill -9 interrupted its write)
    for p in left:
        assert complete(p), p
    if (out / "manifest.json").exists():
        listed = json.loads((out / "manifest.json").read_text())["files"]
        assert all((out / f).exists() for f in listed)
        assert (out / "result.json").exists()
    again = subprocess.run([*CLI, *args], cwd=tmp_path, capture_output=True, text=True,
                           timeout=300)
    assert again.returncode == 2 and "--overwrite" in again.stderr, again.stderr
    again = subprocess.run([*CLI, *args, "--overwrite", "--json"], cwd=tmp_path,
                           capture_output=True, text=True, timeout=300)
    assert again.returncode == 0, again.stderr
    listed = set(json.loads((out / "manifest.json").read_text())["files"])
    assert listed == {p.name for p in out.iterdir() if p.name != "manifest.json"}


# -- kill -9 of the parent ---------------------------------------------------------------------


def test_kill_9_of_the_parent_ends_its_workers(tmp_path, runs):
    r = start(runs, ["anneal", "3_1", "--moves", "50000000", "--replicas", "2"], tmp_path)
    assert until(lambda: len(workers(r.p.pid)) == 2, 120), r.err
    pids = workers(r.p.pid)
    os.kill(r.p.pid, signal.SIGKILL)
    r.wait()
    assert until(lambda: not any(alive(p) for p in pids), 10), [p for p in pids if alive(p)]


def test_sigterm_stops_a_run_after_its_knot_checks(tmp_path, runs):
    # topoly's HOMFLY-PT code installs a C handler for SIGTERM; before the fix, once the start's
    # polynomial was computed `kill PID` was swallowed and the run went on for its whole budget
    r = start(runs, ["anneal", "3_1", "--moves", "50000000", "--replicas", "2"], tmp_path)
    assert until(lambda: len(workers(r.p.pid)) == 2, 120), r.err
    time.sleep(1.0)  # the workers run their replicas: every knot check of the start is done
    pids = workers(r.p.pid)
    os.kill(r.p.pid, signal.SIGTERM)
    # the same stop as Ctrl-C (since 2026-12-03; it was a plain kill), with exit code 143
    rc = r.wait(timeout=20)
    assert rc == 143, r.err
    assert "Traceback" not in r.err
    lines = [ln for ln in r.err.splitlines() if ln.strip()]
    assert lines and lines[-1].startswith("interrupted"), r.err  # as Ctrl-C says it
    assert until(lambda: not any(alive(p) for p in pids), 10), [p for p in pids if alive(p)]


def test_sigterm_after_two_of_three_replicas_reports_them(tmp_path, runs):
    """``kill PID`` stops a run as Ctrl-C does: the finished replicas shown, written and
    marked partial, exit code 143 (a batch system's stop keeps what was done)."""
    r = start(runs, ["anneal", "3_1", "--replicas", "3", "--moves", "600000", "--out", "out"],
              tmp_path)
    assert until(lambda: sum("finished in" in ln for ln in r.err_lines) >= 2, 300), r.err
    pids = workers(r.p.pid)
    os.kill(r.p.pid, signal.SIGTERM)
    rc = r.wait()
    if sum("finished in" in ln for ln in r.err_lines) == 3:
        pytest.skip("the third replica finished with the others (more than two cores)")
    assert rc == 143, r.err
    assert "Traceback" not in r.err
    lines = [ln for ln in r.err.splitlines() if ln.strip()]
    assert lines[-1].startswith("interrupted: 2 of 3 replicas finished"), r.err
    res = json.loads((tmp_path / "out" / "result.json").read_text())
    assert res["interrupted"] is True and len(res["replicas"]) == 2
    assert until(lambda: not any(alive(p) for p in pids), 10), [p for p in pids if alive(p)]


# -- two runs ----------------------------------------------------------------------------------


def test_a_second_run_into_a_folder_in_use_is_refused(tmp_path, runs):
    a = start(runs, ["anneal", "3_1", "--moves", "50000000", "--replicas", "1", "--out", "out",
                     "--checkpoint", "ck"], tmp_path)
    assert until(lambda: workers(a.p.pid), 120), a.err
    for opt, folder in (("--out", "out"), ("--checkpoint", "ck")):
        b = subprocess.run([*CLI, "anneal", "3_1", "--moves", "2000", "--replicas", "1", opt,
                            folder], cwd=tmp_path, capture_output=True, text=True, timeout=120)
        lines = [ln for ln in b.stderr.splitlines() if ln.strip()]
        assert b.returncode == 2 and lines == [f"error: {opt} {folder} is in use by another "
                                               "run"], b.stderr
    a.interrupt()
    assert_interrupted(a, a.wait())
    assert not (tmp_path / "out").exists()  # nothing finished: the claimed folder is released


def test_two_anneals_into_one_folder(tmp_path):
    """The second is refused; with --overwrite it replaces the first completely (no stale
    replica_1.xyz of the first run's second replica)."""
    def run(*extra):
        # one round: with --replicas 1 the adaptive rounds would add replica_1 … by themselves
        return subprocess.run([*CLI, "anneal", "3_1", "--moves", "20000", "--rounds", "1",
                               "--out", "out", "--json", *extra], cwd=tmp_path,
                              capture_output=True, text=True, timeout=300)

    assert run("--replicas", "2").returncode == 0
    assert (tmp_path / "out" / "replica_1.xyz").exists()
    p = run("--replicas", "1")
    assert p.returncode == 2 and "holds the results of another run" in p.stderr
    p = run("--replicas", "1", "--overwrite")
    assert p.returncode == 0, p.stderr
    names = {q.name for q in (tmp_path / "out").iterdir()}
    assert "replica_1.xyz" not in names
    listed = set(json.loads((tmp_path / "out" / "manifest.json").read_text())["files"])
    assert listed == names - {"manifest.json"}


def test_ctrl_c_during_the_paper_study_removes_its_files(tmp_path, runs):
    r = start(runs, ["paper", "--budget", "tiny", "--out", "p"], tmp_path)
    assert until(lambda: workers(r.p.pid), 300), r.err
    time.sleep(1.0)
    r.interrupt()
    assert_interrupted(r, r.wait(), "interrupted while running the study; the files of this "
                                    "run were removed")
    assert not (tmp_path / "p").exists()
