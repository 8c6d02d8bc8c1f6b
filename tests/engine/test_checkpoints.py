"""Checkpoint/resume of long runs (:mod:`stiffknots.engine.checkpoints`, through the driver,
tempering, anneal() and the CLI): a run stopped and resumed ends with exactly the chain and
energy of an uninterrupted run with the same seed (§VII)."""

import json
import subprocess
import sys
from dataclasses import replace

import numpy as np
import pytest

from helpers import braid_chain
from stiffknots.engine.checkpoints import load_checkpoint
from stiffknots.engine.driver import run_replica
from stiffknots.engine.params import Ensemble, MoveParams
from stiffknots.engine.schedules import Schedule
from stiffknots.engine.settings import AnnealSettings
from stiffknots.engine.tempering import run_tempering
from stiffknots.errors import RunStopped
from stiffknots.problems.closed import anneal, checkpoint_path


def chain(name, n=150):
    return braid_chain(name, n)


SMALL = AnnealSettings(moves=300_000, n_chunks=20)
PT = replace(SMALL, schedule=Schedule(kind="tempering", t_start=1e-3, t_end=1e-6, n_temps=3))
# the fixed-force ensemble (§VIII) and the restricted-curvature plan (§IX D) run through the
# same loop and must resume exactly too
FORCE = replace(SMALL, ensemble=Ensemble("force", force=0.05), schedule=Schedule(
    kind="geometric", t_start=1e-2, t_end=1e-6, relax_fraction=0.0))
TIGHT = replace(SMALL, plan="tight", params=MoveParams(exclusion="tube", w=0.25))
# basin hops (each from the lowest polished chain so far) resume exactly too
HOPS = replace(SMALL, schedule=Schedule(hops=3, hop_fraction=0.3))


def start_of(settings):
    if settings.ensemble.kind == "force":
        from stiffknots.knots.open_embedding import pad_open_chain
        from stiffknots.problems.open_extension import open_chain

        return pad_open_chain(open_chain("3_1", 30, seed=0), 80)
    return chain("3_1")


def same(a, b):
    assert np.array_equal(a.coords, b.coords)
    assert a.epsilon == b.epsilon and a.energy == b.energy
    assert np.array_equal(a.trace_epsilon, b.trace_epsilon)
    assert np.array_equal(a.trace_moves, b.trace_moves)
    assert a.acceptance == b.acceptance
    assert a.stage_epsilon == b.stage_epsilon and a.best_stage == b.best_stage


def run(x, settings, **kw):
    """The driver's run loop, or replica exchange for a tempering schedule."""
    if settings.schedule.kind == "tempering":
        return run_tempering(x, settings, **kw)
    return run_replica(x, settings, **kw)


@pytest.mark.parametrize("settings", [SMALL, PT, FORCE, TIGHT,
                                      pytest.param(HOPS, marks=pytest.mark.slow)],  # ≈ 16 s
                         ids=["anneal", "tempering", "force", "tight", "hops"])
def test_stop_and_resume_is_exact(tmp_path, settings):
    x = start_of(settings)
    a = run(x, settings, seed=11)
    ck = tmp_path / "run.npz"
    # stop twice (the second time across the end of the relaxation stage), then finish
    with pytest.raises(RunStopped) as e1:
        run(x, settings, seed=11, checkpoint=ck, stop_after=5)
    assert e1.value.step == 5 and ck.exists()
    with pytest.raises(RunStopped) as e2:
        run(x, settings, seed=11, checkpoint=ck, resume=True, stop_after=9)
    assert e2.value.step == 14
    b = run(x, settings, seed=11, checkpoint=ck, resume=True)
    assert b.resumed_from_step == 14
    same(a, b)
    arrays, meta = load_checkpoint(ck)  # the final checkpoint resumes to the same result
    assert meta["step"] == meta["n_steps"] and meta["seed"] == 11
    same(a, run(x, settings, seed=11, checkpoint=ck, resume=True))


def test_periodic_checkpoint_and_fresh_start(tmp_path):
    x = chain("4_1")
    a = run_replica(x, SMALL, seed=3)
    ck = tmp_path / "sub" / "run.npz"
    b = run_replica(x, SMALL, seed=3, checkpoint=ck, checkpoint_every=4, resume=True)
    same(a, b)  # resume=True without a file starts afresh; checkpointing changes nothing
    arrays, meta = load_checkpoint(ck)
    assert meta["version"] and meta["settings"] == json.loads(json.dumps(SMALL.as_dict()))
    assert arrays["pos"].shape == (150, 3) and arrays["rng"].dtype == np.uint64
    assert len(arrays["trace_epsilon"]) == meta["n_steps"]
    ck2 = tmp_path / "timed.npz"  # by the clock: a tiny period writes after every chunk
    with pytest.raises(RunStopped):
        run_replica(x, SMALL, seed=3, checkpoint=ck2, checkpoint_seconds=1e-9, stop_after=2)
    same(a, run_replica(x, SMALL, seed=3, checkpoint=ck2, checkpoint_seconds=1e-9, resume=True))


