"""Tests of the energies by name (stiffknots.theory.structures.energy): the names, the
results, the cage with its axes held."""

from __future__ import annotations

import pytest

from stiffknots.theory import structures as st


@pytest.mark.slow
def test_cage_perpendicular_axes_are_optimal():
    free = st.solve_structure(st.four_fold_cage(), (16, 32, 64), orders=2).epsilon
    scan = st.cage_axis_scan(angles=(60.0,), Ks=(16, 32, 64))
    assert scan[0]["epsilon"] > free + 1.0


@pytest.mark.parametrize("bad", ["CB(0)", "cb(2)", "5C", "4_1", "CB", "", "PBL(0)", 80])
def test_bad_name(bad):
    with pytest.raises(ValueError) as exc:
        st.structure_energy(bad)
    if isinstance(bad, str):
        for name in ("CB(i)", "'80'", "'4C'"):
            assert name in str(exc.value)


def test_result_is_a_copy():
    a = st.structure_energy("CB(1)")
    a["epsilon"] = 0.0
    assert st.structure_energy("CB(1)")["epsilon"] > 19.0
    assert set(a) >= {"epsilon", "error", "method", "structure", "K", "details"}
