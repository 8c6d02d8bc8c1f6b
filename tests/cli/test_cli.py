"""The command line on good and bad input (exit code 2 and one line on stderr for mistakes)."""

import json
import math
import subprocess
import sys

import pytest


def run(*args):
    p = subprocess.run([sys.executable, "-m", "stiffknots.cli", *args], capture_output=True,
                       text=True, timeout=600)
    return p.returncode, p.stdout, p.stderr


def test_knot_json():
    rc, out, err = run("knot", "4_1", "--json")
    assert rc == 0, err
    d = json.loads(out)
    assert d["name"] == "4_1" and d["crossing_number"] == 4
    assert d["bridge_number"] == 2 and d["braid_index"] == 3
    assert d["lower_bound"] == pytest.approx(8 * math.pi**2)
    assert d["upper_bound"] == pytest.approx(18 * math.pi**2)
    assert d["predicted_ground_state"] is None


def test_knot_torus_ground_state():
    rc, out, _ = run("knot", "T(2,3)", "--json")
    d = json.loads(out)
    assert d["name"] == "3_1"
    assert d["predicted_ground_state"]["shape"] == "CB"
    assert d["predicted_ground_state"]["epsilon"] == pytest.approx(8 * math.pi**2)


def test_elastica_json(tmp_path):
    rc, out, err = run("elastica", "--json", "--out", str(tmp_path))
    assert rc == 0, err
    d = json.loads(out)
    for k in ("alpha_loop", "eps_loop", "alpha_8", "eps_8", "eps_80", "alpha"):
        assert k in d
    assert d["eps_80"] == pytest.approx((math.sqrt(d["eps_8"]) + math.sqrt(2) * math.pi) ** 2)
    assert max(d["cross_check"].values()) < 1e-9
    assert max(d["cross_check_shooting"].values()) < 1e-12  # the ODE shot, a third method
    assert (tmp_path / "elastica.png").stat().st_size > 10_000


def test_families_json():
    rc, out, _ = run("families", "--max-crossings", "10", "--json")
    d = json.loads(out)
    assert d["total"] == 249
    assert d["n_equals_i"] == len(d["knots"]) and "3_1" in d["knots"]
    assert 0.15 < d["fraction"] < 0.25  # paper: ≈ 20 % of prime knots with n_c < 11


@pytest.mark.parametrize(
    "args",
    [("knot", "4_9"), ("knot", "T(2,4)"), ("families", "--max-crossings", "20"),
     ("anneal", "4_1", "--beads", "4"), ("anneal", "4_1", "--exclusion", "soft"),
     ("anneal", "nonsense_knot"), ("anneal", "8_19", "--beads", "20"),
     # found after the worker pool has started: the pool stops cleanly before the exit
     ("anneal", "3_1", "--start", "cage"),
     ("open", "3_1", "--excess-length", "40,,80"), ("open", "3_1", "--excess-length", "40.5")],
)
def test_user_mistakes_exit_2_one_line(args):
    rc, out, err = run(*args)
    assert rc == 2
    assert "Traceback" not in err
    assert err.strip().startswith("error:") and len(err.strip().splitlines()) == 1


def test_anneal_json_small(tmp_path):
    rc, out, err = run("anneal", "3_1", "--moves", "300000", "--replicas", "2", "--rounds", "1",
                       "--json",
                       "--out", str(tmp_path))
    assert rc == 0, err
    d = json.loads(out)
    assert d["knot"] == "3_1" and d["knot_verified"]
    assert len(d["replicas"]) == 2
    assert d["epsilon"] == min(r["epsilon"] for r in d["replicas"])
    assert d["epsilon"] >= d["bounds"]["lower"] * 0.99
    for f in ("result.json", "best.xyz", "best.json", "best.png"):
        assert (tmp_path / f).exists()
    # the best chain names its shape (issue: single runs name their shape)
    assert d["shape"] in ("CB", "4C", "80", "other")
    assert (d["multiplicity"] is not None) == (d["shape"] == "CB")
    # … and its contact structure (§V B), read from the best chain at the run's d
    from stiffknots.analysis import analyse_structure
    from stiffknots.formats import load

    best = load(tmp_path / "best.json").coords
    assert d["structure"] == analyse_structure(best, d=2 ** -0.5).name


@pytest.mark.slow  # ≈ 22 s: two annealings; plan_anneal's coarse stage is tested fast
def test_anneal_coarse_to_fine(tmp_path):
    """--coarse: a first annealing at fewer beads starts the run; the result says so (its N,
    ε and width) and the chain is the requested N, verified; bad uses are one-line errors."""
    rc, out, err = run("anneal", "3_1", "--beads", "60", "--coarse", "30", "--moves",
                       "100000", "--replicas", "1", "--rounds", "1", "--json")
    assert rc == 0, err
    d = json.loads(out)
    c = d["coarse"]
    assert c["beads"] == 30 and c["replicas"] == 2 and "N = 30" in c["width"]["text"]
    assert c["epsilon"] >= d["bounds"]["lower"] * 0.99
    # the chain taken is the lowest that resamples with the rule held (here the lowest)
    assert c["epsilon"] >= c["lowest_epsilon"] and isinstance(c["replica"], int)
    assert d["beads"] == 60 and d["knot_verified"] and "N = 60" in d["width"]["text"]
    for args, msg in [(("--coarse", "60"), "--coarse must be fewer beads than --beads (60)"),
                      (("--coarse", "30", "--from", "x.xyz"), "--coarse and --from both"),
                      (("--coarse", "2"), "--coarse must be an integer in [8")]:
        rc, out, err = run("anneal", "3_1", "--beads", "60", *args)
        assert rc == 2 and msg in err and "Traceback" not in err, err


