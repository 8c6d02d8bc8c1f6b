"""Tests of what a solved structure shows (stiffknots.theory.structures.diagnostics): the
80 as two free closed elastica (§VII, eq. (28)), the cage's symmetric embedded geometry."""

from __future__ import annotations

import math

import numpy as np
import pytest

from stiffknots.theory import elastica_constants
from stiffknots.theory import structures as st

EPS_0 = 2.0 * math.pi**2
EPS_80 = (math.sqrt(56.2198048706607) + math.sqrt(EPS_0)) ** 2  # 142.584368220781


def test_eighty_solution_is_two_free_closed_elastica():
    c = elastica_constants()
    d = st.structure_energy("80")["details"]
    # (eq. (28)): L_0 / L = (2 pi^2 / eps_80)^(1/2) (K = 256 level: O(K^-2) accuracy)
    assert d["length_fraction_circle"] == pytest.approx(math.sqrt(EPS_0 / EPS_80), abs=1e-4)
    # no force between the circle and the 8 (§VII); the 8 carries A / mu = alpha_8 (App. D)
    assert d["force_on_circle_over_mu"] < 1e-8
    for f in d["force_8_over_mu"]:
        assert f == pytest.approx(c.alpha_8, abs=1e-3)
    # planar (the circle may only turn about the bunch axis, a zero mode)
    assert d["out_of_plane_extent_over_L"] < 1e-4
    assert d["stability"]["negative"] == 0
    assert d["coarse_search"]["start_epsilon"] > d["coarse_search"]["epsilon"] + 5.0


def test_cage_geometry_is_symmetric_and_embedded():
    d = st.structure_energy("4C")["details"]
    assert d["axis_angle_deg"] == pytest.approx(90.0, abs=1e-6)
    assert d["angle_a_AB_deg"] == pytest.approx(90.0, abs=1e-6)
    assert d["angle_b_AB_deg"] == pytest.approx(90.0, abs=1e-6)
    assert np.allclose(d["arc_lengths_over_L"], 0.25, atol=1e-9)
    assert d["stability"]["negative"] == 0
    assert all(v < 1e-8 for v in d["balance"].values())
    # every arc stays inside its own open quarter wedge around AB: no arc crosses another
    intervals = sorted((v["azimuth_min"], v["azimuth_max"])
                       for v in d["arc_azimuths_about_AB_deg"].values())
    for lo, hi in intervals:
        assert hi - lo < 90.0
    for (_, hi), (lo, _) in zip(intervals, intervals[1:], strict=False):
        assert hi < lo
    # arcs meet only at the point-braids
    for pairs in d["arc_distances"].values():
        assert min(p["distance"] for p in pairs.values()) > 1e-3
