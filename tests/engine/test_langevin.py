"""Guarded Langevin dynamics (engine.langevin, engine.langevin_kernel): forces, the passage
guard, admissible results of the same knot type, reproducibility, and the schedule."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from tests.helpers import braid_chain

from stiffknots.engine.driver import AnnealSettings
from stiffknots.engine.guard import passage_guard
from stiffknots.engine.langevin import (
    LangevinSettings,
    project_bonds,
    run_langevin,
    run_langevin_replica,
    unit_epsilon,
)
from stiffknots.engine.langevin_kernel import _build_pairs, forces, guard_distance, run_dynamics
from stiffknots.engine.params import MoveParams
from stiffknots.engine.prims import check_state, new_rng_state
from stiffknots.engine.schedules import Schedule
from stiffknots.errors import InvalidParameter
from stiffknots.knots.identify import verify_knot

D = 1 / math.sqrt(2)
DATA = Path(__file__).resolve().parent.parent / "data" / "analysis"
CONTACT = 0.72


def potential(pos, k_bond=1000.0, contact=CONTACT):
    """U of the kernel's model, written independently (numpy, all pairs)."""
    n = len(pos)
    b = np.roll(pos, -1, axis=0) - pos
    ln = np.linalg.norm(b, axis=1)
    u = b / ln[:, None]
    e = k_bond * np.sum((ln - 1) ** 2) + np.sum(1 - np.sum(np.roll(u, 1, axis=0) * u, axis=1))
    sigma = contact / 2 ** (1 / 6)
    for i in range(n):
        for j in range(i + 2, n):
            if i == 0 and j == n - 1:
                continue
            r = np.linalg.norm(pos[i] - pos[j])
            if r < contact:
                q = (sigma / r) ** 6
                e += 4 * (q * q - q) + 1
    return e


def kernel_forces(pos, k_bond=1000.0, contact=CONTACT):
    n = len(pos)
    pi, pj = np.empty(64 * n, np.int64), np.empty(64 * n, np.int64)
    k = _build_pairs(pos, (contact + 0.3) ** 2, pi, pj)
    f, gb, ub, il = np.empty((n, 3)), np.empty((n, 3)), np.empty((n, 3)), np.empty(n)
    u = forces(pos, k_bond, contact / 2 ** (1 / 6), contact ** 2, pi, pj, k, f, gb, ub, il)
    return u, f


def squeezed_chain():
    """A 4_1 chain with bonds off unit length and two beads pressed inside the WCA wall."""
    x = braid_chain("4_1", 60)
    rng = np.random.default_rng(3)
    x = x + rng.normal(0, 0.02, x.shape)
    d = np.linalg.norm(x[:, None] - x[None], axis=2)
    i, j = np.triu_indices(len(x), 2)
    keep = ~((i == 0) & (j == len(x) - 1))
    a, b = i[keep][np.argmin(d[i, j][keep])], j[keep][np.argmin(d[i, j][keep])]
    x[b] = x[a] + (x[b] - x[a]) * 0.69 / np.linalg.norm(x[b] - x[a])  # inside 0.72
    return x


def test_forces_are_minus_the_gradient_of_the_potential():
    x = squeezed_chain()
    u, f = kernel_forces(x)
    assert u == pytest.approx(potential(x), rel=1e-12)
    h = 1e-6
    for i in (0, 7, 31, 59):
        for q in range(3):
            xp, xm = x.copy(), x.copy()
            xp[i, q] += h
            xm[i, q] -= h
            g = (potential(xp) - potential(xm)) / (2 * h)
            assert f[i, q] == pytest.approx(-g, rel=1e-5, abs=1e-6)


def test_guard_distance_is_the_smallest_distance_between_strands():
    from stiffknots.engine.prims import min_nonadjacent_segment_distance

    for name, seg in (("5_2_seed1_r0", 0.36996), ("4_1_seed0_r0", 0.21586)):
        x = np.load(DATA / f"{name}.npy")  # annealed bead-rule chains, N = 150
        exact = float(min_nonadjacent_segment_distance(x, False))
        assert exact == pytest.approx(seg, abs=1e-5)
        assert guard_distance(x, 0.5) == pytest.approx(exact, abs=1e-12)
        assert guard_distance(x, 0.1) == 0.1  # capped


