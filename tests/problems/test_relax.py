"""Relaxing a curve from a file (problems/relax.py, `stiffknots relax`, `anneal --from`)."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from stiffknots.chain import Chain, regular_polygon
from stiffknots.errors import UserInputError
from stiffknots.problems.relax import relax


def _write_plain(path, coords):
    """A plain 'x y z' file that does not repeat its first vertex (closure assumed)."""
    path.write_text("\n".join(f"{float(x)!r} {float(y)!r} {float(z)!r}" for x, y, z in coords)
                    + "\n")


@pytest.mark.parametrize("m", [1, 2])
def test_relax_keeps_type_and_reports_the_input_epsilon(tmp_path, m):
    # a circle (m = 1) and a doubly covered circle (a (2, 1) torus curve, m = 2): both are
    # unknots whose ε as given is known in closed form for unit bonds, N²(1 − cos 2πm/N),
    # up to the small tube amplitude of the doubly covered one
    n = 120
    c = regular_polygon(n, m)
    f = tmp_path / "curve.txt"
    _write_plain(f, c.coords * 1.7)  # another unit of length: ε is scale-free
    p = subprocess.run([sys.executable, "-m", "stiffknots.cli", "relax", str(f), "--beads",
                        str(n), "--moves", "100000", "--replicas", "1", "--json"],
                       capture_output=True, text=True, timeout=300)
    assert p.returncode == 0, p.stderr
    d = json.loads(p.stdout)
    assert d["knot"] == "0_1" and d["knot_verified"]
    assert "assumed closed" in d["closure"]
    assert d["input_epsilon"] == pytest.approx(c.epsilon(), rel=1e-12)
    if m == 1:
        assert d["input_epsilon"] == pytest.approx(n * n * (1 - np.cos(2 * np.pi / n)),
                                                   rel=1e-12)
    assert d["epsilon"] <= d["input_epsilon"] + 1e-6  # the relaxation lowers the energy


def test_relax_of_a_knot_and_anneal_from_it(tmp_path):
    from stiffknots.problems.closed import anneal

    res = anneal("4_1", moves=50_000, replicas=1, seed=0, rounds=1)
    chain = Chain(res.best.coords * 0.3 + 5.0, closed=True)  # rescaled, shifted
    out = relax(chain, moves=100_000, replicas=1)
    assert out.knot == "4_1" and out.best.knot_verified
    assert out.input_epsilon == pytest.approx(res.best.epsilon, rel=1e-9)
    again = anneal("4_1", moves=50_000, replicas=1, seed=1, rounds=1, initial=chain)
    assert again.best.start == "file" and again.best.knot_verified


def test_relax_refuses_what_it_cannot_do():
    with pytest.raises(UserInputError, match="closed"):
        relax(Chain(regular_polygon(40).coords, closed=False))
    c = regular_polygon(100)
    with pytest.raises(UserInputError, match="not 3_1"):
        relax(c, knot="3_1")
    with pytest.raises(UserInputError, match="thinner than the model"):
        # two strands 0.2 apart: thinner than a tube of w/L = 0.005 at N = 100 (w = 0.5)
        relax(regular_polygon(100, 2, amplitude=0.1), beads=100, exclusion="tube",
              w_over_L=0.005)
