"""stiffknots identify / resample on good and bad files (exit 2 and one line for mistakes)."""

import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

RIDGERUNNER = Path(__file__).resolve().parents[1] / "data" / "curves" / "ridgerunner"


def run(*args):
    p = subprocess.run([sys.executable, "-m", "stiffknots.cli", *map(str, args)],
                       capture_output=True, text=True, timeout=600)
    return p.returncode, p.stdout, p.stderr


def test_identify_json_breaks_the_tie():
    rc, out, err = run("identify", RIDGERUNNER / "10.132.vect", "--json")
    assert rc == 0, err
    d = json.loads(out)
    assert d["knot"] == "10_132" and d["candidates"] == ["10_132"]
    assert d["homfly_candidates"] == "5_1|10_132" and d["chirality"] in ("+", "-")
    assert d["closure"].startswith("closed: the VECT vertex count is negative")
    assert d["beads"] == 117 and d["input_epsilon"] > 0
    assert d["bridge_number"] == 3 and d["braid_index"] == 4
    assert d["epsilon_bounds"]["lower"] == pytest.approx(2 * np.pi**2 * 9)


def test_identify_says_the_closure_assumed(tmp_path):
    from stiffknots.formats import load

    x = load(RIDGERUNNER / "4.1.vect").coords
    p = tmp_path / "fig8.csv"
    p.write_text("x,y,z\n" + "".join(f"{a!r},{b!r},{c!r}\n" for a, b, c in x.tolist()))
    rc, out, err = run("identify", p)
    assert rc == 0, err
    assert "assumed closed" in out and "4_1" in out
    rc, out, err = run("identify", p, "--open", "--json")
    assert rc == 0, err
    assert json.loads(out)["closure"] == "open: as requested" and not json.loads(out)["closed"]


@pytest.mark.parametrize("args,what", [
    (("identify", "nope.xyz"), "no such file"),
    (("identify", RIDGERUNNER / "6.2.1.vect"), "2 polylines"),
    (("identify", RIDGERUNNER / "README.md"), "suffix"),
    (("identify", RIDGERUNNER / "3.1.vect", "--bogus"), "No such option"),
    (("resample", RIDGERUNNER / "3.1.vect", "out.pdb"), "suffix"),
    (("resample", RIDGERUNNER / "8.18.vect", "out.xyz", "--beads", "20"), "--beads must be"),
    # the rule of relax and anneal: a tube thinner than a bond, w/L in (0, 1/8]
    (("resample", RIDGERUNNER / "3.1.vect", "out.xyz", "--w-over-L", "0.01"), "below 1/N"),
    (("resample", RIDGERUNNER / "3.1.vect", "out.xyz", "--w-over-L", "0"), "--w-over-L must"),
])
def test_bad_files_and_options_exit_2(tmp_path, args, what):
    rc, out, err = run(*[tmp_path / a if a in ("out.pdb", "out.xyz") else a for a in args])
    assert rc == 2
    assert what in err and "Traceback" not in err


def test_resample_command(tmp_path):
    dest = tmp_path / "r.json"
    rc, out, err = run("resample", RIDGERUNNER / "5.1.vect", dest, "--beads", "100",
                       "--w-over-L", "0.005", "--json")
    assert rc == 0, err
    d = json.loads(out)
    assert d["beads"] == 100 and d["w"] == pytest.approx(0.5)
    from stiffknots.formats import load

    c = load(dest)
    assert c.n_beads == 100 and np.allclose(c.bond_lengths(), 1.0, atol=1e-12)


def test_relax_refuses_a_results_folder_before_any_work(tmp_path):
    # --out holding another run's results is refused before the curve is identified and the
    # problem built (it took 4.7 s): with a knot name that the problem would refuse, the
    # folder's error comes first
    out = tmp_path / "out"
    out.mkdir()
    (out / "manifest.json").write_text("{}")
    rc, _, err = run("relax", RIDGERUNNER / "3.1.vect", "--knot", "4_1", "--out", out)
    assert rc == 2 and "holds the results of another run" in err, err
    assert (out / "manifest.json").read_text() == "{}"