def crossing_loop():
    """A closed 8-bead loop whose segment (0, 1) passes 0.2 above segment (4, 5)."""
    return np.array([
        [-0.5, 0.0, 0.1], [0.5, 0.0, 0.1], [1.5, 0.5, 0.1], [1.5, 1.5, 0.0],
        [0.0, 0.5, -0.1], [0.0, -0.5, -0.1], [-1.5, -1.5, 0.0], [-1.5, -0.5, 0.1],
    ])


@pytest.mark.parametrize("guard", [True, False])
def test_guard_refuses_a_step_that_passes_a_strand_through_another(guard):
    old = crossing_loop()
    x = old.copy()
    v = np.zeros_like(x)
    v[[0, 1], 2] = -40.0  # one step of dt = 0.01 moves segment (0, 1) 0.4 down, through (4, 5)
    v[3, 1] = 5.0  # bead 3, far from the crossing, moves 0.05 along y
    st = np.zeros(5)
    run_dynamics(x, v, 1, 0.01, 1e-9, 1e-12, 1e-13, 1e-6, 0.3, 0.3, 0.5, new_rng_state(1), st,
                 guard)
    assert x[3, 1] == pytest.approx(old[3, 1] + 0.05, abs=1e-6)  # bead 3 moves either way
    if guard:
        # only the beads of the pair that would pass stay, their velocities reversed
        assert st[1] == 2
        assert np.array_equal(x[[0, 1]], old[[0, 1]])
        # the others move by the bending forces only (≈ 10⁻⁵)
        assert np.allclose(x[[2, 4, 5, 6, 7]], old[[2, 4, 5, 6, 7]], atol=1e-3)
        assert v[0, 2] > 39.0 and v[1, 2] > 39.0
        assert passage_guard(old, x)
    else:  # the unguarded step is a strand passage (what the guard exists for)
        assert st[1] == 0
        assert x[0, 2] < -0.2
        assert not passage_guard(old, x)


def test_guard_lets_a_close_pair_move_apart():
    # segment (0, 1) sits 0.01 above (4, 5) and moves up, away from it: the step is certified
    # by the pair's fresh distance, not refused
    old = crossing_loop()
    old[[0, 1, 7], 2] = -0.09
    x = old.copy()
    v = np.zeros_like(x)
    v[[0, 1], 2] = 1.0
    st = np.zeros(5)
    run_dynamics(x, v, 1, 0.01, 1e-9, 1e-12, 1e-13, 1e-6, 0.3, 0.3, 0.5, new_rng_state(1), st)
    assert st[1] == 0 and 0.0099 < st[4] <= 0.01 + 1e-9  # the certified lower bound
    assert x[0, 2] > old[0, 2]


@pytest.mark.parametrize("knot", ["3_1", "4_1"])
def test_run_ends_admissible_and_keeps_the_knot(knot):
    x = braid_chain(knot, 150)
    res = run_langevin(x, LangevinSettings(steps=40_000, dt=0.01), seed=2)
    p = res.pos
    bonds = np.linalg.norm(np.roll(p, -1, axis=0) - p, axis=1)
    assert np.max(np.abs(bonds - 1)) < 1e-12
    assert check_state(p, 0, D, D, False) <= 0.0
    assert res.epsilon == pytest.approx(unit_epsilon(p), rel=1e-10)
    assert res.guard_checks > 1 and res.lowest_guard_distance > 0
    ok, found = verify_knot(p, knot)
    assert ok, found


