"""Tests of the atlas input (stiffknots.report.atlas.schema): its validation and the
family statistics counted from it."""


import pytest

from stiffknots.report.atlas import family_statistics, format_width, write_atlas


def test_family_statistics_from_the_knots(knots):
    f = family_statistics(knots)
    assert f["model"] == "bead"
    # every knot has n_c < 9: that column equals "all knots" and is left out
    assert [g["label"] for g in f["groups"]] == ["n_c < 7", "all knots"]
    assert f["groups"][0] == {"label": "n_c < 7", "total": 5,
                              "counts": {"CB(2)": 2, "4C": 2, "other": 1}}
    assert f["groups"][1]["total"] == 6 and f["groups"][1]["counts"]["CB(3)"] == 1
    t = family_statistics(knots, model="tube", max_crossings=[5])
    assert t["groups"] == [{"label": "n_c < 5", "total": 2, "counts": {"CB(2)": 1, "4C": 1}},
                           {"label": "all knots", "total": 3,
                            "counts": {"CB(2)": 2, "4C": 1}}]


def test_input_errors_say_what_is_wrong(tmp_path, knots):
    k = knots[0]
    no_width = {**k, "models": {"bead": {"ground": {"shape": "CB", "epsilon": 79.0}}}}
    with pytest.raises(ValueError, match="no width"):
        write_atlas(tmp_path, [no_width])
    bare = {**k, "models": {"bead": {"width": 0.01, "ground": {"epsilon": 79.0}}}}
    with pytest.raises(ValueError, match="bare number"):
        write_atlas(tmp_path, [bare])
    with pytest.raises(ValueError, match="appears twice"):
        write_atlas(tmp_path, [k, k])
    bad = {**k, "models": {"bead": {"width": "w", "ground": {"epsilon": 1.0,
                                                            "coords": [[0, 0, 0]]}}}}
    with pytest.raises(ValueError, match=r"shape \(N, 3\)"):
        write_atlas(tmp_path, [bad])
    with pytest.raises(ValueError, match="default_model"):
        write_atlas(tmp_path, knots, default_model="nope")
    named = {**k, "models": {"bead": {"width": "w", "ground": {"epsilon": 1.0,
                                                              "structure": 3}}}}
    with pytest.raises(ValueError, match="structure must be a text"):
        write_atlas(tmp_path, [named])
    fam = {"groups": [], "structures": {"rows": [{"structure": "double point"}]}}
    with pytest.raises(ValueError, match="needs 'structure' .* and 'knots'"):
        write_atlas(tmp_path, knots, families=fam)
    fam["structures"]["rows"][0]["knots"] = "7_4"  # a name, not a list of names
    with pytest.raises(ValueError, match="needs 'structure' .* and 'knots'"):
        write_atlas(tmp_path, knots, families=fam)
    assert not (tmp_path / "index.html").exists()


def test_format_width_reads_one_width_as_object_dict_or_text():
    from stiffknots.width import Width

    w = Width.tube(173, w_over_L=0.004)
    assert format_width(w) == format_width(w.as_dict()) == w.text
    assert format_width("bead rule d = 1/√2, N = 150") == "bead rule d = 1/√2, N = 150"
    assert format_width({"w/L": 0.01}) == "w/L = 0.01"
