"""`--w-over-L` of anneal and open, and `stiffknots thin-limit` (§V A): bad input is one line
and exit 2; the slow end-to-end run checks 3_1's thin limit against 8π² (eq. (30))."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import pytest

EPS_CB2 = 8 * math.pi**2  # 78.9568352...


def run(*args, timeout=600):
    p = subprocess.run([sys.executable, "-m", "stiffknots.cli", *map(str, args)],
                       capture_output=True, text=True, timeout=timeout)
    return p.returncode, p.stdout, p.stderr


def one_line(err: str) -> str:
    lines = [ln for ln in err.splitlines() if ln.strip()]
    assert len(lines) == 1, err
    return lines[0]


@pytest.mark.parametrize("args, words", [
    (("anneal", "3_1", "--w-over-L", "0"), "--w-over-L must be a finite number in (0, 0.125]"),
    (("anneal", "3_1", "--w-over-L", "-0.1"), "--w-over-L must be"),
    (("anneal", "3_1", "--w-over-L", "nan"), "--w-over-L must be"),
    (("anneal", "3_1", "--w-over-L", "0.01"), "the N rule needs N = 115 beads"),
    (("anneal", "3_1", "--w-over-L", "0.01", "--beads", "200"), "thinner than a bond at N = 200"),
    (("anneal", "3_1", "--w-over-L", "0.002", "--w", "0.3"), "give one"),
    (("open", "3_1", "--w-over-L", "0.05"), "thinner than a bond"),
    (("open", "3_1", "--w-over-L", "0.3"), "--w-over-L must be"),
    (("open", "3_1", "--w-over-L", "0.002", "--w", "0.1"), "give one"),
    (("thin-limit", "3_1", "--budget", "huge"), "--budget must be one of small, default"),
    (("thin-limit", "3_9"), "unknown knot"),
    (("thin-limit", "3_1", "--seed", "-1"), "--seed must be"),
    (("thin-limit", "3_1", "--states", "0"), "--states must be"),
])
def test_bad_input_one_line_exit_2(args, words):
    rc, out, err = run(*args, "--json", timeout=120)
    assert rc == 2, err
    assert words in one_line(err)
    assert out == ""


def test_anneal_w_over_l_sets_the_tube_and_the_n_rule():
    rc, out, err = run("anneal", "3_1", "--w-over-L", "0.002", "--moves", "20000",
                       "--rounds", "1", "--replicas", "1", "--no-polish", "--json", timeout=300)
    assert rc == 0, err
    d = json.loads(out)
    # N rule: ⌈(ε/(6·1e-3))^½⌉ with ε = 8π², the trefoil's upper bound
    assert d["beads"] == 115
    assert d["width"]["exclusion"] == "tube"
    assert d["width"]["w"] == pytest.approx(0.23)
    assert d["width"]["w_over_L"] == pytest.approx(0.002)


@pytest.mark.slow
def test_thin_limit_trefoil_small(tmp_path):
    """The trefoil's one state, CB(2), followed to w → 0: within 0.05 % of 8π² and within 3 of
    its own error bars, ε decreasing as w/L decreases; the routes agree."""
    rc, out, err = run("thin-limit", "3_1", "--budget", "small", "--out", tmp_path / "o",
                       "--json", timeout=1800)
    assert rc == 0, err
    d = json.loads(out)
    assert d["knot"] == "3_1" and d["shape"] == "CB(i=2)" and d["ground"] == 0
    assert abs(d["epsilon_thin"] - EPS_CB2) < 5e-4 * EPS_CB2
    assert abs(d["epsilon_thin"] - EPS_CB2) < 3 * d["error"]
    g = d["states"][d["ground"]]
    assert g["epsilon_thin"] == d["epsilon_thin"] and g["event"] is None
    eps = [p["epsilon"] for p in g["points"]]
    wl = [p["w_over_L"] for p in g["points"]]
    assert wl == sorted(wl, reverse=True) == [0.004, 0.002, 0.001, 0.0005]
    assert all(a > b for a, b in zip(eps, eps[1:], strict=False))
    assert g["structure_name"] == "CB(2)" and g["agree"] is True
    assert g["structure_epsilon"] == pytest.approx(EPS_CB2, rel=1e-9)
    for p in g["points"]:
        assert {"w_over_L", "beads", "epsilon", "shape", "structure", "step"} <= set(p)
    assert d["census"]["width"]["w_over_L"] == pytest.approx(0.0047140452)
    assert d["version"] and d["seed"] == 0
    assert (tmp_path / "o" / "branches.png").stat().st_size > 1000
    assert (tmp_path / "o" / "manifest.json").exists()
    assert (tmp_path / "o" / "state_0_w_over_L_0.0005.xyz").exists()


@pytest.mark.slow
def test_thin_limit_figure_eight_names_its_thin_limit_ground_state():
    """4_1 has two states at the atlas width (`other` 128.57, the cage 129.31); the cage's own
    limit agrees with the structure route ε*_4C; the run names the lowest limit, its margin
    and where the branches cross."""
    rc, out, err = run("thin-limit", "4_1", "--budget", "small", "--json", timeout=1800)
    assert rc == 0, err
    d = json.loads(out)
    names = [s["shape"] for s in d["states"]]
    assert "4C" in names and len(names) >= 2
    cage = d["states"][names.index("4C")]
    assert cage["structure_name"] == "2 point-braids" and cage["agree"] is True
    assert abs(cage["epsilon_thin"] - 126.47247) < max(3 * cage["error"], 0.005 * 126.5)
    g = d["states"][d["ground"]]
    assert d["epsilon_thin"] == g["epsilon_thin"] == min(
        s["epsilon_thin"] for s in d["states"] if s["epsilon_thin"] is not None)
    assert d["margin"]["gap"] > 0 and d["margin"]["next"] != d["ground"]
    if d["ground"] != 0:
        assert d["crossing"] is not None


def test_the_table_says_why_routes_differ_or_are_not_compared(capsys):
    """The rows' reasons: a disagreement is 'routes differ — …', a branch too uncertain to
    compare says 'not compared' (no 'differ')."""
    from stiffknots.cli.thin_limit import _table
    from stiffknots.studies.thin_states import route_difference, too_wide

    def state(shape, eps, eps_t, err, se, agree, why):
        return {"shape": shape, "epsilon": eps, "epsilon_thin": eps_t, "error": err,
                "structure_epsilon": se, "agree": agree, "event": None, "events": [],
                "points": [{"beads": 157}], "structure": "2 point-braids",
                "structure_route": {"method": "the graph of the chain", "note": None},
                "difference": why}

    res = {"knot": "8_3", "census": {"width": {"text": "tube w = 1/√2"}, "replicas": 6,
                                     "converged": True, "convergence": "3 searches"},
           "budget": "default", "seed": 0, "parameters": {"widths": [0.004, 0.00025]},
           "ground": 0, "margin": None, "crossing": None,
           "states": [state("other", 197.4, 114.53, 15.23, 126.4725, None,
                            too_wide(114.53, 15.23)),
                      state("4C", 199.0, 128.42, 0.13, 126.4725, False,
                            route_difference(128.42, 126.4725, "2 point-braids", False))]}
    _table(res)
    out = capsys.readouterr().out
    assert "state 0: not compared: the branch's extrapolation 114.53 ± 15" in out
    assert "state 1: routes differ — the branch's extrapolation lies 1.54 % above" in out