def test_resume_refuses_another_run(tmp_path):
    x = chain("3_1")
    ck = tmp_path / "run.npz"
    with pytest.raises(RunStopped):
        run_replica(x, SMALL, seed=1, checkpoint=ck, stop_after=3)
    with pytest.raises(ValueError, match="seed"):
        run_replica(x, SMALL, seed=2, checkpoint=ck, resume=True)
    with pytest.raises(ValueError, match="settings"):
        run_replica(x, replace(SMALL, moves=400_000), seed=1, checkpoint=ck, resume=True)
    with pytest.raises(ValueError, match="starting chain"):
        run_replica(chain("4_1"), SMALL, seed=1, checkpoint=ck, resume=True)


def test_anneal_checkpoint_dir(tmp_path):
    kw = dict(moves=200_000, replicas=1, seed=4, workers=1, rounds=1)
    a = anneal("3_1", **kw)
    b = anneal("3_1", **kw, checkpoint_dir=tmp_path)
    assert checkpoint_path(tmp_path, 0).exists()
    c = anneal("3_1", **kw, checkpoint_dir=tmp_path, resume=True)  # from the final checkpoint
    for r in (b, c):
        assert np.array_equal(r.best.coords, a.best.coords) and r.epsilon == a.epsilon
    assert c.best.resumed_from_step is not None
    with pytest.raises(ValueError, match="checkpoint_dir"):
        anneal("3_1", **kw, resume=True)
    with pytest.raises(ValueError, match="differs"):
        anneal("3_1", **{**kw, "moves": 300_000}, checkpoint_dir=tmp_path, resume=True)


def test_cli_resume_needs_checkpoint():
    p = subprocess.run([sys.executable, "-m", "stiffknots.cli", "anneal", "3_1", "--resume"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 2 and "--checkpoint" in p.stderr


def test_cli_checkpoint_resume(tmp_path):
    def cli(*extra):
        p = subprocess.run([sys.executable, "-m", "stiffknots.cli", "anneal", "4_1", "--moves",
                            "300000", "--replicas", "1", "--rounds", "1", "--json", *extra],
                           capture_output=True, text=True, timeout=600)
        assert p.returncode == 0, p.stderr
        return json.loads(p.stdout)

    a = cli("--checkpoint", str(tmp_path))
    b = cli("--checkpoint", str(tmp_path), "--resume")
    assert a["epsilon"] == b["epsilon"]


KILLED_FORCE_RUN = """
import sys
from stiffknots.problems.open_force import anneal_open_force
anneal_open_force("3_1", 0.05, n_beads=80, moves=3_000_000, replicas=1, seed=1, workers=1,
                  checkpoint_dir=sys.argv[1], checkpoint_seconds=0.05)
"""


@pytest.mark.slow
def test_force_route_resumes_exactly_after_kill_9(tmp_path):
    # an open knot at fixed force (§VIII), killed with SIGKILL in the middle of its run, then
    # resumed from its checkpoint: the same chain, bit for bit, as an uninterrupted run
    import os
    import signal
    import subprocess
    import sys
    import time

    from stiffknots.problems.open_force import anneal_open_force

    kw = {"n_beads": 80, "moves": 3_000_000, "replicas": 1, "seed": 1, "workers": 1}
    ref = anneal_open_force("3_1", 0.05, **kw)
    ck = tmp_path / "ck"
    p = subprocess.Popen([sys.executable, "-c", KILLED_FORCE_RUN, str(ck)])
    f = ck / "replica_0.ckpt.npz"
    t0 = time.time()
    while not f.exists() and time.time() - t0 < 120:
        time.sleep(0.05)
    time.sleep(0.5)  # let it run on past the first checkpoint
    os.kill(p.pid, signal.SIGKILL)
    p.wait()
    _, meta = load_checkpoint(f)
    assert 0 < meta["step"] < meta["n_steps"]  # killed in the middle
    res = anneal_open_force("3_1", 0.05, checkpoint_dir=ck, resume=True, **kw)
    assert res.best.resumed_from_step == meta["step"]
    assert np.array_equal(res.best.coords, ref.best.coords)
    assert res.best.total_energy == ref.best.total_energy
