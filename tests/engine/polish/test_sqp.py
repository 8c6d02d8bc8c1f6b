"""The SQP iteration of the final minimiser (:mod:`stiffknots.engine.polish.sqp`): when it
stops."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from stiffknots.engine.polish import polish

DATA = Path(__file__).resolve().parents[2] / "data" / "analysis"


def fixture_chain(name: str) -> np.ndarray:
    return np.load(DATA / f"{name}.npy")


def test_stall_stop_is_the_minimum_to_far_below_its_promise(monkeypatch):
    # a 3_1 circular braid crawls for tens of steps after its energy has settled; the stall
    # stop ends there, converged, at the energy the crawl would reach to ≤ 1e-9 relative
    import stiffknots.engine.polish.sqp as P

    x = fixture_chain("3_1_seed1_r0")
    fast = polish(x)
    assert fast.converged and fast.relative_kkt <= P.STALL_KKT
    monkeypatch.setattr(P, "STALL_STEPS", 10**9)  # no stall stop: run to the KKT tolerance
    slow = polish(x)
    assert fast.iterations <= slow.iterations
    assert fast.energy == pytest.approx(slow.energy, rel=1e-9)
    assert fast.energy <= fast.energy_before
