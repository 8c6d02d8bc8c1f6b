"""Knot identification (stiffknots.knots.identify) and its agreement with the embeddings."""

import sys
from pathlib import Path

import numpy as np
import pytest

from stiffknots.knots.embedding import (
    D_MIN,
    embed_braid,
    embedding_report,
    minimal_beads,
    parse_braid,
    regular_polygon,
)
from stiffknots.knots.identify import (
    close_open_chain_along_z,
    crossing_number_of_name,
    homfly_code,
    identify,
    normalize_name,
    verify_knot,
)


def _knotinfo(max_crossings, min_crossings=0):
    import database_knotinfo

    out = []
    for k in database_knotinfo.link_list()[1:]:  # row 0 is the header
        c = int(k["crossing_number"])
        if c > max_crossings:
            break
        if c >= min_crossings:
            out.append((k["name"], parse_braid(k["braid_notation"])))
    return out


def _torus(p, q, n=150):
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    r = 2 + np.cos(q * t)
    return np.column_stack([r * np.cos(p * t), r * np.sin(p * t), -np.sin(q * t)])


def test_normalize_name():
    assert normalize_name("4.1") == "4_1"
    assert normalize_name("+4_1") == normalize_name("-4_1") == "4_1"
    assert normalize_name("K3_1") == "3_1"
    assert normalize_name("12n25") == normalize_name("12n_25") == "12n_25"
    assert normalize_name("unknot") == "0_1"
    assert normalize_name("+10_132|-5_1") == "5_1|10_132"
    # composite: relative chirality survives a global mirror
    assert normalize_name("+3_1#+3_1") == normalize_name("-3_1#-3_1") == "3_1#3_1"
    assert normalize_name("+3_1#-3_1") == normalize_name("-3_1#+3_1") == "3_1#-3_1"
    assert crossing_number_of_name("5_2#4_1") == 9


def test_unknot_and_torus_knots():
    assert identify(regular_polygon(150)) == "0_1"
    assert identify(regular_polygon(40)[:, [0, 2, 1]]) == "0_1"  # planar, seen edge-on
    assert identify(_torus(2, 3)) == "3_1"
    assert identify(_torus(2, 5)) == "5_1|10_132"  # HOMFLY-PT cannot separate these
    assert identify(_torus(2, 5), max_crossings=9) == "5_1"
    assert verify_knot(_torus(2, 5), "5.1") == (True, "5_1|10_132")
    assert identify(_torus(3, 4)) == "8_19"
    # repeated first point tolerated
    x = _torus(2, 3)
    assert identify(np.vstack([x, x[:1]])) == "3_1"


def test_mirror_insensitive():
    for w in ([1, 1, 1], [1, 1, 1, 2, -1, 2]):
        x = embed_braid(w, n_beads=150)
        xm = embed_braid([-g for g in w], n_beads=150)
        assert identify(x) == identify(xm)
        assert identify(x * np.array([1, 1, -1])) == identify(x)


def test_verify_knot_mismatch():
    x = embed_braid([1, -2, 1, -2], n_beads=150)
    assert verify_knot(x, "4_1") == (True, "4_1")
    assert verify_knot(x, "3_1") == (False, "4_1")


def test_open_chain_closure_along_z():
    # a straight open chain is unknotted
    line = np.column_stack([np.zeros(10), np.zeros(10), np.arange(10.0)])
    assert identify(line, closed=False) == "0_1"
    # open 5_2: the closed chain cut at its lowest bond; the end is led down, out sideways and
    # up far outside, so that the start is at the bottom and the end at the top (as for the
    # straight tails of the paper's open knots); closing along z gives back the knot
    for word, name in (([1, 1, 1, 2, -1, 2], "5_2"), ([1, -2, 1, -2], "4_1")):
        x = embed_braid(word, n_beads=150, seed=5)
        b = int(np.argmin(x[:, 2]))
        x = np.roll(x, -b, axis=0)  # bead 0 lowest, bead N-1 its neighbour
        lo, hi = x.min(axis=0), x.max(axis=0)
        end = x[-1]
        tail = np.array(
            [
                [end[0], end[1], lo[2] - 2.0],
                [hi[0] + 5.0, end[1], lo[2] - 2.0],
                [hi[0] + 5.0, end[1], hi[2] + 3.0],
            ]
        )
        openchain = np.vstack([x, tail])
        closed = close_open_chain_along_z(openchain)
        assert closed.shape == (len(openchain) + 4, 3)
        assert verify_knot(openchain, name, closed=False)[0]


def _check_knot(name, word, n_beads=150):
    x = embed_braid(word, n_beads=n_beads)
    rep = embedding_report(x)
    assert rep.max_bond_error < 1e-10, name
    assert rep.min_bead_distance >= D_MIN, name
    ok, found = verify_knot(x, name)
    assert ok, (name, found)
    okm, foundm = verify_knot(embed_braid([-g for g in word], n_beads=n_beads), name)
    assert okm and foundm == found, (name, found, foundm)


@pytest.mark.parametrize("name,word", _knotinfo(8), ids=lambda v: v if isinstance(v, str) else "")
def test_knotinfo_through_8_crossings(name, word):
    _check_knot(name, word)


@pytest.mark.slow
@pytest.mark.parametrize("name,word", _knotinfo(10, 9),
                         ids=lambda v: v if isinstance(v, str) else "")
def test_knotinfo_9_and_10_crossings(name, word):
    _check_knot(name, word)


@pytest.mark.slow
@pytest.mark.parametrize("name,word", _knotinfo(10, 3),
                         ids=lambda v: v if isinstance(v, str) else "")