@pytest.mark.slow  # ≈ 45–80 s; `make run` runs the same study at the small budget
def test_paper_tiny_writes_report(tmp_path):
    rc, out, err = run("paper", "--budget", "tiny", "--out", str(tmp_path), "--json")
    assert rc == 0, err
    d = json.loads(out)
    assert set(d["knots"]) == {"3_1", "4_1", "5_2", "6_2", "6_3"}
    for k in d["knots"].values():
        for model in ("bead", "tube"):
            g = k[model]["ground"]
            assert g["shape"] in ("CB", "4C", "80", "other")
            assert g["epsilon"] >= k["lower_bound"] * 0.99  # ε* ≥ 2π²n² (§IV)
            assert k[model]["knot_verified"]
            assert g["epsilon"] == min(k[model]["replica_epsilons"])
            assert (tmp_path / g["picture"]).exists()
            if model == "tube":  # the tube model keeps every segment pair ≥ w apart
                assert g["min_segment_distance"] >= 1 / 2**0.5 - 1e-9
        assert k["ground"] == k["bead"]["ground"]
    for f in ("report.md", "report.html", "summary.json", "eps_vs_n2.png", "elastica.png"):
        assert (tmp_path / f).exists()
    html = (tmp_path / "report.html").read_text()
    assert "<table" in html and "4_1" in html
    md = (tmp_path / "report.md").read_text()
    # the hierarchy is a thin-limit statement (the cage at w = 0), in words, not Python values
    assert "thin limit w/L → 0" in md and "4C 126.47" in md and "holds: yes" in md
    assert ": True" not in md and ": False" not in md


def test_unknown_option_is_a_usage_error_not_a_traceback():
    # typer vendors click; the usage-error path must not import a module that is absent
    rc, out, err = run("anneal", "4_1", "--bogus")
    assert rc == 2
    assert "Traceback" not in err and "No such option" in err


def test_anneal_command_defaults_are_the_library_defaults():
    # the command line spells its defaults out (it imports no engine at start-up): they must
    # be the ones `stiffknots.anneal` uses, which the benchmarks measured
    import inspect

    from stiffknots.cli.anneal import anneal as command
    from stiffknots.engine.schedules import Schedule
    from stiffknots.problems.closed import DEFAULT_ROUNDS, LANGEVIN_ROUNDS
    from stiffknots.problems.closed_plan import plan_anneal

    sig = inspect.signature(command)
    # the command's default (auto) is the library's langevin schedule and rounds for the bead
    # rule, and the library's default schedule and rounds with an option of the Monte Carlo
    assert sig.parameters["schedule"].default == "auto"
    assert sig.parameters["rounds"].default is None
    p = plan_anneal("3_1")
    assert (p.schedule.kind, p.rounds) == ("langevin", LANGEVIN_ROUNDS)
    p = plan_anneal("3_1", checkpoint_dir="ckpt")
    assert (p.schedule.kind, p.rounds) == (Schedule().kind, DEFAULT_ROUNDS)
    for name in ("beads", "moves", "seed", "exclusion", "w", "start", "polish"):
        assert sig.parameters[name].default == inspect.signature(plan_anneal).parameters[
            "w_over_L" if name == "w_over_l" else name].default, name
    assert sig.parameters["replicas"].default == 2


def test_the_command_line_starts_without_dask():
    """Every command imports the command line; Dask (≈ 1 s of imports) only the atlas's run."""
    code = ("import sys, stiffknots.cli.main; "
            "print(sorted(m for m in ('distributed', 'dask', 'topoly') if m in sys.modules))")
    p = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert p.returncode == 0, p.stderr
    assert p.stdout.strip() == "[]"


def test_every_command_takes_json():
    # the README: "Every command takes --json"; version and warmup refused it
    from stiffknots import __version__

    rc, out, err = run("version", "--json")
    assert rc == 0 and json.loads(out) == {"version": __version__}
    # warmup --json: tests/studies/test_warmup.py


