"""Queries of the store (store/queries): the ground table and its CSV, the description of a knot."""

from __future__ import annotations

import csv

import pytest

from stiffknots.store import (
    describe_knot,
    ground_table,
    settings_hash,
    to_csv,
)
from store_support import (
    SETTINGS,
    D,
    chain,
    fill_5_2,
    make_row,
)


def test_ground_table_one_row_per_model_and_csv(store, tmp_path):
    fill_5_2(store)
    # a second settings for the 150-bead bead model with a higher ground: not chosen
    store.put(make_row(settings={**SETTINGS, "moves": 20}, epsilon=140.0, shape="4C"),
              chain())
    store.put(make_row(knot="3_1", shape="CB", multiplicity=2, epsilon=79.5, start="braid"),
              chain())
    table = ground_table(store)
    models = [(t["knot"], t["exclusion"], t["beads"], t["thickness"]) for t in table]
    assert models == [("3_1", "bead", 150, D), ("5_2", "bead", 100, D), ("5_2", "bead", 150, 0.5),
                      ("5_2", "bead", 150, D), ("5_2", "tube", 150, D)]
    row = table[3]
    assert (row["state"], row["epsilon"], row["n_settings"]) == ("80", 103.0, 3)
    assert row["settings_hash"] == settings_hash({**SETTINGS, "moves": 10})
    assert table[0]["state"] == "CB(i=2)" and table[0]["multiplicity"] == 2
    only = store.ground_states(knot="5_2", beads=150, exclusion="bead", thickness=D)
    assert len(only) == 1 and only[0]["epsilon"] == 103.0
    full = store.states("5_2", beads=150, exclusion="bead", thickness=D,
                        settings_hash=settings_hash(SETTINGS))
    assert full["ground"]["epsilon"] == 128.4
    path = to_csv(tmp_path / "out" / "ground.csv", table)
    with open(path, newline="") as f:
        back = list(csv.DictReader(f))
    assert len(back) == 5 and list(back[0]) == list(table[0])
    assert float(back[0]["thickness"]) == D and back[0]["converged"] == ""
    assert back[0]["knot_verified"] == "" and back[0]["metastable"] == ""
    assert (back[3]["state"], back[3]["epsilon"], back[3]["n_settings"]) == ("80", "103.0", "3")
    # one settings only: its ground and, in order, its metastable states
    (one,) = store.ground_states(knot="5_2", exclusion="bead", beads=150, thickness=D,
                                 settings_hash=settings_hash(SETTINGS))
    assert (one["state"], one["count"], one["replicas"], one["n_states"]) == ("4C", 3, 8, 5)
    assert one["metastable"] == "80 147.30 ×2; other 150.00 ×1; 80 152.00 ×1; CB(i=3) 181.20 ×1"


def test_describe_knot_lists_every_ensemble(store):
    fill_5_2(store)
    d = describe_knot(store, "5_2")
    assert d["knot"] == "5_2" and len(d["ensembles"]) == 5 and d["replicas"] == 12
    (main,) = [e for e in d["ensembles"] if e["replicas"] == 8]
    assert main["ground"]["name"] == "4C"
    assert len(describe_knot(store, "5_2", beads=150, exclusion="bead")["ensembles"]) == 3
    with pytest.raises(ValueError, match="no stored replicas of knot '9_9'.*stored knots: 5_2"):
        describe_knot(store, "9_9")
