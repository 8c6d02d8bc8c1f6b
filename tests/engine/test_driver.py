"""The run loop (:mod:`stiffknots.engine.driver`, paper §VII): a replica's result is verified
(energy bookkeeping, bonds, exclusion) and records one trace value per chunk."""

import math

import pytest

from helpers import braid_chain
from stiffknots.engine.driver import AnnealSettings, run_replica


def chain(name, n=150):
    return braid_chain(name, n)


def test_driver_verifies_and_records():
    res = run_replica(chain("3_1"), AnnealSettings(moves=400_000, n_chunks=20), seed=5)
    assert res.energy == pytest.approx(res.energy_recomputed)
    assert res.max_bond_error < 1e-10
    assert res.exclusion_margin >= 0
    assert len(res.trace_epsilon) == 30
    assert res.epsilon >= 2 * math.pi**2 * 4 * 0.99  # lower bound 2π²n², n = 2 (discrete)