def test_hot_dynamics_keeps_the_knot_only_with_the_guard():
    """At T = 3 (30× the schedule's hottest) the WCA wall no longer holds the strands: without
    the guard the 3_1 loses its knot type, with it the type survives every step."""
    x0 = braid_chain("3_1", 60)
    kept = {}
    for guard in (True, False):
        x, v = x0.copy(), np.zeros_like(x0)
        st = np.zeros(5)
        run_dynamics(x, v, 20_000, 0.005, 0.01, 3.0, 2.999, 1000.0, CONTACT, 0.3, 0.5,
                     new_rng_state(5), st, guard)
        kept[guard] = verify_knot(x, "3_1")[0]
        if guard:
            assert st[1] > 0  # the guard had to refuse steps
    assert kept[True]
    assert not kept[False]


def test_same_seed_same_chain_other_seed_other_chain():
    x = braid_chain("3_1", 80)
    s = LangevinSettings(steps=5_000)
    a, b, c = (run_langevin(x, s, seed) for seed in (4, 4, 5))
    assert np.array_equal(a.pos, b.pos)
    assert not np.array_equal(a.pos, c.pos)


def test_projection_reaches_unit_bonds():
    x = braid_chain("4_1", 100)
    y = x * 1.002 + np.random.default_rng(0).normal(0, 1e-3, x.shape)
    p = project_bonds(y)
    assert np.max(np.abs(np.linalg.norm(np.roll(p, -1, 0) - p, axis=1) - 1)) < 1e-13
    assert np.max(np.linalg.norm(p - y, axis=1)) < 0.02


@pytest.mark.parametrize("bad, match", [
    ({"steps": 0}, "steps"), ({"dt": 0.05}, "dt"), ({"contact": 0.7}, "contact"),
    ({"t_end": 1.0}, "t_end"), ({"damp": float("nan")}, "damp"),
])
def test_bad_settings_are_refused(bad, match):
    with pytest.raises(InvalidParameter, match=match):
        run_langevin(braid_chain("3_1", 60), LangevinSettings(**bad))


def test_bad_chains_are_refused():
    x = braid_chain("3_1", 60)
    with pytest.raises(InvalidParameter, match="unit bonds"):
        run_langevin(x * 1.1)
    y = x.copy()
    y[10] = y[30] + 0.3 * (y[10] - y[30]) / np.linalg.norm(y[10] - y[30])
    with pytest.raises(InvalidParameter):
        run_langevin(y)


def test_replica_of_the_schedule_and_its_limits():
    x = braid_chain("3_1", 80)
    s = AnnealSettings(moves=5_000, schedule=Schedule(kind="langevin", t_end=1e-4))
    r = run_langevin_replica(x, s, seed=1, replica=3)
    assert r.replica == 3 and r.best_stage == "langevin"
    assert r.epsilon == pytest.approx(unit_epsilon(r.coords), rel=1e-10)
    assert r.langevin["refused_steps"] >= 0 and r.traces["moves"][-1] == 5_000
    sec = np.asarray(r.traces["seconds"])  # measured at the end of each chunk
    assert np.all(np.diff(sec) > 0) and 0 < sec[-1] <= r.wall_time
    tube = AnnealSettings(moves=5_000, schedule=Schedule(kind="langevin"),
                          params=MoveParams(exclusion="tube"))
    with pytest.raises(InvalidParameter, match="bead rule"):
        run_langevin_replica(x, tube, seed=1)
    with pytest.raises(InvalidParameter, match="hops"):
        Schedule(kind="langevin", hops=2, hop_fraction=0.2).validate()


def test_open_problems_refuse_the_schedule_before_any_worker():
    """An open knot (either ensemble) with the langevin schedule is refused when the problem
    is built, in the caller's process, not first inside a worker."""
    from stiffknots.problems.open_extension import OpenExtension
    from stiffknots.problems.open_force import OpenForce

    sch = Schedule(kind="langevin", t_end=1e-4)
    with pytest.raises(InvalidParameter, match="an open chain"):
        OpenExtension("3_1", excess_length=40, moves=5_000, schedule=sch)
    with pytest.raises(InvalidParameter, match="an open chain"):
        OpenForce("3_1", force=1.0, moves=5_000, schedule=sch)
    with pytest.raises(InvalidParameter, match="closed chains under the bead rule"):
        AnnealSettings(moves=5_000, schedule=sch,
                       params=MoveParams(energy="power", power=2)).validate()
