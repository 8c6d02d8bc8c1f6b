"""Curves that meet themselves and curves of extreme scale (#40 rows 6, 7 and 12): refused,
or read at order 1, never named wrongly."""

import time

import numpy as np
import pytest

from helpers import DATA
from stiffknots.chain import Chain
from stiffknots.geometry import rescaled
from stiffknots.knots.singular import SingularCurveError, _brute_force, meeting_edges

BOWTIE = np.array([[0, 0, 0], [1, 1, 0], [1, 0, 0], [0, 1, 0.0]])


def _trefoil(n=120):
    t = np.linspace(0.0, 2.0 * np.pi, n, endpoint=False)
    return np.column_stack([(2 + np.cos(3 * t)) * np.cos(2 * t),
                            (2 + np.cos(3 * t)) * np.sin(2 * t), np.sin(3 * t)])


def _flat(x):
    y = x.copy()
    y[:, 2] = 0.0
    return y


def test_meeting_edges_finds_crossings_and_only_them():
    assert meeting_edges(BOWTIE) == (0, 2)
    assert meeting_edges(_trefoil()) is None
    assert meeting_edges(_flat(_trefoil())) is not None
    rng = np.random.default_rng(40)
    for k in range(40):  # the grid search (≥ 600 edges) against every pair
        x = np.cumsum(rng.normal(size=(int(rng.integers(600, 900)), 3)), axis=0)
        if k % 2:
            x[:, 2] = np.round(x[:, 2])  # strands in common planes: some meet
        i, _ = _brute_force(x, True, (1e-12 * np.ptp(x, axis=0).max()) ** 2)
        assert (meeting_edges(x) is None) == (i < 0)


def test_meeting_edges_of_a_million_vertices_takes_seconds():
    x = _trefoil(1_000_000)
    meeting_edges(x[:1000])  # compiled
    t = time.perf_counter()
    assert meeting_edges(x) is None
    assert meeting_edges(_flat(x)) is not None
    assert time.perf_counter() - t < 30


def test_rescaled_is_exact_and_leaves_order_one_alone():
    x = _trefoil()
    assert rescaled(x) is x
    for s in (1e300, 1e-300, 2.0 ** 40):
        y = rescaled(x * s)
        assert 0.5 <= np.abs(y).max() < 1
        np.testing.assert_array_equal(y * (np.abs(x * s).max() / np.abs(y).max()), x * s)
    assert Chain(x * 1e300, True).epsilon() == pytest.approx(Chain(x, True).epsilon(),
                                                              rel=1e-12)


def test_identify_refuses_a_singular_polygon_and_reads_any_scale():
    from stiffknots.knots.identify import identify_details

    with pytest.raises(SingularCurveError, match="meets itself"):
        identify_details(BOWTIE)
    x = _trefoil(60)
    with pytest.raises(SingularCurveError, match=r"meets itself.*no knot type"):
        identify_details(_flat(x))
    for s in (1e300, 1e-300):
        assert identify_details(x * s).name == "3_1"


def test_resample_of_a_singular_curve_blames_the_curve_not_the_beads():
    from stiffknots.knots.resample import resample

    c = Chain(_flat(_trefoil(60)), True, {"source": "flat.xyz"})
    with pytest.raises(SingularCurveError) as e:
        resample(c, 100)
    assert str(e.value).startswith("flat.xyz: the curve meets itself")
    y = resample(Chain(_trefoil(60) * 1e300, True), 100)  # order 1 inside, unit bonds out
    np.testing.assert_allclose(y.bond_lengths(), 1.0, atol=1e-12)
    assert y.meta["chord"] > 1e299


def test_touching_strands_blame_the_curve_too():
    from stiffknots.knots.resample import CurveError, ResampleError, resample

    x = np.load(DATA / "resample" / "4_1_bead_touching.npy")
    with pytest.raises(ResampleError) as e:
        resample(Chain(x, True), 300)
    assert isinstance(e.value, CurveError)
    assert "--beads" not in e.value.for_option("--beads")
    assert "touching strands" in e.value.for_option("--beads")