def test_knot_of_13_crossings_with_ranges_of_n_and_i():
    # KnotInfo gives 13a_69 only 3 ≤ n ≤ 4 and 3 ≤ i ≤ 6: the bounds hold at the ends of the
    # ranges (n ≥ 3 below; n ≤ 4, i ≤ 6 above), and the text shows no Python value
    from stiffknots.theory.bounds import closed_bounds

    rc, out, err = run("knot", "13a_69", "--json")
    d = json.loads(out)
    assert d["bridge_number"] is None and d["bridge_number_range"] == [3, 4]
    assert d["braid_index_range"] == [3, 6]
    assert d["lower_bound"] == pytest.approx(18 * math.pi**2)
    assert d["upper_bound"] == pytest.approx(closed_bounds(4, 6).upper)
    assert d["restricted_curvature_bounds"]["lower"] == pytest.approx(6 * math.pi)
    rc, out, err = run("knot", "13a_69")
    assert rc == 0 and "between 3 and 4" in out
    assert not any(w in out for w in ("None", "True", "[-1"))


def test_help_texts_are_reflowed_paragraphs():
    from stiffknots.cli.app import reflow

    assert reflow("One line\n    and its end.\n\n    A second\n    paragraph.") == (
        "One line and its end.\n\nA second paragraph.")
    rc, out, err = run("--help")
    assert rc == 0
    # thin-limit's docstring was wrapped at 96 columns: each of its lines ended mid-sentence
    assert "sorted into a census, every state followed down to w/L" in " ".join(out.split())
    assert "state's own structure graph solved at w = 0" in " ".join(out.split())


@pytest.mark.slow
def test_anneal_unconverged_bead_rule_points_to_the_tube_model():
    """An adaptive bead-rule run that ends without a verdict says why bead-rule searches rarely
    meet and names the tube model and the other engine; a tube run, or a fixed budget
    (--rounds 1), does not."""
    from stiffknots.cli.anneal import BEAD_HINT

    first = BEAD_HINT.split(":")[0]
    base = ("anneal", "6_3", "--moves", "20000", "--replicas", "1")
    for engine, other in (((), "--schedule geometric"),  # the default: the dynamics
                          (("--schedule", "geometric"), "--schedule langevin")):
        rc, out, err = run(*base, *engine, "--rounds", "2", "--no-polish")
        assert rc == 0, err
        flat = " ".join(out.split())
        assert "NOT converged" in flat and " ".join(first.split()) in flat
        assert "--exclusion tube" in flat and other in flat
    for extra in (("--rounds", "1"), ("--rounds", "2", "--exclusion", "tube")):
        rc, out, err = run(*base, *extra, "--no-polish")
        assert rc == 0, err
        assert " ".join(first.split()) not in " ".join(out.split())


@pytest.mark.slow  # ≈ 19 s
def test_anneal_schedule_auto_is_the_dynamics_unless_a_monte_carlo_option():
    """`anneal`'s default schedule (auto) runs the Langevin dynamics for the bead rule, with
    64 rounds at most; an option of the Monte Carlo (tube model, its moves' parameters …) runs
    the paper's annealing with 8; the result says which and why."""
    from stiffknots.problems.closed_plan import plan_anneal

    def kind_rounds(**kw):
        p = plan_anneal("3_1", **kw)
        return p.schedule.kind, p.rounds

    assert kind_rounds() == ("langevin", 64)
    assert kind_rounds(exclusion="tube") == ("geometric", 8)
    assert kind_rounds(rounds=3) == ("langevin", 3)
    assert kind_rounds(schedule="geometric") == ("geometric", 8)
    assert kind_rounds(schedule="langevin") == ("langevin", 64)
    for extra, kind, why in (((), "langevin", "the bead rule's default"),
                             (("--exclusion", "tube"), "geometric", "with --exclusion tube"),
                             (("--delta", "0.02"), "geometric", "with --delta")):
        rc, out, err = run("anneal", "3_1", "--moves", "4000", "--rounds", "1",
                           "--replicas", "1", "--no-polish", "--json", *extra)
        assert rc == 0, err
        d = json.loads(out)
        assert d["settings"]["schedule"]["kind"] == d["schedule"] == kind
        assert why in d["schedule_choice"] and d["max_rounds"] == 1


@pytest.mark.slow  # ≈ 20 s; the langevin schedule is anneal's default, run by the fast tests
def test_anneal_with_the_langevin_schedule():
    """`anneal --schedule langevin`: replicas of guarded Langevin dynamics, polished and
    verified, the table's unit in dynamics steps and no Monte Carlo acceptance."""
    rc, out, err = run("anneal", "3_1", "--schedule", "langevin", "--moves", "4000",
                       "--rounds", "1", "--json")
    assert rc == 0, err
    d = json.loads(out)
    assert d["settings"]["schedule"]["kind"] == "langevin"
    assert d["settings"]["schedule"]["t_end"] == pytest.approx(1e-4)
    assert d["settings"]["moves"] == 4000
    for r in d["replicas"]:
        assert r["knot_verified"] and r["langevin"]["refused_steps"] >= 0
        assert r["polish"]["relative_kkt"] < 1e-6
    rc, out, err = run("anneal", "3_1", "--schedule", "langevin", "--moves", "4000",
                       "--rounds", "1")
    assert rc == 0, err
    flat = " ".join(out.split())
    assert "4,000 dynamics steps/replica" in flat and "–" in flat
