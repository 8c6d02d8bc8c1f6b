"""The thin-limit values of the shape classes (theory/references.py) against their sources."""

from __future__ import annotations

import math

import pytest

from stiffknots.theory.elastica import eps_80
from stiffknots.theory.references import EPS_4C, thin_limit_note, thin_limit_of_shape


@pytest.mark.parametrize("shape,mult,i", [("CB", 2, 2), ("CB3", None, 3), ("CB", 1, 1)])
def test_circular_braid_is_2pi2_i2(shape, mult, i):
    assert thin_limit_of_shape(shape, mult)["epsilon"] == pytest.approx(2 * math.pi**2 * i * i,
                                                                         rel=1e-15)


def test_eighty_is_appendix_d():
    assert thin_limit_of_shape("80")["epsilon"] == pytest.approx(eps_80(), rel=1e-15)
    assert thin_limit_of_shape("80")["epsilon"] == pytest.approx(142.584368, abs=1e-6)


def test_unknown_shapes_have_no_value():
    assert thin_limit_of_shape("other") is None and thin_limit_of_shape(None) is None
    assert thin_limit_of_shape("CB", None) is None
    note = thin_limit_note(150.0, "other", None, "bead rule d = 0.7071, N = 150")
    assert note["epsilon"] is None and "upper bound" in note["note"]


def test_note_states_width_and_excess():
    note = thin_limit_note(79.0182, "CB", 2, "bead rule d = 0.7071, N = 150 (w/L ≈ 0.0047)")
    assert note["excess"] == pytest.approx(79.0182 / (8 * math.pi**2) - 1)
    assert "w/L ≈ 0.0047" in note["note"] and "+0.078 %" in note["note"]


@pytest.mark.slow
def test_tabulated_cage_is_the_structure_solve():
    from stiffknots.theory.structures import structure_energy

    assert structure_energy("4C")["epsilon"] == pytest.approx(EPS_4C, abs=1e-8)


def test_note_below_the_thin_limit_and_small_excesses():
    # the unknot at N = 150: the regular 150-gon, N²(1 − cos 2π/N), lies below 2π²
    eps = 150**2 * (1 - math.cos(2 * math.pi / 150))
    note = thin_limit_note(eps, "CB", 1, "bead rule d = 0.7071, N = 150")
    assert note["excess"] < 0 and "-0.015 %" in note["note"]
    assert "discretisation" in note["note"]
    # 3_1 at N = 600: +0.005 %, shown to two significant figures
    note = thin_limit_note(8 * math.pi**2 * 1.00005, "CB", 2, "N = 600")
    assert "+0.005 %" in note["note"] and "discretisation" not in note["note"]
