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
    """The trefoil's thin limit within 0.05 % of 8π² and within 3 of its own error bars;
    ε*_w decreasing as w/L decreases."""
    rc, out, err = run("thin-limit", "3_1", "--budget", "small", "--out", tmp_path / "o",
                       "--json", timeout=1800)
    assert rc == 0, err
    d = json.loads(out)
    assert d["knot"] == "3_1" and d["shape"] == "CB2"
    assert abs(d["epsilon_thin"] - EPS_CB2) < 5e-4 * EPS_CB2
    assert abs(d["epsilon_thin"] - EPS_CB2) < 3 * d["error"]
    eps = [p["epsilon"] for p in d["points"]]
    wl = [p["w_over_L"] for p in d["points"]]
    assert wl == sorted(wl, reverse=True)
    assert all(a > b for a, b in zip(eps, eps[1:], strict=False))
    assert d["series_decreasing"]
    assert d["structure"]["name"] == "CB(2)"
    assert d["structure"]["epsilon"] == pytest.approx(EPS_CB2, rel=1e-9)
    for p in d["points"]:
        assert {"w_over_L", "beads", "epsilon", "shape", "converged"} <= set(p)
    assert {"model", "p"} <= set(d["fit"])
    assert d["version"] and d["seed"] == 0 and d["parameters"]["beads"] >= 8
    assert (tmp_path / "o" / "thin_limit.png").stat().st_size > 1000
    assert (tmp_path / "o" / "manifest.json").exists()


@pytest.mark.slow
def test_thin_limit_figure_eight_points_say_how_their_shape_was_read():
    """4_1's cage reads 'other' at d = w in the thinnest tubes and 4C at d = 0.5: a point's
    shape and the words of its verdict must not disagree silently."""
    rc, out, err = run("thin-limit", "4_1", "--json", timeout=1800)
    assert rc == 0, err
    for p in json.loads(out)["points"]:
        assert p["run_shape"] in p["convergence"]
        if p["run_shape"] != p["shape"]:
            assert f"read at d = 0.5 it is {p['shape']}" in p["convergence"]
