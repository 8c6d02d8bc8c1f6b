"""Tests of stiffknots.analysis: contacts, line-/point-braids, structure graph (§V), shape
classes CB / 4C / 80 (§VII, Fig. 7) and ground/metastable grouping."""

import json
import math
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from stiffknots.analysis import (
    DEFAULT_D,
    ContactMap,
    analyse_structure,
    classify,
    contact_map,
    group_states,
    line_braids,
    local_multiplicity,
    structure_graph,
    structure_name,
)
from stiffknots.analysis.contacts import index_separation
from stiffknots.analysis.synthetic import (
    eight_plus_circle,
    four_cage,
    random_compact_chain,
    resample_closed,
    torus_braid,
)
from stiffknots.chain import Chain, regular_polygon
from stiffknots.errors import ChainWarning
from stiffknots.theory.elastica import eight_curve, eighty_curve

DATA = Path(__file__).parent.parent / "data" / "analysis"
MANIFEST = json.loads((DATA / "fixtures.json").read_text())["fixtures"]


def fixture(name):
    return np.load(DATA / name)


def rotation(seed=3):
    q, _ = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    return q


def covered_beads(stretches, n):
    return np.concatenate([(s + np.arange(ln)) % n for s, ln in stretches])


# ------------------------------------------------------------------------------- contacts


