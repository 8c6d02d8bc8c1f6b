"""The atlas study without a cluster: family statistics from synthetic store rows (a small
fixed set whose answer is known), the --json entries, the atlas input, the catalogue's family
coverage against the paper (§VII: all knots with n_c < 7, 75 % of those with n_c < 9)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stiffknots.analysis.synthetic import four_cage, torus_braid
from stiffknots.chain import regular_polygon
from stiffknots.knots.catalogue import catalogue, get_knot
from stiffknots.knots.families import (
    EIGHTY_FAMILY,
    coverage,
    families_of,
    predicted_shape,
)
from stiffknots.knots.starts import default_start_names
from stiffknots.store import Store
from stiffknots.studies.atlas import (
    atlas_input,
    eps_n2_points,
    families_table,
    family_study,
    json_entry,
    knot_records,
    structure_groups,
)
from stiffknots.sweeps import BUDGETS, parse_models, sweep_settings

D = 1 / math.sqrt(2)

# knot → (ε, shape, multiplicity) of its bead replicas: a fixed set with a known answer
ROWS = {
    "3_1": [(79.1, "CB", 2), (79.15, "CB", 2)],  # n = i: CB(2) as predicted, converged
    "4_1": [(128.4, "4C", None), (128.45, "4C", None), (147.0, "80", None)],  # 4C, converged
    "5_2": [(147.3, "80", None)],  # a cage knot whose ground is the 80: a mismatch
    "6_2": [(153.0, "80", None), (160.0, "other", None)],  # 80 as predicted, not converged
    "7_4": [(190.0, "other", None)],  # in no family
    "8_19": [(181.0, "CB", 3), (181.1, "CB", 3)],  # n = i = 3: CB(3)
}


def chain_of(shape, mult, r):
    """A unit-bond chain of the shape (the contacts are what the structure names read): the
    circular braid CB(i) and the 4-fold cage synthetic, every other shape a plain circle (no
    contacts); shifted by the replica index."""
    if shape == "CB":
        x = torus_braid(mult, 150, separation=0.9)
    elif shape == "4C":
        x = four_cage()
    else:
        x = regular_polygon(150).coords
    return x + r


STRUCTURE = {"CB2": "circular line-braid (m = 2)", "CB3": "circular line-braid (m = 3)",
             "4C": "2 point-braids", "other": "no contacts", "80": "no contacts"}


@pytest.fixture()
def store(tmp_path):
    bead, tube = parse_models("bead,tube")
    st = Store(tmp_path / "s.db")
    for knot, reps in ROWS.items():
        starts = default_start_names(knot, 150)  # round-robin, as a sweep assigns them
        for r, (eps, shape, mult) in enumerate(reps):
            st.put({"knot": knot, "exclusion": "bead", "beads": 150, "thickness": D,
                    "seed": 0, "replica": r, "settings": sweep_settings(bead, BUDGETS["small"]),
                    "epsilon": eps, "min_segment_distance": 0.6, "wall_seconds": 1.0,
                    "shape": shape, "multiplicity": mult, "start": starts[r % len(starts)]},
                   chain_of(shape, mult, r))
    # a replica of another budget: another ensemble, never mixed in
    st.put({"knot": "5_2", "exclusion": "bead", "beads": 150, "thickness": D, "seed": 0,
            "replica": 0, "settings": sweep_settings(bead, BUDGETS["tiny"]), "epsilon": 100.0,
            "min_segment_distance": 0.6, "wall_seconds": 1.0, "shape": "4C"},
           four_cage())
    yield st
    st.close()


def _records(store):
    bead, tube = parse_models("bead,tube")
    hashes = {"bead": _hash(bead), "tube": _hash(tube)}
    return knot_records(store, list(ROWS) + ["9_1"], [bead, tube], hashes)


def _hash(model):
    from stiffknots.store import settings_hash

    return settings_hash(sweep_settings(model, BUDGETS["small"]))


def test_family_statistics_from_store_rows(store):
    entries = [json_entry(r, "bead") for r in _records(store)]
    grounds = {e["name"]: e["models"]["bead"]["ground"] for e in entries}
    assert grounds["9_1"] is None  # swept, nothing stored
    study = family_study(grounds, model="bead", width="bead rule d = 1/√2, N = 150")
    by = {k["name"]: k for k in study["knots"]}
    assert by["3_1"]["predicted"] == by["3_1"]["shape"] == "CB(i=2)"
    assert by["8_19"]["predicted"] == by["8_19"]["shape"] == "CB(i=3)"
    assert (by["5_2"]["predicted"], by["5_2"]["shape"]) == ("4C", "80")
    assert by["5_2"]["epsilon"] == 147.3  # the other budget's 100.0 is not this ensemble
    assert by["6_2"]["as_predicted"] is True and by["6_2"]["converged"] is False
    assert by["7_4"]["families"] == [] and by["7_4"]["predicted"] is None
    assert [r["name"] for r in study["mismatch"]] == ["5_2"]
    assert [(r["name"], r["shape"]) for r in study["no_family"]] == [("7_4", "other")]
    # every ground state's contact structure named from its chain (§V B)
    assert {k: by[k]["structure"] for k in ("3_1", "4_1", "7_4", "8_19")} == {
        "3_1": STRUCTURE["CB2"], "4_1": STRUCTURE["4C"], "7_4": STRUCTURE["other"],
        "8_19": STRUCTURE["CB3"]}
    assert by["9_1"]["structure"] is None  # nothing stored
    assert study["no_family_structures"] == [
        {"structure": "no contacts", "count": 1, "knots": ["7_4"], "shapes": {"other": 1},
         "epsilon": [190.0, 190.0]}]
    g7, g9, gall = study["groups"]
    assert (g7["label"], g9["label"], gall["label"]) == ("n_c < 7", "n_c < 9",
                                                          "all swept (n_c ≤ 9)")
    # n_c < 7: 3_1, 4_1, 5_2, 6_2
    assert g7["knots"] == 4
    assert g7["counts"] == {"CB(i)": 1, "4C": 1, "80": 2}
    assert (g7["in_family"], g7["as_predicted"], g7["converged"]) == (4, 3, 2)
    # n_c < 9 adds 7_4 and 8_19; 9_1 has no result
    assert g9["knots"] == gall["knots"] == 6
    assert g9["counts"] == {"CB(i)": 2, "4C": 1, "80": 2, "other": 1}
    assert (g9["in_family"], g9["as_predicted"], g9["converged"]) == (5, 4, 3)
    # ε against n² for n = 2, 3, 4
    assert sorted(p["knot"] for p in study["eps_n2"]["2"]) == ["3_1", "4_1", "5_2", "6_2",
                                                               "7_4"]
    assert [p["knot"] for p in study["eps_n2"]["3"]] == ["8_19"]
    assert study["eps_n2"]["4"] == []
    # the catalogue: the paper's claims
    cat = {r["label"]: r for r in study["catalogue"]}
    assert (cat["n_c < 7"]["covered"], cat["n_c < 7"]["knots"]) == (7, 7)
    assert (cat["n_c < 9"]["covered"], cat["n_c < 9"]["knots"]) == (26, 35)
    assert cat["n_c < 7"]["paper"] == 1.0 and cat["n_c < 9"]["paper"] == 0.75
    # as the atlas shows it
    t = families_table(study)
    assert [g["label"] for g in t["groups"]] == [g["label"] for g in study["groups"]]
    assert t["groups"][1]["total"] == 6
    assert t["groups"][1]["counts"]["ground = the family's shape"] == 4
    assert "Swept knots in no family: 1 with results, in 1 contact structures" in t["note"]
    assert "no result yet" not in t["note"]  # 9_1 is in the family n = i
    assert t["structures"]["rows"] == [{"structure": "no contacts", "knots": ["7_4"],
                                        "shapes": {"other": 1}, "epsilon": [190.0, 190.0]}]
    assert "5_2 (80, predicted 4C)" in t["note"]
    assert "26 of 35 (74 %, paper 75 %)" in t["note"]


def test_json_entries_and_atlas_input(store, tmp_path):
    recs = _records(store)
    e = json_entry(recs[1], "bead")  # 4_1
    assert (e["name"], e["n"], e["i"], e["crossing_number"]) == ("4_1", 2, 3, 4)
    assert (e["shape"], e["multiplicity"], e["epsilon"], e["converged"]) == ("4C", None,
                                                                            128.4, True)
    assert e["families"] == ["4C", "80"] and "N = 150" in e["width"]
    b = e["models"]["bead"]
    assert b["replicas"] == 3 and b["ground"]["count"] == 2 and b["ground"]["converged"]
    assert b["ground"]["structure"] == STRUCTURE["4C"]
    assert b["metastable"][0]["structure"] == STRUCTURE["80"]
    assert [s["name"] for s in b["metastable"]] == ["80"]
    assert b["metastable"][0]["converged"] is None
    assert e["models"]["tube"] == {**e["models"]["tube"], "replicas": 0, "ground": None,
                                   "converged": False}
    # the pages' input: the representative replica's chain for the 3D view
    a = atlas_input(store, recs[1])
    assert list(a["models"]) == ["bead"]  # no tube results: no tube entry
    g = a["models"]["bead"]["ground"]
    assert g["coords"].shape == (150, 3) and g["epsilon"] == 128.4
    assert g["structure"] == STRUCTURE["4C"]
    rep = store.replicas(knot="4_1", shape="4C")
    best = min(rep, key=lambda r: r["epsilon"])
    assert np.array_equal(g["coords"], store.coords(best["id"]))
    # each bead's contact-zone kind, read from the same chain as the structure's name
    from stiffknots.analysis.structure import analyse_structure

    assert g["zones"] == analyse_structure(g["coords"], True).bead_kinds().tolist()
    assert set(g["zones"]) == {0, 2}  # the cage: free strands and two point-braids
    from stiffknots.analysis.structure import Structure
    from stiffknots.report.atlas import ZONE_KINDS

    assert ZONE_KINDS == Structure.BEAD_KINDS  # the pages name the codes as the analysis does
    from stiffknots.report.atlas import write_atlas

    study = family_study({x["name"]: x["models"]["bead"]["ground"]
                          for x in (json_entry(r, "bead") for r in recs)},
                         model="bead", width="bead rule d = 1/√2, N = 150")
    index = write_atlas(tmp_path / "atlas", [atlas_input(store, r) for r in recs],
                        families=families_table(study), thumbnails=False)
    html = index.read_text()
    assert "Conjectured families and the ground states found" in html
    page = (tmp_path / "atlas" / "knots" / "4_1.html").read_text()
    assert f"<td>{STRUCTURE['4C']}</td>" in page  # the states table names the structure
    assert f'title="{STRUCTURE["4C"]}"' in html  # the ground-shape badge's tooltip
    # the knots in no family, by structure, linked to their pages
    assert ('<table id="structures">' in html and '<td>no contacts</td><td class="num">1</td>'
            in html and '<a href="knots/7_4.html">7_4</a>' in html)
    assert (tmp_path / "atlas" / "knots" / "8_19.html").exists()


def test_family_membership():
    assert families_of(get_knot("3_1")) == ["n=i", "80"]
    assert families_of(get_knot("4_1")) == ["4C", "80"]
    assert families_of(get_knot("6_1")) == ["4C", "80"]
    assert families_of(get_knot("8_3")) == ["4C"]
    assert families_of(get_knot("6_3")) == ["80"]
    assert families_of(get_knot("7_4")) == []
    assert families_of(get_knot("8_19")) == ["n=i"]
    assert predicted_shape(get_knot("3_1")) == ("CB", 2)
    assert predicted_shape(get_knot("5_2")) == ("4C", None)
    assert predicted_shape(get_knot("6_2")) == ("80", None)
    assert predicted_shape(get_knot("7_4")) is None
    assert len(EIGHTY_FAMILY) == 26
    # every 80 is a two-bridge knot (module docstring of eighty_embedding)
    assert all(get_knot(k).bridge_number == 2 for k in EIGHTY_FAMILY)


def test_coverage_of_the_catalogue_is_the_papers():
    rows = coverage(catalogue(10))
    r7, r9, rall = rows
    assert (r7["knots"], r7["covered"], r7["outside"]) == (7, 7, [])
    assert (r9["knots"], r9["covered"]) == (35, 26)  # 74 %: the paper's "75 %"
    assert r9["outside"] == ["7_4", "7_7", "8_4", "8_9", "8_11", "8_12", "8_13", "8_14",
                             "8_15"]
    assert rall["knots"] == 249 and rall["by_family"]["n=i"] == 46
    with pytest.raises(ValueError, match="tabulated through 10"):
        coverage(catalogue(11))


def test_eps_n2_points_skip_missing():
    pts = eps_n2_points([{"name": "a", "n": 2, "i": 2, "epsilon": 80.0, "class": "CB(i)"},
                         {"name": "b", "n": 5, "i": 5, "epsilon": 500.0, "class": "CB(i)"},
                         {"name": "c", "n": 3, "i": 3, "epsilon": None, "class": None}])
    assert pts == {"2": [{"knot": "a", "n": 2, "i": 2, "epsilon": 80.0, "shape": "CB(i)"}],
                   "3": [], "4": []}


def test_a_sweep_ensemble_converges_only_after_every_default_start(tmp_path):
    # braid and cage agreeing on 4_1's cage is no verdict while its 80 has not been tried
    # (the solver's rule, problems.base.verdict); the stored table and the page say so too
    from stiffknots.store import ground_table
    from stiffknots.sweeps import ensemble_converged
    from stiffknots.sweeps.convergence import untried_starts

    bead, _ = parse_models("bead,tube")
    with Store(tmp_path / "s.db") as st:
        def put(r, eps, shape, start):
            st.put({"knot": "4_1", "exclusion": "bead", "beads": 150, "thickness": D,
                    "seed": 0, "replica": r, "settings": sweep_settings(bead, BUDGETS["small"]),
                    "epsilon": eps, "min_segment_distance": 0.6, "wall_seconds": 1.0,
                    "shape": shape, "start": start}, np.arange(450.0).reshape(150, 3) + r)

        put(0, 128.384, "4C", "braid")
        put(1, 128.39, "4C", "cage")
        states = st.states("4_1")
        assert untried_starts(states) == ["eighty"]
        assert not ensemble_converged(states)
        row = ground_table(st)[0]
        assert row["starts_tried"] == ["braid", "cage"] and not ensemble_converged(row)
        put(2, 129.2, "other", "eighty")  # tried, and nothing lower: converged
        assert ensemble_converged(st.states("4_1")) and ensemble_converged(ground_table(st)[0])
        # the starts asked for can be given (none: the ground state's rule alone)
        assert ensemble_converged(states, starts=())


def test_a_bead_ground_above_the_tube_ground_is_flagged(tmp_path):
    # a tube chain of width w = d is bead-admissible, so the bead rule's minimum lies at or
    # below the tube's: a bead ground above it is a search that missed (10_4, 2026-12-03)
    bead, tube = parse_models("bead,tube")
    hashes = {m.exclusion: _hash(m) for m in (bead, tube)}

    def entry(eps_bead, eps_tube):
        with Store(tmp_path / f"{eps_bead}-{eps_tube}.db") as st:
            for model, eps in ((bead, eps_bead), (tube, eps_tube)):
                for r in range(2):
                    st.put({"knot": "3_1", "exclusion": model.exclusion, "beads": 150,
                            "thickness": model.thickness, "seed": 0, "replica": r,
                            "settings": sweep_settings(model, BUDGETS["small"]),
                            "epsilon": eps + 0.01 * r, "min_segment_distance": 0.6,
                            "wall_seconds": 1.0, "shape": "CB", "multiplicity": 2,
                            "start": "braid"}, np.zeros((150, 3)) + r)
            return json_entry(knot_records(st, ["3_1"], [bead, tube], hashes)[0], "bead")

    flag = entry(80.5, 79.3)["bead_above_tube"]
    assert flag["bead"] == 80.5 and flag["tube"] == 79.3
    assert flag["missed_by"] == pytest.approx(1.2 / 79.3) and "missed" in flag["note"]
    assert entry(79.02, 79.06)["bead_above_tube"] is None  # bead below tube: as it must be


def test_structure_groups_largest_first_and_skip_missing():
    rows = [{"name": "7_4", "structure": "2 line-braids (m = 2) + double point",
             "shape": "other", "epsilon": 171.2},
            {"name": "8_12", "structure": "line-braid (m = 3)", "shape": "other",
             "epsilon": 249.2},
            {"name": "8_9", "structure": "line-braid (m = 3)", "shape": "CB(i=3)",
             "epsilon": 183.5},
            {"name": "9_9", "structure": None, "shape": None, "epsilon": None}]
    g = structure_groups(rows)
    assert [(x["structure"], x["count"], x["knots"]) for x in g] == [
        ("line-braid (m = 3)", 2, ["8_12", "8_9"]),
        ("2 line-braids (m = 2) + double point", 1, ["7_4"])]
    assert g[0]["shapes"] == {"other": 1, "CB(i=3)": 1}
    assert g[0]["epsilon"] == [183.5, 249.2]


def test_converged_counts_list_the_knots_not_converged():
    """Per model: the counts over the knots with results, and the others by name, in order."""
    from stiffknots.studies.atlas import converged_counts, not_converged_text
    from stiffknots.sweeps import parse_models

    models = parse_models("bead,tube")

    def entry(name, bead, tube):
        return {"name": name, "models": {
            "bead": {"ground": None if bead is None else {"epsilon": 1.0}, "converged": bead},
            "tube": {"ground": None if tube is None else {"epsilon": 1.0}, "converged": tube}}}

    entries = [entry("3_1", True, True), entry("7_4", False, True), entry("10_1", False, None),
               entry("10_2", None, None)]
    c = converged_counts(entries, models)
    assert c == {"bead": {"converged": 1, "knots": 3, "not_converged": ["7_4", "10_1"]},
                 "tube": {"converged": 2, "knots": 2, "not_converged": []}}
    assert not_converged_text(c) == "bead 2 of 3: 7_4, 10_1; tube none of 2"
    assert not_converged_text(converged_counts([entry("10_2", None, None)], models)) == (
        "no results stored yet")
