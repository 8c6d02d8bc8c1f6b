"""Tests of the shape distance that tells states apart (stiffknots.analysis.identity), on
annealed chains of tests/data/analysis: replicas of one state against distinct states."""

import math

import numpy as np
import pytest

from stiffknots.analysis.identity import SAME_STATE_DISTANCE, resample_unit, shape_distance


def _rotation(seed):
    q, r = np.linalg.qr(np.random.default_rng(seed).normal(size=(3, 3)))
    q = q * np.sign(np.diag(r))
    if np.linalg.det(q) < 0:
        q[:, 0] *= -1
    return q


def _circle(n, radius=1.0):
    t = 2 * math.pi * np.arange(n) / n
    return radius * np.column_stack([np.cos(t), np.sin(t), np.zeros(n)])


def test_resample_unit_has_unit_length_equal_spacing_and_zero_centroid(annealed):
    y = resample_unit(annealed("6_3_seed1_r1.npy"), 200)
    seg = np.linalg.norm(np.diff(np.vstack([y, y[:1]]), axis=0), axis=1)
    assert seg.sum() == pytest.approx(1.0, rel=2e-3)          # chords: slightly below L = 1
    assert seg.max() / seg.min() < 1.05
    assert np.abs(y.mean(axis=0)).max() < 1e-12


def test_a_moved_renumbered_reversed_mirrored_copy_is_at_distance_zero(annealed):
    x = annealed("4_1_seed1_r0.npy")
    for shift in (0, 1, 37, 149):
        y = np.roll(x[::-1], shift, axis=0) @ _rotation(shift).T + np.array([3.0, -7.0, 1.0])
        assert shape_distance(x, y) < 1e-6
        assert shape_distance(x, y * [-1.0, 1.0, 1.0]) < 1e-6         # its mirror image
    # the same polygon with its bond midpoints as extra vertices: another bead count
    mid = 0.5 * (x + np.roll(x, -1, axis=0))
    fine = np.stack([x, mid], axis=1).reshape(-1, 3)
    assert shape_distance(x, fine) < 1e-6
    # ... numbered from the middle of bond 0: the fraction of a sample spacing is found too
    assert shape_distance(x, np.roll(fine, -1, axis=0)) < 1e-6


def test_without_mirror_a_chiral_state_and_its_image_differ(annealed):
    x = annealed("5_2_seed1_r0.npy")                 # an 80 of the chiral knot 5_2
    y = x * [-1.0, 1.0, 1.0]
    assert shape_distance(x, y, mirror=False) > 10 * shape_distance(x, y)
    assert shape_distance(x, x @ _rotation(3).T, mirror=False) < 1e-6


def test_distance_is_symmetric_and_scales_out(annealed):
    a, b = annealed("5_2_seed1_r0.npy"), annealed("6_2_seed1_r0.npy")
    assert shape_distance(a, b) == pytest.approx(shape_distance(b, a), abs=1e-6)
    assert shape_distance(a, 2.5 * b) == pytest.approx(shape_distance(a, b), abs=1e-9)
    # two circles of any size and bead count are one shape
    assert shape_distance(_circle(40, 3.0), _circle(150, 0.2)) < 2e-3


def test_a_circle_against_a_doubly_covered_circle():
    """Analytic case. At unit length a circle has radius r₁ = 1/(2π), a doubly covered circle
    r₂ = 1/(4π); the second turns twice as fast, so their cross-covariance vanishes for every
    shift and no orthogonal map brings any point closer: the distance is √(r₁² + r₂²)."""
    n = 600
    t = 2 * math.pi * np.arange(n) / n
    double = np.column_stack([np.cos(2 * t), np.sin(2 * t), 0.01 * np.sin(t)])
    d = shape_distance(_circle(n), double)
    r1, r2 = 1 / (2 * math.pi), 1 / (4 * math.pi)
    assert d == pytest.approx(math.sqrt(r1**2 + r2**2), rel=0.02)


@pytest.mark.parametrize("a,b", [("3_1_seed1_r0", "3_1_seed1_r1"),
                                 ("4_1_seed1_r0", "4_1_seed1_r1"),
                                 ("5_2_seed1_r0", "5_2_seed1_r1"),
                                 ("6_2_seed1_r0", "6_2_seed1_r1")])
def test_replicas_of_one_state_are_within_the_same_state_distance(annealed, a, b):
    d = shape_distance(annealed(a + ".npy"), annealed(b + ".npy"))
    assert d < SAME_STATE_DISTANCE / 1.5


@pytest.mark.parametrize("a,b", [("4_1_seed0_r0", "4_1_seed1_r0"),   # flat "other" / cage
                                 ("6_3_seed1_r0", "6_3_seed1_r1"),   # CB(3) / 80
                                 ("5_2_tube_cage", "5_2_tube_80")])
def test_distinct_states_of_one_knot_are_far_apart(annealed, a, b):
    d = shape_distance(annealed(a + ".npy"), annealed(b + ".npy"))
    assert d > 2 * SAME_STATE_DISTANCE


def test_bad_chains_are_refused_with_the_reason():
    with pytest.raises(ValueError, match=r"\(N, 3\)"):
        shape_distance(np.zeros((5, 2)), _circle(10))
    with pytest.raises(ValueError, match="zero-length bond"):
        shape_distance(np.vstack([_circle(10), _circle(10)[-1:]]), _circle(10))
    with pytest.raises(ValueError, match="finite"):
        shape_distance(np.full((10, 3), np.nan), _circle(10))
    with pytest.raises(ValueError, match="points"):
        shape_distance(_circle(10), _circle(10), points=4)
