"""Tests of line-braids, point-braids, multiple points and the structure graph
(stiffknots.analysis.structure; paper §V, Figs 5 and 7)."""

import json
from types import SimpleNamespace

import numpy as np
import pytest

from stiffknots.analysis.contacts import ContactMap, contact_map
from stiffknots.analysis.shapes import classify
from stiffknots.analysis.structure import (
    analyse_structure,
    line_braids,
    local_multiplicity,
    structure_graph,
    structure_name,
)
from stiffknots.analysis.synthetic import eight_plus_circle, four_cage, torus_braid
from stiffknots.chain import regular_polygon
from stiffknots.errors import ChainWarning


def covered_beads(stretches, n):
    return np.concatenate([(s + np.arange(ln)) % n for s, ln in stretches])


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


def test_open_hairpin_is_a_line_braid_with_ends(hairpin):
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


def test_structure_graph_covers_every_bead_once(annealed):
    for x in (eight_plus_circle(), four_cage(), annealed("6_2_seed1_r1.npy"),
              annealed("3_1_seed1_r0.npy")):
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


def test_annealed_trefoil_has_a_multiplicity_two_line_braid(annealed):
    """Fig. 9a: the 3_1 is a line-braid of multiplicity 2 (partly in contact at N = 150)."""
    st = analyse_structure(annealed("3_1_seed1_r1.npy"))
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