def test_minimal_embedding_keeps_knot_type(name, word):
    n = minimal_beads(word)
    assert n <= 150
    ok, found = verify_knot(embed_braid(word, n_beads=n), name)
    assert ok, (name, n, found)


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads /proc (Linux)")
def test_topoly_leaves_sigterm_at_its_default():
    """topoly's compiled code installs a SIGTERM handler; identify puts the default back, so
    that `kill PID` still stops a run (it used to be swallowed)."""
    import signal

    t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
    x = np.c_[np.sin(t) + 2 * np.sin(2 * t), np.cos(t) - 2 * np.cos(2 * t), -np.sin(3 * t)]
    homfly_code(x)
    caught = next(int(line.split()[1], 16) for line in Path("/proc/self/status").read_text()
                  .splitlines() if line.startswith("SigCgt:"))
    assert not caught >> (signal.SIGTERM - 1) & 1


_SIGTERM_SCRIPT = """
import os, signal
from stiffknots.knots.identify import _keep_sigterm
got = []
signal.signal(signal.SIGTERM, lambda s, f: got.append("ours"))
with _keep_sigterm():
    # as topoly does: a handler of its own (a C one there; a pending signal survives a
    # handler change, it would not survive SIG_IGN)
    signal.signal(signal.SIGTERM, lambda s, f: got.append("topoly's"))
    os.kill(os.getpid(), signal.SIGTERM)
    during = list(got)
import time
end = time.monotonic() + 10
while not got and time.monotonic() < end:  # the Python-level handler runs in this thread
    time.sleep(0.001)
print(during, got)
"""


@pytest.mark.skipif(not hasattr(__import__("signal"), "pthread_sigmask"), reason="POSIX")
def test_a_sigterm_during_a_knot_check_is_not_lost():
    """SIGTERM is held back while topoly runs (it installs a handler of its own that swallows
    it): one sent then reaches the process's own handler once the call is over — the command
    line's stop of ``kill PID`` (stiffknots.cli.main) never came when it fell in a knot check.
    In a fresh process: topoly runs in the caller only while it is the process's one thread
    (the mask is per thread; a test runner's threads would take the signal)."""
    import subprocess
    import sys

    p = subprocess.run([sys.executable, "-c", _SIGTERM_SCRIPT], capture_output=True,
                       text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert p.stdout.split("\n")[0] == "[] ['ours']", p.stdout


_KILL_DURING_CHECKS_SCRIPT = """
import stiffknots  # first: numpy's threads then start with SIGTERM blocked
import os, signal, subprocess, time
import numpy as np
from stiffknots.knots.identify import homfly_code

got = []
signal.signal(signal.SIGTERM, lambda s, f: got.append("ours"))
t = np.linspace(0, 2 * np.pi, 120, endpoint=False)
x = np.column_stack([(2 + np.cos(5 * t)) * np.cos(3 * t), (2 + np.cos(5 * t)) * np.sin(3 * t),
                     np.sin(5 * t)])  # the (5, 3) torus knot: ~0.1 s a check, 90 % of it in topoly
homfly_code(x)
others = [t for t in os.listdir("/proc/self/task") if int(t) != os.getpid()]
free = [t for t in others
        if not int(open(f"/proc/self/task/{t}/status").read().split("SigBlk:")[1].split()[0], 16)
        & (1 << (signal.SIGTERM - 1))]
killer = subprocess.Popen(["sh", "-c", f"sleep 0.5; kill -TERM {os.getpid()}"])
end, calls = time.monotonic() + 10, 0
while not got and time.monotonic() < end:
    homfly_code(x)
    calls += 1
killer.wait()
print(len(others), len(free), got, calls)
"""


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
def test_a_kill_during_real_knot_checks_reaches_the_process():
    """``kill PID`` while knot checks run back to back (topoly's own SIGTERM handler installed
    at each): it reaches the process's handler. numpy's OpenBLAS threads block SIGTERM (they
    took it before and topoly's handler swallowed it: 5 lost of 5 tries)."""
    import subprocess

    p = subprocess.run([sys.executable, "-c", _KILL_DURING_CHECKS_SCRIPT], capture_output=True,
                       text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    others, free, got, calls = p.stdout.split()
    assert free == "0", p.stdout
    assert got == "['ours']", p.stdout


_FORK_NOISE_SCRIPT = """
import os, threading, time
import numpy as np
from stiffknots.knots.identify import homfly_code

# CPython's own after-fork handler (threading._after_fork) re-initialises the locks of the
# other threads in the child and can fail there ("SystemError ... _thread.RLock", seen with two
# sk.anneal calls in two threads); an after-fork handler that fails stands in for it
os.register_at_fork(after_in_child=lambda: 1 / 0)
stop = threading.Event()
other = threading.Thread(target=stop.wait)  # a second thread: the knot check forks
other.start()
t = np.linspace(0, 2 * np.pi, 60, endpoint=False)
x = np.column_stack([(2 + np.cos(3 * t)) * np.cos(2 * t), (2 + np.cos(3 * t)) * np.sin(2 * t),
                     np.sin(3 * t)])
codes = {homfly_code(x) for _ in range(3)}
stop.set()
other.join()
print(len(codes))
"""


def test_a_knot_check_forked_from_a_threaded_process_prints_nothing():
    """#40 row 10: two sk.anneal calls in two threads printed 'SystemError … _thread.RLock'
    tracebacks from threading's _after_fork: the knot check forks a child when other threads
    run, and Python reports in the child what its after-fork handlers fail to re-initialise
    of threads the child does not have. The child runs topoly alone and leaves by _exit: that
    report is noise on the user's stderr."""
    import subprocess
    import sys

    p = subprocess.run([sys.executable, "-c", _FORK_NOISE_SCRIPT], capture_output=True,
                       text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip() == "1"
    assert p.stderr == "", p.stderr
