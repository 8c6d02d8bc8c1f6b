"""Parallel tempering (replica exchange) for the chain of §VII: the swap criterion, its
bookkeeping, energies and topology of every copy, reproducibility."""

import math
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from helpers import braid_chain
from stiffknots.engine import kernel as K
from stiffknots.engine.driver import AnnealSettings
from stiffknots.engine.schedules import Schedule
from stiffknots.engine.state import ChainState, MoveParams
from stiffknots.engine.tempering import (
    attempt_swaps,
    copy_seeds,
    run_tempering,
    swap_probability,
)
from stiffknots.knots.identify import identify


def chain(name, n=150):
    return braid_chain(name, n)


PT = AnnealSettings(moves=400_000, n_chunks=20,
                    schedule=Schedule(kind="tempering", t_start=1e-3, t_end=1e-6, n_temps=4))


def test_swap_probability_limits():
    assert swap_probability(1e-3, 1e-3, 0.7, 0.2) == 1.0  # equal temperatures
    assert swap_probability(1e-4, 1e-2, 0.5, 0.5) == 1.0  # equal energies
    assert swap_probability(1e-4, 1e-2, 0.9, 0.5) == 1.0  # the cold copy has the higher E
    p = swap_probability(1e-4, 1e-3, 0.50, 0.51)
    assert p == pytest.approx(math.exp(-(1e4 - 1e3) * 0.01))
    assert swap_probability(1e-7, 1e-2, 0.0, 1.0) == 0.0  # no overflow


def test_swap_detailed_balance():
    """π(x) P(x→y) = π(y) P(y→x) for the product measure exp(−E_a/T_a − E_b/T_b)."""
    rng = np.random.default_rng(0)
    for _ in range(200):
        t1, t2 = np.sort(rng.uniform(1e-3, 1e-2, 2))
        e1, e2 = rng.uniform(0.5, 0.52, 2)
        fwd = math.exp(-e1 / t1 - e2 / t2) * swap_probability(t1, t2, e1, e2)
        rev = math.exp(-e2 / t1 - e1 / t2) * swap_probability(t1, t2, e2, e1)
        assert fwd == pytest.approx(rev, rel=1e-9)


def test_attempt_swaps_bookkeeping():
    temps = np.full(5, 1e-3)  # equal temperatures: every attempt is accepted
    states = [SimpleNamespace(energy=float(e), name=i) for i, e in enumerate([3, 1, 4, 1, 5])]
    tried = np.zeros(4, dtype=np.int64)
    acc = np.zeros(4, dtype=np.int64)
    order = np.arange(5)
    rng = K.new_rng_state(1)
    attempt_swaps(states, temps, 0, rng, tried, acc, order)
    assert list(tried) == [1, 0, 1, 0] and list(acc) == [1, 0, 1, 0]
    assert [s.name for s in states] == [1, 0, 3, 2, 4] and list(order) == [1, 0, 3, 2, 4]
    attempt_swaps(states, temps, 1, rng, tried, acc, order)
    assert list(tried) == [1, 1, 1, 1] and list(order) == [1, 3, 0, 4, 2]


def test_swap_frequency_matches_metropolis():
    t = np.array([1e-3, 2e-3])
    e_cold, e_hot = 0.500, 0.498  # cold copy lower: p = exp(−500·0.002) = e^−1
    tried = np.zeros(1, dtype=np.int64)
    acc = np.zeros(1, dtype=np.int64)
    rng = K.new_rng_state(9)
    n = 20_000
    for _ in range(n):
        states = [SimpleNamespace(energy=e_hot), SimpleNamespace(energy=e_cold)]
        attempt_swaps(states, t, 0, rng, tried, acc, np.arange(2))
    p = swap_probability(t[0], t[1], e_hot, e_cold)
    assert p == pytest.approx(math.exp(-1.0))
    assert abs(acc[0] / n - p) < 4 * math.sqrt(p * (1 - p) / n)


def test_copies_energy_and_knot_type():
    """Every copy keeps its incremental energy equal to the recomputed one and its knot type,
    through moves and exchanges."""
    x = chain("4_1")
    start = identify(x)
    temps = Schedule(kind="tempering", t_start=1e-1, t_end=1e-4, n_temps=4).ladder()
    seeds = copy_seeds(5, 4)
    states = [ChainState(x, MoveParams(), seed=seeds[k]) for k in range(4)]
    tried = np.zeros(3, dtype=np.int64)
    acc = np.zeros(3, dtype=np.int64)
    order = np.arange(4)
    rng = K.new_rng_state(seeds[4])
    for r in range(6):
        for k in range(4):
            states[k].run(50_000, temps[k])
        attempt_swaps(states, temps, r % 2, rng, tried, acc, order)
    for s in states:
        assert s.energy == pytest.approx(s.recomputed_energy(), rel=1e-10, abs=1e-12)
        assert s.violation() <= 1e-12
        assert identify(s.pos) == start
    assert sorted(order) == [0, 1, 2, 3]
    assert tried.sum() == 3 * 3  # 6 rounds: pairs (0,1),(2,3) then (1,2), alternately


def test_run_tempering_result():
    x = chain("3_1")
    a = run_tempering(x, PT, seed=2)
    b = run_tempering(x, PT, seed=2)
    assert np.array_equal(a.coords, b.coords) and a.epsilon == b.epsilon
    info = a.tempering
    assert info["ladder"] == pytest.approx(list(np.geomspace(1e-6, 1e-3, 4)))
    assert all(0 <= r <= 1 for r in info["swap_rate"])
    assert all(t >= s for t, s in zip(info["swap_tried"], info["swap_accepted"], strict=True))
    assert sum(info["swap_tried"]) == 10 * 2 + 10 * 1  # 20 rounds, even/odd pairs
    assert a.energy == pytest.approx(a.energy_recomputed)
    assert a.exclusion_margin >= 0 and a.max_bond_error < 1e-10
    assert identify(a.coords) == identify(x)
    assert a.trace_moves[-1] <= PT.moves
    c = run_tempering(x, replace(PT, moves=410_000), seed=2)
    assert not np.array_equal(a.coords, c.coords)


def test_tempering_validation():
    with pytest.raises(ValueError, match="n_temps"):
        Schedule(kind="tempering", n_temps=1).validate()
    with pytest.raises(ValueError, match="schedule"):
        Schedule(kind="hotter").validate()