def test_contact_map_matches_brute_force():
    x = random_compact_chain(120, seed=5)
    cm = contact_map(x)
    n = len(x)
    d = np.linalg.norm(x[:, None] - x[None], axis=2)
    i, j = np.triu_indices(n, 1)
    sep = np.minimum(j - i, n - (j - i))
    want = {(a, b) for a, b in zip(i, j, strict=True)
            if sep[(a * (2 * n - a - 1)) // 2 + b - a - 1] >= 5 and d[a, b] <= math.sqrt(2)}
    got = set(zip(cm.i.tolist(), cm.j.tolist(), strict=True))
    assert got == want
    assert cm.cutoff == pytest.approx(math.sqrt(2.0)) == pytest.approx(2 * DEFAULT_D)
    assert np.all(index_separation(cm.i, cm.j, n) >= cm.min_sep)
    assert np.allclose(cm.dist, d[cm.i, cm.j])
    m = cm.matrix()
    assert m.sum() == 2 * cm.n_contacts and np.array_equal(m, m.T)


def test_contact_separation_cyclic_for_closed_plain_for_open():
    x = regular_polygon(40).coords  # beads 0 and 39 are bonded (closed) or far in index (open)
    closed = contact_map(x, closed=True, cutoff=2.5)
    opened = contact_map(x, closed=False, cutoff=2.5)
    assert closed.n_contacts == 0
    pairs = set(zip(opened.i.tolist(), opened.j.tolist(), strict=True))
    assert (0, 39) in pairs and (0, 38) in pairs and (1, 39) in pairs
    assert all(j - i >= 5 for i, j in pairs)


def test_contact_cutoff_and_factor():
    x = regular_polygon(150, 2).coords  # covers 1.0 apart
    assert contact_map(x, factor=1.5).n_contacts > 0
    assert contact_map(x, cutoff=0.9).n_contacts == 0
    assert contact_map(x, d=0.5, factor=2.2).cutoff == pytest.approx(1.1)


@pytest.mark.parametrize(
    "kwargs, match",
    [
        ({"coords": np.zeros((10, 2))}, "shape"),
        ({"coords": np.full((10, 3), np.nan)}, "finite"),
        ({"coords": np.zeros((3, 3))}, "at least 4"),
        ({"coords": "abc"}, "numbers"),
        ({"min_sep": 1}, "min_sep"),
        ({"min_sep": 80}, "no possible contact"),
        ({"d": -1.0}, "d must be"),
        ({"factor": 0}, "factor must be"),
        ({"cutoff": float("inf")}, "cutoff must be"),
    ],
)
def test_contact_map_bad_input(kwargs, match):
    args = {"coords": regular_polygon(100).coords}
    args.update(kwargs)
    with pytest.raises(ValueError, match=match):
        contact_map(args.pop("coords"), **args)


# ---------------------------------------------------------------- multiplicity and braids


@pytest.mark.parametrize("i", [2, 3, 4])
def test_multiplicity_of_torus_braids(i):
    # covers 0.9 apart: for i = 4 the diagonal pairs of the square cross-section (1.27) are
    # within the contact distance too, so every strand touches all the others
    x = torus_braid(i, 50 * i, separation=0.9)
    m = local_multiplicity(contact_map(x))
    assert np.all(m == i)
    braids = line_braids(x)
    assert len(braids) == 1 and braids[0].closed and braids[0].multiplicity == i
    assert braids[0].stretches == [(0, len(x))]


def test_multiplicity_counts_strands_not_beads():
    """m(s) = 1 + number of index-contiguous groups among the partners of s (cyclic if
    closed)."""
    def cmap(pairs, closed):
        i, j = np.array(pairs).T
        return ContactMap(40, closed, 1.0, 5, i, j, np.ones(len(pairs)))

    wrap = [(0, 20), (1, 20), (20, 39)]           # one strand through beads 39, 0, 1
    assert local_multiplicity(cmap(wrap, True))[20] == 2
    assert local_multiplicity(cmap(wrap, False))[20] == 3   # open: 39 and 0 are far apart
    two = [(0, 20), (2, 20), (9, 20)]              # gap 7 > min_sep: two strands
    m = local_multiplicity(cmap(two, True))
    assert m[20] == 3 and m[0] == m[9] == 2 and m[5] == 1


def test_multiplicity_of_plain_circle_is_one():
    x = regular_polygon(150).coords
    assert np.all(local_multiplicity(contact_map(x)) == 1)
    st = analyse_structure(x)
    assert st.line_braids == [] and st.zones == []
    assert len(st.graph.edges) == 1 and st.graph.edges[0].nodes == (None, None)
    assert st.graph.edges[0].length == pytest.approx(150.0)


def hairpin(arm=40, tail=10, gap=1.0):
    """Open chain: a straight arm, a half-circle turn of diameter `gap`, a straight arm back
    that goes on for `tail` more bonds."""
    k = 3
    a = np.column_stack([np.arange(arm, 0, -1.0), np.zeros(arm), np.zeros(arm)])
    th = np.linspace(-math.pi / 2, math.pi / 2, k + 2)[1:-1]
    c = np.column_stack([-gap * np.cos(th), 0.5 * gap * np.sin(th) + 0.5 * gap, np.zeros(k)])
    b = np.column_stack([np.arange(1, arm + tail + 1.0), np.full(arm + tail, gap),
                         np.zeros(arm + tail)])
    return np.vstack([a, c, b])


def test_open_hairpin_is_a_line_braid_with_ends():
    x = hairpin()
    st = analyse_structure(x, closed=False, min_length=10)
    assert st.multiplicity.max() == 2
    assert len(st.line_braids) == 1
    br = st.line_braids[0]
    assert br.multiplicity == 2 and len(br.stretches) == 2 and not br.closed
    assert br.length > 25
    g = st.graph
    assert g.counts() == {"line-braid": 1, "braid-end": 2, "chain-end": 1, "arc": 2}
    arcs = [e for e in g.edges if e.kind == "arc"]
    turn = [e for e in arcs if e.nodes[0] == e.nodes[1]]
    tail = [e for e in arcs if e.nodes[0] != e.nodes[1]]
    # the turn is a loop at one end of the braid, the tail joins the other end to the free end
    assert len(turn) == 1 and g.nodes[turn[0].nodes[0]].kind == "braid-end"
    assert len(tail) == 1 and {g.nodes[k].kind for k in tail[0].nodes} == {"braid-end",
                                                                             "chain-end"}
    assert turn[0].nodes[0] not in tail[0].nodes
    assert tail[0].length == pytest.approx(10.0, abs=2.0)


def test_structure_graph_covers_every_bead_once():
    for x in (eight_plus_circle(), four_cage(), fixture("6_2_seed1_r1.npy"),
              fixture("3_1_seed1_r0.npy")):
        st = analyse_structure(x)
        n = len(x)
        zone_beads = [covered_beads(z.runs, n) for z in st.zones]
        arc_beads = [covered_beads(e.stretches, n) for e in st.graph.edges if e.kind == "arc"]
        beads = np.concatenate(zone_beads + arc_beads)
        assert np.array_equal(np.sort(beads), np.arange(n))
        # every node is reached by at least two edge ends (strands pass through)
        assert all(st.graph.degree(k) >= 2 for k in range(len(st.graph.nodes)))
        json.dumps(st.to_dict())


def test_bead_kinds_mark_each_zone_on_its_beads():
    """bead_kinds: the cage's two point-braids, the 80's point-braid and double points, the
    circular braid everywhere a line-braid, the circle nowhere in contact; each code exactly
    on the beads of its zones' runs."""
    cases = [(four_cage(), {0, 2}), (eight_plus_circle(600), {0, 2, 3}),
             (torus_braid(2, 100, separation=0.9), {1}),
             (regular_polygon(150).coords, {0})]
    for x, codes in cases:
        st = analyse_structure(x)
        k = st.bead_kinds()
        assert k.shape == (len(x),) and set(np.unique(k).tolist()) == codes
        for z in st.zones:
            code = {"line-braid": 1, "point-braid": 2, "multiple-point": 3}[z.kind]
            assert (k[covered_beads(z.runs, len(x))] == code).all()
        assert ((k == 0) == (st.multiplicity == 1)).all()  # every contact bead is in a zone
        assert st.BEAD_KINDS[2] == "point-braid"


def test_a_contact_distance_too_short_for_the_bonds_is_warned_of():
    """Read at d = 0.1 (a thin tube on unit bonds) the contacts of touching strands are
    missed where their beads are staggered: a ChainWarning says so; at the bead rule's d it
    does not."""
    import warnings

    x = regular_polygon(150).coords
    with pytest.warns(ChainWarning, match="contacts are missed"):
        analyse_structure(x, d=0.1)
    with warnings.catch_warnings(record=True) as got:
        warnings.simplefilter("always")
        analyse_structure(x)
    assert not [w for w in got if "contacts are missed" in str(w.message)]


def test_cage_structure_two_point_braids_four_arcs():
    """Fig. 9b: the two contact zones of the 4-fold cage are point-braids."""
    g = structure_graph(four_cage())
    assert g.counts() == {"point-braid": 2, "arc": 4}
    for e in g.edges:
        assert e.multiplicity == 1 and e.nodes[0] != e.nodes[1]
    assert [g.degree(k) for k in range(2)] == [4, 4]


def test_eighty_structure_one_point_braid_three_double_points():
    """Fig. 9c: the 80 shows one point-braid and three double points."""
    # at N = 150 the circle crosses the lobe next to the 8's crossing and the three double
    # points merge into one triple contact; they separate from N ≈ 600 on
    for n in (600, 1200):
        st = analyse_structure(eight_plus_circle(n))
        assert st.zone_counts() == {"line-braid": 0, "point-braid": 1, "multiple-point": 3}


def test_annealed_trefoil_has_a_multiplicity_two_line_braid():
    """Fig. 9a: the 3_1 is a line-braid of multiplicity 2 (partly in contact at N = 150)."""
    st = analyse_structure(fixture("3_1_seed1_r1.npy"))
    assert st.multiplicity.max() == 2
    assert any(b.multiplicity == 2 and b.length >= 15 for b in st.line_braids)


def test_structure_names_of_the_paper_shapes():
    """The names of Fig. 7: the trefoil's circular line-braid, the cage's two point-braids,
    the 80's point-braid and three double points; a plain circle has no contacts."""
    for i in (2, 3):
        assert analyse_structure(torus_braid(i, 50 * i, separation=0.9)).name == (
            f"circular line-braid (m = {i})")
    assert analyse_structure(four_cage()).name == "2 point-braids"
    assert analyse_structure(eight_plus_circle(600)).name == "point-braid + 3 double points"
    assert analyse_structure(regular_polygon(150).coords).name == "no contacts"
    st = analyse_structure(four_cage())
    assert st.to_dict()["name"] == st.name
    assert classify(four_cage()).structure["name"] == "2 point-braids"


def _zone(kind, m, closed=False):
    return SimpleNamespace(kind=kind, multiplicity=m, closed=closed)


@pytest.mark.parametrize("zones, name", [
    ([], "no contacts"),
    ([_zone("multiple-point", 2)], "double point"),
    ([_zone("line-braid", 2), _zone("multiple-point", 2), _zone("line-braid", 2)],
     "2 line-braids (m = 2) + double point"),
    ([_zone("multiple-point", 2), _zone("multiple-point", 3), _zone("multiple-point", 2),
      _zone("multiple-point", 5)], "5-fold point + triple point + 2 double points"),
    ([_zone("point-braid", 2), _zone("line-braid", 2), _zone("line-braid", 3),
      _zone("point-braid", 3)],
     "line-braid (m = 3) + line-braid (m = 2) + point-braid (m = 3) + point-braid"),
    ([_zone("line-braid", 2, closed=True)], "circular line-braid (m = 2)"),
])
def test_structure_name_counts_and_orders_the_zones(zones, name):
    """Line-braids first (highest m first), then point-braids, then multiple points by the
    strands meeting; a kind that occurs more than once is counted."""
    assert structure_name(zones) == name


def _braid(stretches, m=3):
    return SimpleNamespace(kind="line-braid", multiplicity=m, closed=False,
                           stretches=stretches)


@pytest.mark.parametrize("stretches, hold, m", [
    ({2: 29.0, 3: 0.0}, 4.2, 2),   # a third strand touches one bead (8_5's ground, N = 150)
    ({2: 10.0, 3: 7.0}, 4.2, 3),   # three strands that part and meet again (8_18's CB(3))
    ({2: 10.0, 3: 7.0}, 8.0, 2),   # m = 3 held too short: the longest constant stretch
    ({2: 10.0, 3: 7.0}, None, 2),
    ({2: 3.0, 3: 3.0}, 4.2, 3),    # none held: the longest, the larger m on a tie
])
def test_a_line_braid_is_named_by_the_strands_it_holds(stretches, hold, m):
    """A line-braid's m: the largest local multiplicity one strand holds over ``hold``, not
    the largest anywhere in it."""
    assert structure_name([_braid(stretches)], hold) == f"line-braid (m = {m})"


def test_zone_stretches_are_the_longest_constant_multiplicity_runs():
    """On a circular braid of i strands every bead has m = i along the whole chain."""
    st = analyse_structure(torus_braid(3, 150, separation=0.9))
    (z,) = st.zones
    assert z.stretches == {3: pytest.approx(150.0, rel=1e-3)}
    assert st.to_dict()["zones"][0]["stretches"] == {"3": z.stretches[3]}


def test_structure_bad_parameters():
    x = regular_polygon(60).coords
    with pytest.raises(ValueError, match="tangent_angle"):
        analyse_structure(x, tangent_angle=95)
    with pytest.raises(ValueError, match="min_length"):
        analyse_structure(x, min_length=-1)
    with pytest.raises(ValueError, match="ContactMap"):
        local_multiplicity(x)


# ------------------------------------------------------------------------- classification


@pytest.mark.parametrize("i", [2, 3])
def test_synthetic_circular_braids(i):
    s = classify(torus_braid(i))
    assert (s.label, s.multiplicity) == ("CB", i)
    assert s.features["CB"]["curvature_ratio"] == pytest.approx(1.0, abs=0.02)
    s = classify(regular_polygon(150, i).coords)
    assert (s.label, s.multiplicity) == ("CB", i)


def test_plain_circle_is_cb_one():
    """Documented choice: the circle is the i = 1 member of the n = i family (ε = 2π²)."""
    s = classify(regular_polygon(150).coords)
    assert (s.label, s.multiplicity) == ("CB", 1)


def test_eight_plus_circle_is_80():
    # the theory module's planar 80 (circle outside the lobe), lifted like eight_plus_circle
    shadow = resample_closed(eighty_curve(4001)[:-1], 150)
    shadow[:, 2] = 0.75 * np.cos(2 * np.pi * np.arange(150) / 150)
    for x in (eight_plus_circle(), eight_plus_circle(inside=False), eight_plus_circle(300),
              shadow):
        s = classify(x)
        assert s.label == "80" and s.multiplicity is None, s.reason
        f = s.features["80"]
        assert f["circle_fraction"] == pytest.approx(0.372, abs=0.02)
        assert f["eight"]["turns"] == pytest.approx(1.452, abs=0.05)
    assert Chain(eight_plus_circle(600)).epsilon() == pytest.approx(142.58, rel=0.01)


def test_four_cage_is_4c():
    for n in (150, 300):
        s = classify(four_cage(n))
        assert s.label == "4C", s.reason
        assert s.features["4C"]["pole_axes_angle"] == pytest.approx(90.0, abs=5.0)


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_random_compact_chain_is_other(seed):
    s = classify(random_compact_chain(150, seed=seed))
    assert s.label == "other" and "CB: fails" in s.reason


def test_lone_figure_eight_and_ellipse_are_other():
    eight = resample_closed(eight_curve(2001)[:-1], 150)
    eight[:, 2] = 0.6 * np.cos(2 * np.pi * np.arange(150) / 150)  # lift the crossing apart
    assert classify(eight).label == "other"
    t = np.linspace(0, 2 * np.pi, 3000, endpoint=False)
    ellipse = resample_closed(np.column_stack([2 * np.cos(t), np.sin(t)]), 150)
    assert classify(ellipse).label == "other"


def test_classification_is_invariant_under_rigid_motions():
    rot = rotation()
    for x in (torus_braid(2), four_cage(), eight_plus_circle(), fixture("5_2_seed1_r0.npy")):
        a, b = classify(x), classify(x @ rot.T + np.array([5.0, -3.0, 7.0]))
        assert (a.label, a.multiplicity) == (b.label, b.multiplicity)
    # scale invariance once the contact distance scales with the chain
    x = fixture("4_1_seed1_r0.npy")
    assert classify(3.0 * x, d=3.0 * DEFAULT_D).label == "4C"


def test_shape_output_is_plain_data():
    s = classify(fixture("6_2_seed1_r0.npy"))
    d = json.loads(json.dumps(s.to_dict()))
    assert d["label"] == "80"
    assert set(d["checks"]) == {"CB", "4C", "80"}
    assert all(d["checks"]["80"].values())
    assert str(classify(torus_braid(3))) == "CB(i=3)"


def test_open_chain_is_other():
    s = classify(hairpin(), closed=False)
    assert s.label == "other" and "open" in s.reason


@pytest.mark.parametrize("item", MANIFEST, ids=[m["file"] for m in MANIFEST])
def test_annealed_fixtures(item):
    x = fixture(item["file"])
    assert Chain(x).epsilon() == pytest.approx(item["epsilon"], rel=1e-9)
    s = classify(x)
    assert (s.label, s.multiplicity) == (item["label"], item["multiplicity"]), s.reason


def test_annealed_fixtures_cover_the_paper_classes():
    """3_1 → CB(2), 4_1 → 4C, 5_2/6_2/6_3 → 80 (Fig. 7); plus CB(3) and a flat 'other'."""
    found = {(m["knot"], m["label"], m["multiplicity"]) for m in MANIFEST}
    assert ("3_1", "CB", 2) in found and ("4_1", "4C", None) in found
    assert {("5_2", "80", None), ("6_2", "80", None), ("6_3", "80", None)} <= found
    assert ("6_3", "CB", 3) in found and ("4_1", "other", None) in found


def test_flat_4_1_state_is_an_8_and_0_joined_by_a_crossing():
    """The flat 4_1 state fails the 80 only because its 8 and 0 meet at a crossing, not at a
    point-braid (cut angle ≈ 78° > 45°), and fails the 4C because it is flat."""
    s = classify(fixture("4_1_seed0_r0.npy"))
    assert s.label == "other"
    failed80 = [k for k, v in s.checks["80"].items() if not v]
    assert failed80 == ["smooth_cut"]
    assert not s.checks["4C"]["three_dimensional"]


def test_classify_large_chain():
    s = classify(torus_braid(2, 2000))
    assert (s.label, s.multiplicity) == ("CB", 2)
    assert classify(random_compact_chain(2000)).label == "other"


# --------------------------------------------------------------------------- group_states


def test_group_states_picks_lowest_epsilon_as_ground():
    items = [{"coords": fixture(m["file"]), "epsilon": m["epsilon"], "meta": {"file": m["file"]}}
             for m in MANIFEST if m["knot"] == "6_3"]
    res = group_states(items)
    assert res.ground.label == "80" and res.ground.eps_min == pytest.approx(166.756, abs=1e-3)
    assert [(s.label, s.multiplicity) for s in res.metastable] == [("CB", 3)]
    assert res.ground.meta == {"file": "6_3_seed1_r1.npy"}
    json.dumps(res.to_dict())


def test_group_states_counts_and_tolerance():
    x80, x4c = fixture("5_2_seed1_r0.npy"), fixture("4_1_seed1_r0.npy")
    items = [
        {"coords": x80, "epsilon": 150.1},
        {"coords": x80, "epsilon": 148.8},
        {"coords": x4c, "epsilon": 129.6},
        {"coords": x80, "epsilon": 148.9},
        {"coords": x80, "epsilon": 153.0},   # > 1 % above 148.8: a separate 80 state
        SimpleNamespace(coords=x4c, epsilon=130.0),
    ]
    res = group_states(items)
    assert res.ground.label == "4C" and res.ground.count == 2
    assert res.ground.representative == 2 and res.ground.members == [2, 5]
    assert res.ground.eps_mean == pytest.approx(129.8)
    first, second = res.metastable
    assert (first.label, first.count, first.representative) == ("80", 3, 1)
    assert first.eps_min == pytest.approx(148.8) and first.eps_max == pytest.approx(150.1)
    assert (second.label, second.count, second.eps_min) == ("80", 1, 153.0)
    # a looser tolerance merges the two 80 states
    assert [s.count for s in group_states(items, rel_tol=0.05).states] == [2, 4]


def test_group_states_with_given_labels():
    items = [{"label": "CB", "multiplicity": 2, "epsilon": 80.0},
             {"label": "CB", "multiplicity": 3, "epsilon": 181.0},
             {"label": "CB", "multiplicity": 2, "epsilon": 79.5}]
    res = group_states(items)
    assert res.ground.name == "CB(i=2)" and res.ground.count == 2
    assert res.ground.representative == 2
    assert res.metastable[0].name == "CB(i=3)"


@pytest.mark.parametrize(
    "items, kwargs, match",
    [
        ([], {}, "at least one"),
        ([{"label": "80"}], {}, "epsilon must be a number"),
        ([{"label": "80", "epsilon": float("nan")}], {}, "finite"),
        ([{"label": "8", "epsilon": 1.0}], {}, "label must be one of"),
        ([{"label": "CB", "epsilon": 1.0}], {}, "multiplicity"),
        ([{"epsilon": 1.0}], {}, "neither 'coords'"),
        ([{"label": "80", "epsilon": 1.0}], {"rel_tol": -0.1}, "rel_tol"),
    ],
)
def test_group_states_bad_input(items, kwargs, match):
    with pytest.raises(ValueError, match=match):
        group_states(items, **kwargs)
