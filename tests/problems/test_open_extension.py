"""Open chains (paper §VIII) and the curvature limit (§IX.D) in the kernel."""

from __future__ import annotations

import json

import numpy as np
import pytest

from stiffknots.analysis.open_shape import open_shape
from stiffknots.engine.state import ChainState, MoveParams, check_open_clamping
from stiffknots.knots.catalogue import get_knot
from stiffknots.knots.identify import close_open_chain_along_z, verify_knot
from stiffknots.knots.open_embedding import embed_open
from stiffknots.problems.open_extension import excess_length_for_force
from stiffknots.problems.tightest import length_over_R, radius_of_turn


def _open(name, nk, seed=1):
    k = get_knot(name)
    return embed_open(k.braid_word, k.braid_strands, nk, expected=name, seed=seed)


@pytest.fixture(scope="module")
def open52():
    return _open("5_2", 40)


def test_open_embedding_is_clamped_and_knotted():
    x = _open("3_1", 30)
    zlo, zhi = check_open_clamping(x)
    assert zlo == x[0, 2] and zhi == x[-1, 2]
    assert np.max(np.abs(np.linalg.norm(np.diff(x, axis=0), axis=1) - 1)) < 1e-10
    # excess length of the construction: L_e = N_k (arms of one bond)
    assert abs((len(x) - 1) - (x[-1, 2] - x[0, 2]) - 30) < 1e-9
    assert verify_knot(close_open_chain_along_z(x), "3_1")[0]


@pytest.mark.parametrize("temperature", [0.5, 1e-3])
@pytest.mark.parametrize("exclusion", ["bead", "tube"])
def test_open_moves_keep_ends_bonds_energy_and_knot(open52, temperature, exclusion):
    p = MoveParams(exclusion=exclusion, m_max=30)
    st = ChainState(open52, p, seed=7, closed=False)
    ends = st.pos[[0, 1, -2, -1]].copy()
    le0 = st.excess_length
    for _ in range(10):
        st.run(100_000, temperature)
        assert np.array_equal(st.pos[[0, 1, -2, -1]], ends)  # clamped ends never move
        check_open_clamping(st.pos)  # free beads stay strictly inside the slab
        assert st.violation() <= 1e-12
        ok, found = verify_knot(close_open_chain_along_z(st.pos), "5_2")
        assert ok, found
    bonds = np.linalg.norm(np.diff(st.pos, axis=0), axis=1)
    assert np.max(np.abs(bonds - 1)) < 1e-10
    assert abs(st.energy - st.recomputed_energy()) < 1e-9 * max(1, st.energy)
    assert st.excess_length == pytest.approx(le0, abs=1e-12)
    acc = st.acceptance()
    assert acc["single"]["accepted"] > 0 and acc["multi"]["accepted"] > 0


def test_open_energy_counts_interior_joints_only():
    # straight open chain along z: zero energy; one 90° kink adds exactly 1
    x = np.zeros((12, 3))
    x[:, 2] = np.arange(12)
    st = ChainState(x, MoveParams(), closed=False)
    assert st.energy == 0.0
    assert st.excess_length == 0.0


def test_open_rejects_unclamped_chain():
    x = _open("3_1", 30)
    y = x + np.array([0.1, 0.0, 0.0])  # bonds intact, ends off the axis
    with pytest.raises(ValueError, match="z axis"):
        ChainState(y, MoveParams(), closed=False)


def test_power_energy_bookkeeping_and_curvature_ratchet():
    from stiffknots.knots.embedding import embed_braid

    k = get_knot("4_1")
    x = embed_braid(k.braid_word, k.braid_strands, n_beads=100)
    p = MoveParams(energy="power", power=8, energy_scale=1 - np.cos(4 * np.pi / 100))
    st = ChainState(x, p, seed=3)
    cap = float(st.turning_angles().max())
    st.set_max_turn(cap)
    for temp in (1.0, 0.1, 0.0):
        st.run(200_000, temp)
        th = float(st.turning_angles().max())
        assert th <= cap + 1e-12  # the limit is never exceeded
        cap = th
        st.set_max_turn(cap)
        rec = st.recomputed_energy()
        assert abs(st.energy - rec) <= 1e-9 * max(1.0, rec)
    assert verify_knot(st.pos, "4_1")[0]


def test_curvature_limit_only_lets_violating_joints_straighten():
    from stiffknots.knots.embedding import embed_braid

    k = get_knot("3_1")
    x = embed_braid(k.braid_word, k.braid_strands, n_beads=60)
    st = ChainState(x, MoveParams(), seed=5)
    th0 = st.turning_angles()
    limit = float(np.quantile(th0, 0.5))  # half of the joints start beyond the limit
    st.set_max_turn(limit)
    st.run(300_000, 0.05)
    th1 = st.turning_angles()
    # a joint beyond the limit is the same joint or straighter; joints within stay within
    # (joints move, so compare the largest angles)
    assert th1.max() <= th0.max() + 1e-12
    assert np.sum(th1 > limit + 1e-12) <= np.sum(th0 > limit + 1e-12)


def test_length_over_R_of_covered_polygons():
    from stiffknots.chain import regular_polygon

    for n, m in ((150, 1), (150, 2), (300, 3)):
        c = regular_polygon(n, m, amplitude=0.01 if m > 1 else None)
        th = float(np.max(c.turning_angles()))
        assert th == pytest.approx(2 * np.pi * m / n, rel=5e-3)
        # the m-covered circle: L†/R → 2π m as N grows (discrete value 2N sin(πm/N))
        assert length_over_R(th, n) == pytest.approx(2 * n * np.sin(th / 2), rel=1e-12)
        assert length_over_R(th, n) == pytest.approx(2 * np.pi * m, rel=5e-3)
    assert radius_of_turn(np.pi / 3) == pytest.approx(1.0)  # equilateral: R = chord


def _tangent_loop(radius=12.0, n_loop=80):
    """A planar circle in the xz plane touching the z axis, with straight tails along z."""
    t = np.linspace(0, 2 * np.pi, n_loop, endpoint=False)
    circle = np.column_stack([radius - radius * np.cos(t), np.zeros_like(t),
                              50 + radius * np.sin(t)])
    tails = np.column_stack([np.zeros(40), np.zeros(40), np.linspace(0, 100, 40)])
    return np.vstack([tails[:20], circle, tails[20:]])


def test_open_shape_recognises_a_tangent_loop():
    s = open_shape(_tangent_loop())
    assert s["label"] == "loop", s
    assert s["features"]["axis_distance_over_radius"] == pytest.approx(1.0, abs=0.05)
    line = np.column_stack([np.zeros(50), np.zeros(50), np.arange(50.0)])
    assert open_shape(line)["label"] == "other"
    # a loop perpendicular to the line (the axis pierces it) is not the tangent loop
    x = _tangent_loop()
    rot = x.copy()
    rot[:, 1], rot[:, 2] = x[:, 2] - 50, x[:, 1] + 50
    rot[:20] = x[:20]
    assert open_shape(rot)["label"] == "other"


def test_excess_length_for_force_inverts_the_tension_law():
    le = excess_length_for_force(2 * np.pi**2, 0.01)
    assert 2 * np.pi**2 / le**2 == pytest.approx(0.01)
    with pytest.raises(ValueError):
        excess_length_for_force(20.0, -1.0)


@pytest.mark.slow  # 48 s (compiles the open and tightest kernels); tests/cli/test_probe.py
def test_cli_open_and_tightest_json(capsys):  # runs both commands in the default suite
    from stiffknots.cli import app

    app(["open", "3_1", "--excess-length", "30", "--moves", "200000", "--replicas", "1",
         "--json"], standalone_mode=False)
    d = json.loads(capsys.readouterr().out)
    for key in ("knot", "tension", "excess_length", "eps_e", "shape"):
        assert key in d
    assert d["knot"] == "3_1" and d["excess_length"] == 30
    assert d["tension"] == pytest.approx(d["eps_e"] / 30**2)
    # a scan: every point says its own width (N grows with L_e at fixed extension), the top
    # level says the width of the point whose numbers it repeats (the last), and μ = −dE/dL_e
    # is reported next to E/L_e (§VIII)
    app(["open", "3_1", "--excess-length", "20,40", "--moves", "100000", "--replicas", "1",
         "--exclusion", "tube", "--w", "0.1", "--json"], standalone_mode=False)
    d = json.loads(capsys.readouterr().out)
    n = [p["beads"] for p in d["points"]]
    assert n[0] < n[1] and [p["width"]["beads"] for p in d["points"]] == n
    assert d["beads"] == n[-1] and d["width"] == d["points"][-1]["width"]
    # an open chain of N beads is N − 1 bonds long
    assert d["width"]["w_over_L"] == pytest.approx(0.1 / (n[-1] - 1))
    assert d["eps_e"] == d["points"][-1]["eps_e"]
    (fd,) = d["finite_differences"]
    e = [p["energy"] for p in d["points"]]
    assert fd["mu_finite_difference"] == pytest.approx(-(e[1] - e[0]) / 20)
    app(["tightest", "3_1", "--beads", "60", "--moves", "200000", "--replicas", "1", "--json"],
        standalone_mode=False)
    d = json.loads(capsys.readouterr().out)
    for key in ("knot", "length_over_R", "lower_bound", "upper_bound"):
        assert key in d
    assert d["lower_bound"] == pytest.approx(4 * np.pi)
    assert d["length_over_R"] >= d["lower_bound"] * 0.99


def _zigzag_open_chain(n=11):
    """Open chain: ends clamped on z, free beads on a planar zigzag (all bonds 1)."""
    h = np.sqrt(0.75)
    x = [(0.0, 0.0, 0.0), (0.0, 0.0, 1.0)]
    for k in range(2, n - 1):
        x.append((0.5 if k % 2 == 0 else 0.0, 0.0, 1.0 + (k - 1) * h))
    top = x[-1][2]
    assert x[-1][0] == 0.0
    x.append((0.0, 0.0, top + 1.0))
    return np.array(x)


@pytest.mark.parametrize("seed", range(5))
def test_open_bead_rule_holds_for_the_last_bead(seed):
    # bead N−1 starts no segment of an open chain, so the cell scan over segments must still
    # check it as a bead: hot moves of a short chain press free beads against the top end
    from stiffknots.engine.kernel import check_state

    x = _zigzag_open_chain()
    st = ChainState(x, MoveParams(exclusion="bead", m_max=6), seed=seed, closed=False)
    for _ in range(50):
        st.run(2_000, 3.0)
        assert check_state(st.pos, 0, st.params.d, 0.0, True) <= 1e-12
